"""``python -m core bench stability``: how much the estimate moves when the scan does.

For the bundled bunny (and any files given), with the default estimate (k="auto", NR):

- **subsample**: the estimate on a random 50 % of the points against the full cloud's at
  the same points: median |dH| / median |H| (target <= 0.2 on the bunny), and the share of
  normals whose sign flips (orientation that holds under resampling);
- **noise**: the estimate with isotropic noise of 0.2 mean spacing against the clean one,
  and the same at one fixed scale (k = the clean estimate's median k on both): the
  first includes what the noise does to the choice of scale, the second only what it does
  to a fit;
- **file normals**: where the file has normals, the share of estimated normals on the
  same side (the scanner knows where it was).

The table also gives the share of border points (see :mod:`core.border`), of striped
points (sampled along scan lines, :mod:`core.anisotropy`: H there may show the pattern) and the
count of file normals that :mod:`core.normal_repair` would fix (unusable or unscaled).
Medians over the points valid in both runs.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..normal_repair import split_normals
from ._table import fmt, text_table

BUNNY = Path(__file__).resolve().parents[2] / "resources" / "bunny.ply"


def _compare(full, part, rows):
    """(median |dH| / median |H|, share of flipped normals) of ``part`` against ``full[rows]``."""
    both = full.valid[rows] & part.valid
    h_full = full.mean[rows][both]
    dh = np.abs(part.mean[both] - h_full)
    flips = np.einsum("ij,ij->i", part.normals[both], full.normals[rows][both]) < 0
    scale = np.median(np.abs(h_full)) if len(h_full) else 0.0
    ratio = float(np.median(dh) / scale) if scale > 0 else float("nan")  # a flat cloud: no scale
    return ratio, float(np.mean(flips)) if len(flips) else float("nan")


def measure(points, file_normals=None, *, seed=0, noise_sigma=0.2, estimate_kw=None):
    """The stability numbers of one cloud; a dict (see the module doc)."""
    import core
    from core.noise import add_noise

    kw = dict(estimate_kw or {})
    rng = np.random.default_rng(seed)
    full = core.estimate(points, **kw)
    half = np.sort(rng.choice(len(points), len(points) // 2, replace=False))
    sub = core.estimate(points[half], **kw)
    noisy = core.estimate(add_noise(points, noise_sigma, seed=seed), **kw)
    out = dict(n=len(points), valid=float(full.valid.mean()), border=float(full.border.mean()),
               striped=float(full.striped.mean()), repaired=None)
    out["sub_dh"], out["sub_flip"] = _compare(full, sub, half)
    out["noise_dh"], out["noise_flip"] = _compare(full, noisy, np.arange(len(points)))
    out["fixed_k"] = int(np.median(full.k_point))
    fixed = dict(kw, k=out["fixed_k"])
    out["noise_dh_fixed"], _ = _compare(core.estimate(points, **fixed),
                                        core.estimate(add_noise(points, noise_sigma, seed=seed), **fixed),
                                        np.arange(len(points)))
    out["file_agree"] = None
    if file_normals is not None:
        fn = np.asarray(file_normals, dtype=float)
        counts = split_normals(fn)[2]
        out["repaired"] = counts["unusable"] + counts["renormalised"]
        ok = np.isfinite(fn).all(axis=1) & (np.linalg.norm(np.nan_to_num(fn), axis=1) > 0) & full.valid
        out["file_agree"] = float(np.mean(np.einsum("ij,ij->i", full.normals[ok], fn[ok]) > 0))
    return out


def run(paths=(), *, seed=0, out=print):
    import core

    rows, results = [], []
    for path in [BUNNY, *paths]:
        cloud = core.io.read_cloud(path, drop_nonfinite=True)
        r = measure(cloud.points, cloud.normals, seed=seed)
        results.append((str(path), r))
        rows.append([Path(path).name, f"{r['n']:,}", fmt(r["sub_dh"]), f"{100 * r['sub_flip']:.2f}",
                     fmt(r["noise_dh"]), f"{fmt(r['noise_dh_fixed'])} (k={r['fixed_k']})", f"{100 * r['noise_flip']:.2f}",
                     "-" if r["file_agree"] is None else f"{100 * r['file_agree']:.2f}",
                     f"{100 * r['border']:.1f}", f"{100 * r['striped']:.1f}",
                     "-" if r["repaired"] is None else f"{r['repaired']:,}"])
    out(text_table(["cloud", "points", "50% |dH|/|H|", "50% flips %", "noise 0.2 |dH|/|H|", "same, fixed k", "noise flips %",
                    "agree w/ file normals %", "border %", "striped %", "file normals repaired"], rows, title="Stability of the default estimate (k=auto, NR)"))
    out("targets: 50% subsample |dH|/|H| <= 0.2 on the bunny; flips ~0. 'same, fixed k': the noise's effect on\n"
        "a fit at one scale; the difference to the column before is its effect on the choice of scale")
    return results


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m core bench stability", description=__doc__.splitlines()[0])
    p.add_argument("files", nargs="*", help="more point clouds (any format core.io reads)")
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args(argv)
    run(a.files, seed=a.seed)
    return 0
