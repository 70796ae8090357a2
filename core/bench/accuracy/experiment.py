"""The runs: the race on every shape, the robustness table and the options table."""

from __future__ import annotations

import time

import numpy as np

from ... import noise
from ...estimate import estimate
from ...neighbours import build_neighbours
from ...normals import orient_normals, pca_normals
from .. import apss as _apss
from .cases import AccuracyRun, ShapeTable, _errors, _make_cases, _mean_over, _oracle, _sweep
from .config import (APSS, APSS_PCA_K, APSS_SCALES, APSSE, AUTO, COUPLING_LEVEL, DEFAULT_LEVELS, EVALUATE, JET2,
                     JET3, K_GRID, METHODSMIN_JET3, NFE, NR15, NRBEST, OPTIONS_LEVELS, OPTIONS_SHAPES,
                     OUTLIER_FRACTION, PAPER_K, QUANTITIES, ROBUST_LEVELS, SHAPES, _seed)
from .conventions import apss_conventions


def run(points=5000, levels=DEFAULT_LEVELS, seeds=2, seed=0, shapes_=tuple(SHAPES), *, k_grid=K_GRID,
        apss_scales=APSS_SCALES, apss_pca_k=APSS_PCA_K, evaluate=EVALUATE, use_apss=True,
        robust_levels=ROBUST_LEVELS, options_shapes=OPTIONS_SHAPES, options_levels=OPTIONS_LEVELS,
        options_passes=(1, 2, 3), progress=None) -> AccuracyRun:
    """Run the race, the robustness table and the options table; return the numbers."""
    levels = tuple(float(x) for x in levels)
    if not levels or any(not np.isfinite(x) or x < 0 for x in levels):
        raise ValueError(f"levels must be finite numbers >= 0, got {levels}")
    if seeds < 1:
        raise ValueError(f"seeds must be >= 1, got {seeds}")
    unknown = [s for s in shapes_ if s not in SHAPES]
    if unknown:
        raise ValueError(f"unknown shape(s) {unknown}; valid: {list(SHAPES)}")
    say = progress or (lambda msg: None)
    t_all = time.perf_counter()
    notes, conventions, use_apss = _apss_setup(use_apss)
    columns = tuple(c for c in (NR15, AUTO, NRBEST, JET2, JET3, APSS) if c != APSS or use_apss)
    k_grid = tuple(sorted(set(int(k) for k in k_grid)))
    jet_grid = tuple(k for k in k_grid if k >= METHODSMIN_JET3)
    k_max = max(max(k_grid), max(apss_pca_k), PAPER_K)
    sample = dict(points=points, seeds=seeds, seed=seed, evaluate=evaluate, k_max=k_max)
    grids = {NRBEST: k_grid, JET2: k_grid, JET3: jet_grid, APSS: tuple(apss_scales)}
    tables, race_cases = {}, {}
    for name in shapes_:
        tables[name] = _race_table(name, levels, columns, grids, tuple(apss_pca_k), sample, race_cases, say)
    robust_rows = _robustness(tables, shapes_, robust_levels, sample, race_cases, use_apss, say)
    options = _options(shapes_, options_shapes, options_levels, options_passes, sample, race_cases, say)
    setup = dict(points=points, levels=levels, seeds=seeds, seed=seed, shapes=tuple(shapes_), k_grid=k_grid,
                 jet_grid=jet_grid, apss_scales=tuple(apss_scales), apss_pca_k=tuple(apss_pca_k), evaluate=evaluate,
                 use_apss=use_apss, auto=True, robust=True, robust_levels=tuple(robust_levels),
                 options_levels=tuple(options_levels), options_passes=tuple(options_passes),
                 pymeshlab=_apss.version() if use_apss else "")
    return AccuracyRun(tables, robust_rows, options, setup, notes, conventions, time.perf_counter() - t_all)


def _apss_setup(use_apss):
    """(notes, conventions, use_apss): APSS runs when asked for and pymeshlab is there."""
    notes, conventions = [], {}
    if use_apss and not _apss.available():
        notes.append(f"APSS skipped: pymeshlab is not installed (optional benchmark dependency: "
                     f"`{_apss.INSTALL_HINT}`).")
        return notes, conventions, False
    if not use_apss:
        notes.append("APSS skipped (--no-apss).")
        return notes, conventions, False
    conventions = apss_conventions()
    if not conventions["ok"]:
        notes.append(f"APSS convention check FAILED ({conventions}): its numbers below are suspect.")
    return notes, conventions, True


def _cases(name, level, sample, race_cases=None):
    if race_cases is not None and (name, level) in race_cases:
        return race_cases[(name, level)]
    s = sample
    return _make_cases(name, s["points"], level, s["seeds"], s["seed"], s["evaluate"], s["k_max"])


