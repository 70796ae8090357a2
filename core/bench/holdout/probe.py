"""``python -m core bench holdout --probe``: where the default's principal direction comes from
with noise, and what else it could come from (issue 15's open e1 cells; see core/scale.py).

Per (surface, noise) case, the mean e1 error (degrees, the race's points) of: NR's refined
fit (the default), its first fit (no refinement pass), the position jet of the jet rule at
its own chosen k (:func:`core.scale.choose_jets`), the two averaged (half of each traceless
shape operator, in NR's tangent plane), and NR's direction averaged over its 8 nearest points
(a wider scale for the direction alone); plus the share of points whose NR fit is on the
largest candidate. A ratio below 1 would be a better direction than the default's.
"""

from __future__ import annotations

import numpy as np

from ... import metrics
from ..._progress import Progress
from ...estimate import prepare
from ...linalg import tangent_basis
from ...planning import plan as make_plan
from ...refinement import fit_passes, refine
from .harness import make_case


def _angles(nrm, e1, e2, sample, use):
    flip = np.einsum("ij,ij->i", nrm, sample.normals) < 0
    e = np.where(flip[:, None], e2, e1)
    deg = np.degrees(np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", e, sample.e1)), 0.0, 1.0)))
    return float(np.nanmean(np.where(use, deg, np.nan)))


def _shape(k1, k2, e1, e2, nrm, ref):
    """k1 e1 e1^T + k2 e2 e2^T, its sign turned to the orientation of ``ref``."""
    s = k1[:, None, None] * np.einsum("ni,nj->nij", e1, e1) + k2[:, None, None] * np.einsum("ni,nj->nij", e2, e2)
    return np.nan_to_num(np.where((np.einsum("ij,ij->i", nrm, ref) < 0)[:, None, None], -s, s))


def _direction(S, nrm):
    """The first principal direction of the (averaged) shape operators S in the planes of ``nrm``."""
    b1, b2 = tangent_basis(np.nan_to_num(nrm, nan=0.0) + np.isnan(nrm).any(1)[:, None] * [0.0, 0.0, 1.0])
    d = np.einsum("ni,nij,nj->n", b1, S, b1) - np.einsum("ni,nij,nj->n", b2, S, b2)
    o = 2 * np.einsum("ni,nij,nj->n", b1, S, b2)
    half = 0.5 * np.arctan2(o, d)
    e1 = np.cos(half)[:, None] * b1 + np.sin(half)[:, None] * b2
    return e1, np.cross(nrm, e1)


def probe_case(sampler, name, level, n, seed, evaluate) -> dict:
    """The e1 errors of the alternatives above on one case (in the stages' spatial order)."""
    sample, pts, ev = make_case(sampler, name, level, n, seed, evaluate)
    plan = make_plan(len(pts))
    report = Progress(None)
    front = prepare(pts, None, plan, None, report)
    order = front.order.order if front.order.order is not None else np.arange(len(pts))
    s = sample  # truth in the sorted order
    truth = type("T", (), {"normals": s.normals[order], "e1": s.e1[order]})
    umbilic = (s.k1 - s.k2) <= metrics.UMBILIC * np.maximum(np.abs(s.k1), np.abs(s.k2))
    use = (ev & s.interior & ~umbilic)[order]
    best = refine(front.pts, front.init, front.outlier, front.fit_nb, front.scale, plan, report).fit
    first = next(fit_passes(front.pts, front.init, front.outlier, front.fit_nb, front.scale, plan, report,
                             n_fits=1))[1]
    jets, ok = front.scale.jets, best.valid & front.scale.jets[-1]
    out = {"nr": _angles(best.normals, best.e1, best.e2, truth, use & ok)}
    out["first fit"] = _angles(first.normals, first.e1, first.e2, truth, use & ok & first.valid) / out["nr"]
    out["jet"] = _angles(jets[0], jets[3], jets[4], truth, use & ok) / out["nr"]
    s_nr = _shape(best.k1, best.k2, best.e1, best.e2, best.normals, best.normals)
    s_jet = _shape(jets[1], jets[2], jets[3], jets[4], jets[0], best.normals)
    out["half jet"] = _angles(best.normals, *_direction(0.5 * (s_nr + s_jet), best.normals), truth, use & ok) / out["nr"]
    idx, _ = front.nb.take(8)
    nearby = np.einsum("nj,njab->nab", best.valid[idx] * np.sign(np.einsum("ni,nji->nj", np.nan_to_num(best.normals),
                                                                                np.nan_to_num(best.normals)[idx])),
                       s_nr[idx])
    out["8 nearest"] = _angles(best.normals, *_direction(nearby, best.normals), truth, use & ok) / out["nr"]
    out["on largest k"] = float(np.mean(front.scale.k[use] == plan.candidates[-1]))
    return out


def main(names, levels, surfaces, args) -> None:
    print("e1 error of the default (NR, degrees) and of the alternatives as a ratio to it")
    for name in names:
        for level in levels:
            if level == 0:
                continue
            r = probe_case(surfaces[name], name, level, args.points, args.seed, args.evaluate)
            cells = "  ".join(f"{k} {v:.2f}" for k, v in r.items() if k != "nr")
            print(f"{name:<11} {level:4g}  nr {r['nr']:.3f}  {cells}", flush=True)
