"""The runs: every method on noisy samples of every surface, and the exact-normal references."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ... import build_neighbours, estimate, metrics, noise
from .config import DEFAULT_LEVELS, METHODS, QUANTITIES, SURFACES, _seed


@dataclass
class SurfaceTable:
    """Errors on one surface, averaged over the repeats.

    ``mean[q]``, ``median[q]``, ``std[q]`` : (levels, methods) arrays for quantity ``q``
    (a key of :data:`QUANTITIES`) with estimated normals: the mean absolute error (and the
    median absolute error), averaged over repeats, and the spread of the per-repeat means.
    ``exact_mean[q]``, ``exact_median[q]`` : (methods,) arrays, noise-free with exact normals.
    ``invalid`` : (levels, methods) mean fraction of points the method left invalid.
    """

    surface: str
    title: str
    n_points: int
    k: int
    repeats: int
    levels: tuple
    methods: tuple
    mean: dict = field(default_factory=dict)
    median: dict = field(default_factory=dict)
    std: dict = field(default_factory=dict)
    exact_mean: dict = field(default_factory=dict)
    exact_median: dict = field(default_factory=dict)
    invalid: np.ndarray | None = None
    spacing: float = float("nan")
    seconds: float = 0.0

    def value(self, quantity, method, level=None, *, exact=False, stat="mean") -> float:
        """One entry: ``level`` is a noise level (default the highest) unless ``exact``."""
        j = self.methods.index(method)
        if exact:
            return float((self.exact_mean if stat == "mean" else self.exact_median)[quantity][j])
        i = len(self.levels) - 1 if level is None else self.levels.index(level)
        return float((self.mean if stat == "mean" else self.median)[quantity][i, j])


@dataclass
class PaperRun:
    """What :func:`run` returns: one :class:`SurfaceTable` per surface plus the setup."""

    tables: dict
    setup: dict
    seconds: float


def _errors(result, sample):
    """(mean, median) absolute error per quantity, over the points metrics.summary uses."""
    means = metrics.summary(result, sample)
    pe = metrics.point_errors(result, sample)
    medians = {}
    for q, _, _ in QUANTITIES:
        v = pe[q][sample.interior & np.isfinite(pe[q])]
        medians[q] = float(np.median(v)) if len(v) else float("nan")
    return {q: means[q] for q, _, _ in QUANTITIES}, medians, means["invalid_fraction"]


def run(points=5000, k=15, levels=DEFAULT_LEVELS, repeats=3, seed=0, surfaces=("torus", "saddle"),
        methods=METHODS, progress=None) -> PaperRun:
    """Run the experiment and return the table data.

    Parameters
    ----------
    points : number of random points per sample.
    k : neighbourhood size (the paper: 15).
    levels : noise levels, σ as a fraction of the mean point spacing of the clean sample.
    repeats : independent samples (surface and noise seeds) averaged per entry.
    seed : base seed; the same arguments give the same numbers.
    surfaces : names from :data:`SURFACES`.
    methods : names from :data:`core.METHODS`, run with PCA normals at every level and with
        the exact normals on the noise-free sample.
    progress : callable(message: str), optional.
    """
    levels = tuple(float(x) for x in levels)
    methods = tuple(methods)
    if not levels or any(not np.isfinite(x) or x < 0 for x in levels):
        raise ValueError(f"levels must be finite numbers >= 0, got {levels}")
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    unknown = [s for s in surfaces if s not in SURFACES]
    if unknown:
        raise ValueError(f"unknown surface(s) {unknown}; valid: {list(SURFACES)}")
    t_all = time.perf_counter()
    tables = {}
    nq, nl, nm = len(QUANTITIES), len(levels), len(methods)
    for s_i, name in enumerate(surfaces):
        title, make = SURFACES[name]
        t0 = time.perf_counter()
        est_mean = np.full((repeats, nq, nl, nm), np.nan)
        est_median = np.full_like(est_mean, np.nan)
        invalid = np.zeros((repeats, nl, nm))
        ex_mean = np.full((repeats, nq, nm), np.nan)
        ex_median = np.full_like(ex_mean, np.nan)
        spacing = []
        for r in range(repeats):
            sample = make(points, _seed(seed, s_i, r))
            spacing.append(noise.mean_spacing(sample.points))
            # noise-free points with the exact normals (the paper's "E" curves)
            nb = build_neighbours(sample.points, k)
            for j, m in enumerate(methods):
                res = estimate(sample.points, sample.normals, k=k, method=m, neighbours=nb)
                mean, median, _ = _errors(res, sample)
                for qi, (q, _, _) in enumerate(QUANTITIES):
                    ex_mean[r, qi, j], ex_median[r, qi, j] = mean[q], median[q]
            # estimated normals (weighted PCA) at every noise level, the same noisy cloud for all methods
            for li, sigma in enumerate(levels):
                pts = noise.add_noise(sample.points, sigma, relative=True, spacing=spacing[-1],
                                      seed=_seed(seed, s_i, r, li + 1))
                nb = build_neighbours(pts, k)
                for j, m in enumerate(methods):
                    res = estimate(pts, k=k, method=m, neighbours=nb)
                    mean, median, inv = _errors(res, sample)
                    invalid[r, li, j] = inv
                    for qi, (q, _, _) in enumerate(QUANTITIES):
                        est_mean[r, qi, li, j], est_median[r, qi, li, j] = mean[q], median[q]
            if progress is not None:
                progress(f"[{name}] repeat {r + 1}/{repeats} done, {time.perf_counter() - t0:.1f} s")
        tab = SurfaceTable(name, title, points, k, repeats, levels, methods, invalid=invalid.mean(0),
                           spacing=float(np.mean(spacing)))
        for qi, (q, _, _) in enumerate(QUANTITIES):
            tab.mean[q] = est_mean[:, qi].mean(0)
            tab.median[q] = est_median[:, qi].mean(0)
            tab.std[q] = est_mean[:, qi].std(0)
            tab.exact_mean[q] = ex_mean[:, qi].mean(0)
            tab.exact_median[q] = ex_median[:, qi].mean(0)
        tab.seconds = time.perf_counter() - t0
        tables[name] = tab
    setup = dict(points=points, k=k, levels=levels, repeats=repeats, seed=seed, surfaces=tuple(surfaces),
                 methods=methods)
    return PaperRun(tables, setup, time.perf_counter() - t_all)
