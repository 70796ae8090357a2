"""Cases, oracles and the score of the hold-out race (see :mod:`core.bench.holdout`)."""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from ... import metrics, noise, shapes
from ...estimate import estimate
from ...neighbours import build_neighbours
from ...normals import orient_normals, pca_normals
from .. import apss as _apss
from .._common import QUANTITIES, seed_of

#: the oracles' grids: jets of degree 2 and 3 on k neighbours, APSS at filter scales (x local spacing)
KS = (15, 20, 30, 45, 60, 90, 130, 180, 240)
APSS_SCALES = (2.0, 3.0, 4.0, 6.0, 8.0, 11.0, 16.0)
LEVELS = (0.0, 0.1, 0.2, 0.5)
#: a cell is lost when the default's error exceeds the best peer's by more than this factor
LOST = 1.0
FAR = 1.10
#: samplers that add their own noise (the range scan moves points along its view rays)
NOISE_BUILT_IN = {"range_scan": lambda n, seed, level: shapes.range_scan(n, noise=level, seed=seed)}
QKEYS = tuple(q for q, _, _ in QUANTITIES)


def make_case(sampler, name, level, n, seed, evaluate):
    """(sample, noisy points, evaluated mask): isotropic noise of ``level`` x mean spacing,
    ``evaluate`` random interior points (the same for every method)."""
    if name in NOISE_BUILT_IN:
        sample = NOISE_BUILT_IN[name](n, seed, level)
        pts = sample.points
    else:
        sample = sampler(n, seed)
        pts = noise.add_noise(sample.points, level, seed=seed_of(seed, 17, int(round(level * 1000))))
    pool = np.flatnonzero(sample.interior)
    ev = np.zeros(len(pts), dtype=bool)
    ev[np.random.default_rng(seed_of(seed, 5)).choice(pool, min(evaluate, len(pool)), replace=False)] = True
    return sample, pts, ev


def errors(result, sample, ev) -> dict:
    m = metrics.summary(result, sample, mask=ev)
    return {q: float(m[q]) for q in QKEYS}


def oracle_errors(sample, pts, ev, use_apss=True) -> dict:
    """{label: errors} of every peer at every setting of its grid (the truth picks the best later)."""
    nb = build_neighbours(pts, min(max(KS), len(pts)))
    out = {"nr15": errors(estimate(pts, k=15, neighbours=nb), sample, ev)}
    for d in (2, 3):
        for k in KS:
            r = estimate(pts, k=k, method="jet", options={"degree": d}, neighbours=nb)
            out[f"jet{d} k={k}"] = errors(r, sample, ev)
    if use_apss and _apss.available():
        idx, dist = nb.take(15)
        nrm, ok = pca_normals(pts, idx, dist)
        nrm = np.where(ok[:, None], orient_normals(pts, nrm, idx, "outward", ok=ok), [0.0, 0.0, 1.0])
        nrm[np.einsum("ij,ij->i", nrm, sample.normals) < 0] *= -1  # oriented by the truth: an oracle
        for sc in APSS_SCALES:
            out[f"apss {sc:g}"] = errors(_apss.apss_curvature(pts, nrm, scale=sc, evaluate=ev), sample, ev)
    return out


def auto_run(sample, pts, ev, options=None) -> dict:
    """The default (k="auto") on the case: its errors, seconds, median k and degree mix."""
    t = time.perf_counter()
    r = estimate(pts, options=options)
    sec = time.perf_counter() - t
    k = np.asarray(r.k_point)[ev]
    return {"errors": errors(r, sample, ev), "seconds": sec, "k_median": float(np.median(k))}


def best(oracles: dict, q: str):
    """(label, error) of the best peer setting for quantity ``q``."""
    cands = [(v[q], lab) for lab, v in oracles.items() if math.isfinite(v[q])]
    err, lab = min(cands) if cands else (math.nan, "")
    return lab, err


class Cache:
    """Oracle errors by case key in a JSON file (the oracles do not change with the rule)."""

    def __init__(self, path):
        self.path = path
        self.data = {}
        if path and os.path.exists(path):
            with open(path, encoding="utf-8") as fh:
                self.data = json.load(fh)

    def get(self, key, compute):
        if key not in self.data:
            self.data[key] = compute()
            if self.path:
                tmp = f"{self.path}.tmp{os.getpid()}"
                with open(tmp, "w", encoding="utf-8") as fh:
                    json.dump(self.data, fh)
                os.replace(tmp, self.path)
        return self.data[key]


def score(rows) -> dict:
    """Cells lost (ratio > :data:`LOST`), far (> :data:`FAR`), worst and geometric mean of the
    ratios default / best peer over all (surface, level, quantity) cells of ``rows``."""
    ratios = [r["ratio"][q] for r in rows for q in QKEYS if math.isfinite(r["ratio"][q])]
    if not ratios:
        return dict(cells=0, lost=0, far=0, worst=math.nan, geomean=math.nan)
    return dict(cells=len(ratios), lost=sum(x > LOST for x in ratios), far=sum(x > FAR for x in ratios),
                worst=max(ratios), geomean=float(np.exp(np.mean(np.log(np.maximum(ratios, 1e-12))))))