def _race_table(name, levels, columns, grids, apss_pca_k, sample, race_cases, say) -> ShapeTable:
    t0 = time.perf_counter()
    tab = ShapeTable(name, SHAPES[name][0], levels, columns)
    tab.grids = grids
    for col in columns:
        tab.err[col] = {q: np.full(len(levels), np.nan) for q, _, _ in QUANTITIES}
        tab.chosen[col] = {q: [None] * len(levels) for q, _, _ in QUANTITIES}
        tab.sweeps[col] = [None] * len(levels)
        tab.invalid[col] = np.zeros(len(levels))
    for li, level in enumerate(levels):
        cases = race_cases[(name, level)] = _cases(name, level, sample)
        g = cases[0].sample.gaussian
        tab.k_range = (float(g.min()), float(g.max()))
        tab.spacing = float(np.mean([c.spacing for c in cases]))
        sweeps = _race_sweeps(tab, level, cases, grids, apss_pca_k, APSS in columns)
        for col in columns:
            sw = sweeps[col]
            tab.sweeps[col][li] = sw
            for q, _, _ in QUANTITIES:
                c, v = _oracle(sw, q)
                tab.err[col][q][li] = v
                tab.chosen[col][q][li] = c
            tab.invalid[col][li] = max(e["invalid"] for e in sw.values())
        say(f"[{name}] σ={level:g}: done, {time.perf_counter() - t0:.1f} s")
    _references(tab, _cases(name, 0.0, sample), grids[APSS], APSS in columns)
    tab.seconds = time.perf_counter() - t0
    return tab


def _est_errors(cases, k, method="nr", options=None):
    return _mean_over([_errors(estimate(c.points, k=k, method=method, options=options,
                                        neighbours=c.nb if k <= c.nb.k_max else None), c) for c in cases])


def _race_sweeps(tab, level, cases, grids, apss_pca_k, use_apss) -> dict:
    """{column: {candidate: mean errors}} on the cases of one shape and noise level."""
    sweeps = {NR15: {PAPER_K: _est_errors(cases, PAPER_K)}}
    errs, ks = [], []
    for c in cases:
        r = estimate(c.points)  # no parameter set: the default
        errs.append(_errors(r, c))
        ks.append(np.asarray(r.k_point)[c.evaluate])
    sweeps[AUTO] = {"auto": _mean_over(errs)}
    ks = np.concatenate(ks)
    tab.auto_k.append(float(np.median(ks)))
    tab.auto_k_range.append((float(np.percentile(ks, 10)), float(np.percentile(ks, 90))))
    tab.auto_k_top.append((int(ks.max()), float(np.mean(ks == ks.max()))))
    if level == COUPLING_LEVEL:
        # with an integer k the initial PCA normals use the same k; auto keeps them at the
        # paper's 15 and only fits at its larger k
        k_fit = int(np.median(ks))
        tab.coupling = dict(level=level, k=k_fit, auto=sweeps[AUTO]["auto"], coupled=_est_errors(cases, k_fit),
                            decoupled=_mean_over([_errors(estimate(
                                c.points, c.pca_normals(PAPER_K), k=k_fit,
                                neighbours=c.nb if k_fit <= c.nb.k_max else None), c) for c in cases]))
    sweeps[NRBEST] = _sweep(grids[NRBEST], lambda k: _est_errors(cases, k))
    sweeps[JET2] = _sweep(grids[JET2], lambda k: _est_errors(cases, k, "jet", {"degree": 2}))
    sweeps[JET3] = _sweep(grids[JET3], lambda k: _est_errors(cases, k, "jet", {"degree": 3}))
    if use_apss:
        sweeps[APSS] = {}
        for pk in apss_pca_k:
            sw = _sweep(grids[APSS], lambda sc, pk=pk: _mean_over([
                _errors(_apss.apss_curvature(c.points, c.pca_normals(pk), scale=sc, evaluate=c.evaluate), c)
                for c in cases]))
            sweeps[APSS].update({(pk, sc): e for sc, e in sw.items()})
    return sweeps


def _references(tab, cases, apss_scales, use_apss) -> None:
    """Noise-free points with exact normals: NF k=15 (the paper's NFE) and APSS at its best scale."""
    tab.ref[NFE] = _mean_over([_errors(estimate(c.points, c.sample.normals, k=PAPER_K, method="nf",
                                                neighbours=c.nb), c) for c in cases])
    if not use_apss:
        return
    sw = _sweep(apss_scales, lambda sc: _mean_over([
        _errors(_apss.apss_curvature(c.points, c.sample.normals, scale=sc, evaluate=c.evaluate), c)
        for c in cases]))
    tab.ref[APSSE] = {}
    tab.ref_chosen[APSSE] = {}
    for q, _, _ in QUANTITIES:
        c, v = _oracle(sw, q)
        tab.ref[APSSE][q] = v
        tab.ref_chosen[APSSE][q] = (None, c)


