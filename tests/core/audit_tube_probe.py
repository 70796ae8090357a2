"""The tube test probed in the round-eight audit (README): how often sqrt(l_mid / l_max) < 0.5 and
sqrt(l_min / l_mid) > 0.5 fire on wires and on surfaces estimated right (``PYTHONPATH=. python tests/core/audit_tube_probe.py``)."""
import os, sys
import numpy as np
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # the audit generators beside it
import core
from core.noise import add_noise
from core import shapes, shapes_thin
from scipy.spatial import cKDTree
import audit_thin as T
from audit_inputs import ribbon

def shape_stats(pts, res, sel, floor=40):
    tree = cKDTree(pts); e = np.full(len(pts), np.nan); f = e.copy()
    kk = np.maximum(res.k_point, floor)
    for k in np.unique(kk[sel]):
        c = sel[kk[sel] == k]
        _, idx = tree.query(pts[c], k=int(min(k, len(pts))))
        nb = pts[idx] - pts[idx].mean(1, keepdims=True)
        lam = np.linalg.eigvalsh(np.einsum("mki,mkj->mij", nb, nb))  # ascending
        e[c] = np.sqrt(lam[:, 1] / lam[:, 2]); f[c] = np.sqrt(lam[:, 0] / np.maximum(lam[:, 1], 1e-300))
    return e, f

def report(name, pts, mask, k):
    res = core.estimate(pts, k=k)
    sel = np.flatnonzero(res.valid & mask)
    if not len(sel): print(name, k, "none valid"); return
    e, f = shape_stats(pts, res, sel)
    e, f = e[sel], f[sel]
    fire = (e < 0.5) & (f > 0.5)
    fire2 = (e < 0.6) & (f > 0.4)
    print(f"{name:<18} k{k:<5} valid {len(sel)}/{mask.sum()} fire(e<.5,f>.5) {fire.mean():.4f} ({fire.sum()}) fire(e<.6,f>.4) {fire2.mean():.4f} ({fire2.sum()}) e p1/50 {np.percentile(e,[1,50]).round(2)} f p50/99/99.9 {np.percentile(f,[50,99,99.9]).round(2)}", flush=True)

cases = []
for sig in (0.0, 0.2, 0.5):
    for r in (0.5, 1.0, 2.0, 3.0):
        w = T.wire_over_plane(8000, radius_spacings=r, seed=0); p = add_noise(w.points, sig*w.params["spacing"], relative=False, seed=3)
        cases.append((f"wire{r} s{sig}", p, w.params["part"] == 1))
        if r == 1.0: cases.append((f"ground s{sig}", p, w.params["part"] == 0))
    l = T.line_over_plane(8000, height=0.05, seed=0); p = add_noise(l.points, sig*l.params["spacing"], relative=False, seed=3)
    cases.append((f"rail s{sig}", p, l.params["part"] == 1))
    h = T.helix(3000, seed=0); cases.append((f"helix s{sig}", add_noise(h.points, sig*h.params["spacing"], relative=False, seed=2), np.ones(3000, bool)))
for sig in (0.0, 0.2, 0.5):
    t = shapes.torus(20000, seed=0).points; cases.append((f"torus s{sig}", add_noise(t, sig, seed=1), np.ones(len(t), bool)))
    for ratio in (3.0, 8.0, 16.0):
        s = shapes_thin.stripe_scan(20000, ratio=ratio, seed=0).points; cases.append((f"stripe{ratio} s{sig}", add_noise(s, sig, seed=1), np.ones(len(s), bool)))
    for rr in (2.0, 3.0):
        tt = shapes_thin.thin_tube(20000, radius_spacings=rr, seed=0).points; cases.append((f"tube{rr} s{sig}", add_noise(tt, sig, seed=1), np.ones(len(tt), bool)))
    rs = shapes_thin.range_scan(20000, seed=0).points; cases.append((f"rangescan s{sig}", add_noise(rs, sig, seed=1), np.ones(len(rs), bool)))
    rb = ribbon(width_spacings=4.0).points; cases.append((f"ribbon4 s{sig}", add_noise(rb, sig, seed=1), np.ones(len(rb), bool)))
    for mk in (shapes_thin.thin_plate, shapes_thin.thin_shell, shapes_thin.thin_wedge, shapes_thin.thin_bracket):
        q = mk(20000, seed=0).points; cases.append((f"{mk.__name__} s{sig}", add_noise(q, sig, seed=1), np.ones(len(q), bool)))
    c = shapes.cube(20000, seed=0).points; cases.append((f"cube s{sig}", add_noise(c, sig, seed=1), np.ones(len(c), bool)))
for name, p, m in cases:
    for k in (15, "auto"):
        report(name, p, m, k)
