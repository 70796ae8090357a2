"""Proof that a speed change changed no number: every per-point output of ``core.estimate``
(k = 15 and k = "auto") on tori and saddles at 20k and 100k points, noise-free, with noise
of 0.2 and 0.5 spacing and quantised, saved by one version of the code and compared with
another's.

    python -m core.bench.perf_identity save before.npz     # on the old code
    python -m core.bench.perf_identity save after.npz      # on the new code
    python -m core.bench.perf_identity compare before.npz after.npz

``compare`` lists every array that is not bit-identical and fails (exit 1) if any float
differs by 1e-12 or more, if a NaN moved, or if an integer or flag (k_point,
degree_point, passes_run, valid, border, ...) changed at all.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from .. import estimate, noise, shapes

FIELDS = ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "degree_point", "outlier_score", "crease",
          "orientation_confidence")
TOLERANCE = 1e-12


def clouds(sizes=(20_000, 100_000)):
    """(name, points) of the clouds compared."""
    for n in sizes:
        torus = shapes.torus(n, seed=0).points
        yield f"torus{n}", torus
        yield f"torus{n}_n0.2", noise.add_noise(torus, 0.2, seed=1)
        yield f"saddle{n}_n0.5", noise.add_noise(shapes.saddle(n, seed=2).points, 0.5, seed=3)
    yield "quantised20000", np.round(shapes.torus(20_000, seed=4).points * 30) / 30
    yield "saddle20000", shapes.saddle(20_000, seed=5).points


def snapshot(path, out=print) -> None:
    """Every output of the estimates of :func:`clouds` into ``path`` (.npz)."""
    arrays = {}
    for name, pts in clouds():
        for k in (15, "auto"):
            t0 = time.process_time()
            res = estimate(pts, k=k)
            key = f"{name}_{k}"
            for f in FIELDS:
                if getattr(res, f) is not None:
                    arrays[f"{key}:{f}"] = np.asarray(getattr(res, f))
            arrays[f"{key}:border"] = np.asarray(res.border)
            arrays[f"{key}:nb_idx"] = res.neighbours.indices[:, :min(30, res.neighbours.k_max)]
            arrays[f"{key}:nb_dist"] = res.neighbours.distances[:, -1]
            arrays[f"{key}:passes_run"] = np.asarray(res.params.get("passes_run", -1))
            out(f"{key:28s} {time.process_time() - t0:7.2f} s CPU")
    np.savez(path, **arrays)


def _difference(x, y):
    """(bit-identical, within tolerance, max |x - y|) of two saved arrays."""
    if x.shape != y.shape:
        return False, False, np.inf
    if x.dtype.kind != "f":
        same = bool(np.array_equal(x, y))
        return same, same, 0.0 if same else np.inf
    exact = bool(np.array_equal(x, y, equal_nan=True))
    finite = np.isfinite(x) & np.isfinite(y)
    gap = float(np.abs(x[finite] - y[finite]).max()) if finite.any() else 0.0
    return exact, bool(np.array_equal(np.isnan(x), np.isnan(y)) and gap < TOLERANCE), gap


def compare(path_a, path_b, out=print) -> int:
    """Report the arrays of two snapshots that differ; 1 if any differs beyond tolerance."""
    a, b = np.load(path_a), np.load(path_b)
    if set(a.files) != set(b.files):
        out(f"different arrays: {sorted(set(a.files) ^ set(b.files))}")
        return 1
    bad, worst = 0, 0.0
    for f in sorted(a.files):
        exact, ok, gap = _difference(a[f], b[f])
        worst = max(worst, gap)
        if not exact:
            out(f"{f:50s} {'within 1e-12' if ok else 'DIFFERS'}: max |diff| {gap:.3g}")
        bad += not ok
    out(f"{len(a.files)} arrays compared, {bad} differ by 1e-12 or more (or in a flag), largest difference {worst:.3g}")
    return int(bad > 0)


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) == 2 and args[0] == "save":
        snapshot(args[1])
        return 0
    if len(args) == 3 and args[0] == "compare":
        return compare(args[1], args[2])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())
