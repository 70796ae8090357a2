"""The noisy samples every method shares, and the bookkeeping of errors and sweeps."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ... import metrics, noise
from ...neighbours import build_neighbours
from ...normals import orient_normals, pca_normals
from .config import NOISE_BUILT_IN, QUANTITIES, SHAPES, _nanmean, _seed


@dataclass
class Case:
    """One noisy sample: the clean sample, the noisy points and what every method shares."""

    sample: object
    points: np.ndarray
    evaluate: np.ndarray
    nb: object
    spacing: float
    pca: dict = field(default_factory=dict)

    def pca_normals(self, k):
        """Weighted-PCA normals at ``k``, oriented outward (as core.estimate does)."""
        if k not in self.pca:
            idx, dist = self.nb.take(k)
            nrm, ok = pca_normals(self.points, idx, dist)
            nrm = orient_normals(self.points, nrm, idx, "outward", ok=ok)
            self.pca[k] = np.where(ok[:, None], nrm, np.array([0.0, 0.0, 1.0]))
        return self.pca[k]


def _errors(result, case, mask=None) -> dict:
    use = case.evaluate if mask is None else (case.evaluate & mask)
    s = metrics.summary(result, case.sample, mask=use)
    return {q: s[q] for q, _, _ in QUANTITIES} | {"invalid": s["invalid_fraction"]}


def _mean_over(errs: list) -> dict:
    return {key: _nanmean([e[key] for e in errs]) for key in errs[0]}


def _sweep(cands, evaluate_fn, *, patience=2):
    """Evaluate candidates in order (all seeds each); stop once ``patience`` candidates in a
    row are worse than the best so far on every quantity. Returns {candidate: mean errors}."""
    out = {}
    best = {q: math.inf for q, _, _ in QUANTITIES}
    worse_run = 0
    for c in cands:
        e = evaluate_fn(c)
        out[c] = e
        improved = False
        for q, _, _ in QUANTITIES:
            if np.isfinite(e[q]) and e[q] < best[q]:
                best[q] = e[q]
                improved = True
        worse_run = 0 if improved else worse_run + 1
        if worse_run >= patience:
            break
    return out


@dataclass
class ShapeTable:
    """Errors on one shape.

    ``err[col][q]`` : (levels,) mean over seeds of the mean absolute error; for oracle
    columns the best candidate per (level, quantity), named in ``chosen[col][q][level]``.
    ``sweeps[col][level]`` : {candidate: mean errors} as evaluated. ``ref[col][q]`` :
    σ = 0 with exact normals. ``auto_k`` : (levels,) median k chosen by k="auto".
    """

    shape: str
    title: str
    levels: tuple
    columns: tuple
    err: dict = field(default_factory=dict)
    chosen: dict = field(default_factory=dict)
    sweeps: dict = field(default_factory=dict)
    ref: dict = field(default_factory=dict)
    ref_chosen: dict = field(default_factory=dict)
    invalid: dict = field(default_factory=dict)
    auto_k: list = field(default_factory=list)
    auto_k_range: list = field(default_factory=list)
    auto_k_top: list = field(default_factory=list)
    coupling: dict = field(default_factory=dict)
    grids: dict = field(default_factory=dict)
    k_range: tuple = (float("nan"), float("nan"))
    spacing: float = float("nan")
    seconds: float = 0.0

    def value(self, col, q, level) -> float:
        return float(self.err[col][q][self.levels.index(level)])


@dataclass
class AccuracyRun:
    tables: dict
    robust: list
    options: dict
    setup: dict
    notes: list
    conventions: dict
    seconds: float


def _oracle(sweep: dict, q: str):
    """(best candidate, its error) for quantity q."""
    cands = [c for c in sweep if np.isfinite(sweep[c][q])]
    if not cands:
        return None, float("nan")
    c = min(cands, key=lambda c: sweep[c][q])
    return c, sweep[c][q]


def _make_cases(name, points, level, seeds, base_seed, evaluate, k_max):
    title, make = SHAPES[name]
    s_i = list(SHAPES).index(name)
    cases = []
    for r in range(seeds):
        if name in NOISE_BUILT_IN:  # e.g. along a scanner's view rays; the truth is the clean sample's
            sample = NOISE_BUILT_IN[name](points, _seed(base_seed, s_i, r), level)
            pts = sample.points
            spacing = noise.mean_spacing(pts)
        else:
            sample = make(points, _seed(base_seed, s_i, r))
            spacing = noise.mean_spacing(sample.points)
            pts = noise.add_noise(sample.points, level, relative=True, spacing=spacing,
                                  seed=_seed(base_seed, s_i, r, int(round(level * 1000)) + 1))
        rng = np.random.default_rng(_seed(base_seed, s_i, r, 99))
        ev = np.zeros(len(pts), dtype=bool)
        pool = np.flatnonzero(sample.interior)
        ev[rng.choice(pool, size=min(evaluate, len(pool)), replace=False) if evaluate else pool] = True
        nb = build_neighbours(pts, min(k_max, len(pts)))
        cases.append(Case(sample, pts, ev, nb, spacing))
    return cases