def _robustness(tables, shapes_, robust_levels, sample, race_cases, use_apss, say) -> list:
    """Rows of the outlier table: errors on the inliers with and without 3 % outliers."""
    t0 = time.perf_counter()
    rows = []
    for name in shapes_:
        for level in robust_levels:
            cases = _cases(name, level, sample, race_cases)
            outl = [noise.add_outliers(c.points, OUTLIER_FRACTION, spacing=c.spacing,
                                       seed=_seed(sample["seed"], 7, ci, int(level * 1000)))
                    for ci, c in enumerate(cases)]
            tab = tables[name]
            for label, kw in _robust_variants(tab, level):
                clean = _mean_over([_errors(estimate(c.points, **kw), c, ~m) for c, (_, m) in zip(cases, outl)])
                dirty = _mean_over([_errors(estimate(p, **kw), c, ~m) for c, (p, m) in zip(cases, outl)])
                rows.append(dict(shape=name, level=level, method=label, clean=clean, dirty=dirty))
            if use_apss and level in tab.levels:
                rows.append(_apss_robustness(name, level, tab, cases, outl))
            say(f"[robustness] {name} σ={level:g}: done, {time.perf_counter() - t0:.1f} s")
    return rows


def _robust_variants(tab, level):
    variants = [("NR k=15", dict(k=PAPER_K)), ("NR k=15, Tukey", dict(k=PAPER_K, options={"robust": "tukey"})),
                ("NR auto", {}), ("NR auto, Tukey", dict(options={"robust": "tukey"}))]
    if level in tab.levels:
        kj = tab.chosen[JET2]["mean"][tab.levels.index(level)]
        if kj is not None:
            variants.append((f"jet2 k={kj}", dict(k=kj, method="jet", options={"degree": 2})))
    return variants


def _apss_robustness(name, level, tab, cases, outl) -> dict:
    pk, sc = tab.chosen[APSS]["mean"][tab.levels.index(level)]
    errs_c, errs_d = [], []
    for c, (p, m) in zip(cases, outl):
        errs_c.append(_errors(_apss.apss_curvature(c.points, c.pca_normals(pk), scale=sc,
                                                   evaluate=c.evaluate & ~m), c, ~m))
        nb = build_neighbours(p, pk)
        idx, dist = nb.take(pk)
        nrm, ok = pca_normals(p, idx, dist)
        nrm = np.where(ok[:, None], orient_normals(p, nrm, idx, "outward", ok=ok), [0.0, 0.0, 1.0])
        errs_d.append(_errors(_apss.apss_curvature(p, nrm, scale=sc, evaluate=c.evaluate & ~m), c, ~m))
    return dict(shape=name, level=level, method=f"APSS {sc:g}/n{pk}", clean=_mean_over(errs_c),
                dirty=_mean_over(errs_d))


def _options(shapes_, options_shapes, options_levels, options_passes, sample, race_cases, say) -> dict:
    """NR's options (weights, constraint, passes, tol, initial jet) at k=15 and k="auto"."""
    t0 = time.perf_counter()
    options = {}
    configs = [(w, cns, p) for w in ("uniform", "theta") for cns in ("project", "exact", "none")
               for p in options_passes]
    for name in options_shapes:
        if name not in shapes_:
            continue
        for kmode in (PAPER_K, "auto"):
            rows = {}
            for level in options_levels:
                cases = _cases(name, level, sample, race_cases)
                nb = (lambda c: None) if kmode == "auto" else (lambda c: c.nb)
                for w, cns, p in configs:
                    kw = dict(k=kmode, passes=p, options={"weights": w, "constraint": cns})
                    rows.setdefault((w, cns, str(p)), {})[level] = _mean_over(
                        [_errors(estimate(c.points, neighbours=nb(c), **kw), c) for c in cases])
                rows.setdefault(("uniform", "project", "≤5, tol 0.1°"), {})[level] = _mean_over(
                    [_errors(estimate(c.points, k=kmode, passes=5, tol=0.1, neighbours=nb(c)), c) for c in cases])
                if kmode != "auto":  # the initial normals refined by a 2-jet (k="auto" uses them by default)
                    rows.setdefault(("uniform", "project", "1, initial jet"), {})[level] = _mean_over(
                        [_errors(estimate(c.points, k=kmode, initial="jet", neighbours=c.nb), c) for c in cases])
            options[(name, kmode)] = rows
        say(f"[options] {name}: done, {time.perf_counter() - t0:.1f} s")
    return options
