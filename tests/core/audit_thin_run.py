"""Round-eight audit runner (README, "Round-eight input audit"): ``PYTHONPATH=. python tests/core/audit_thin_run.py
CLASS [SEEDS] [SIGMAS]``, CLASS one of wire, line, helix, holes, under, double; one JSON line per estimate."""
import json, os, sys, time
import numpy as np
from scipy.spatial.transform import Rotation
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))  # the audit generators beside it
import core
from core.noise import add_noise
from core.shapes import sphere, torus, plane
from audit_shapes import with_holes, plane_and_sphere, subset, spaced
import audit_thin as T

def posed(pts, nrm, seed):
    R = Rotation.random(random_state=100 + seed).as_matrix()
    off = np.random.default_rng(seed).uniform(-5, 5, 3)
    return pts @ R.T + off, nrm @ R.T

def metrics(res, nrm_true, H_true, mask, has_truth=True):
    m = mask
    v = res.valid[m]
    out = {"n": int(m.sum()), "valid": round(float(v.mean()), 4) if m.sum() else None}
    if not v.any():
        return out
    n_est = res.normals[m][v]
    Hest = res.mean[m][v]
    if not has_truth:
        out["medHs"] = float(np.median(np.abs(Hest)))
        out["crease"] = round(float(res.crease[m][v].mean()), 3)
        out["border"] = round(float(res.border[m][v].mean()), 3)
        return out
    nt = nrm_true[m][v]
    cos = np.einsum("ij,ij->i", n_est, nt)
    sign = np.where(cos < 0, -1.0, 1.0)
    ang = np.degrees(np.arccos(np.clip(np.abs(cos), 0, 1)))
    Ht = H_true[m][v]
    err = np.abs(Hest * sign - Ht)
    rel = np.where(np.abs(Ht) > 1e-9, err / np.maximum(np.abs(Ht), 1e-300), err)
    off = ((err > np.abs(Ht)) & (np.abs(Ht) > 1e-9)) | (ang > 10)
    out.update(medrel=float(np.median(rel)), p90rel=float(np.percentile(rel, 90)),
               off=round(float(off.mean()), 4), offflag=round(float((off & ~res.crease[m][v] & ~res.border[m][v]).mean()), 4),
               ang50=round(float(np.median(ang)), 2))
    return out

def run(name, sample, sigma, seed, masks, has_truth=True):
    s = sample.params["spacing"]
    pts, nrm = posed(sample.points, np.nan_to_num(sample.normals), seed)
    if sigma:
        pts = add_noise(pts, sigma * s, relative=False, seed=seed + 11)
    scale = 1.0
    for k in (15, "auto"):
        t = time.process_time()
        res = core.estimate(pts, k=k)
        row = {"cls": name, "sigma": sigma, "seed": seed, "k": str(k), "cpu": round(time.process_time() - t, 1)}
        for mname, (m, truth) in masks.items():
            row[mname] = metrics(res, nrm, sample.mean, m, truth)
        print(json.dumps(row), flush=True)

SIGMAS = [0.0, 0.1, 0.2, 0.5]
def cls_wire(seed, sigma):
    for r in (0.5, 1.0, 2.0):
        smp = T.wire_over_plane(8000, radius_spacings=r, seed=seed)
        p = smp.params["part"]
        run(f"wire r{r}", smp, sigma, seed, {"wire": (p == 1, True), "ground": (p == 0, True)})
    smp = T.wire_over_plane(8000, radius_spacings=1.0, seed=seed, vertical=True)
    p = smp.params["part"]
    run("pole r1", smp, sigma, seed, {"pole": (p == 1, True), "ground": (p == 0, True)})
    smp = T.wire_over_plane(8000, radius_spacings=4.0, seed=seed)
    p = smp.params["part"]
    run("wire r4", smp, sigma, seed, {"wire": (p == 1, True), "ground": (p == 0, True)})

def cls_line(seed, sigma):
    for h in (0.3, 0.05):
        smp = T.line_over_plane(8000, height=h, seed=seed)
        p = smp.params["part"]
        run(f"line h{h}", smp, sigma, seed, {"line": (p == 1, False), "ground": (p == 0, True)})

def cls_helix(seed, sigma):
    smp = T.helix(3000, seed=seed)
    run("helix", smp, sigma, seed, {"helix": (np.ones(len(smp.points), bool), False)})

def cls_holes(seed, sigma):
    for base in (spaced(plane(12000, seed=seed), 4.0), spaced(sphere(12000, seed=seed), 4*np.pi), spaced(torus(12000, seed=seed), 8*np.pi**2)):
        smp = with_holes(base, holes=8, radius_spacings=(2.0, 10.0), seed=seed)
        rim = smp.params["rim"] & smp.interior
        run(f"holes {base.name}", smp, sigma, seed, {"rim": (rim, True), "rest": (~smp.params["rim"] & smp.interior, True)})

def cls_under(seed, sigma):
    for c in (1.5, 2.0, 3.0):
        smp = plane_and_sphere(8000, radius_spacings=c, seed=seed)
        p = smp.params["part"]
        run(f"ball c{c}", smp, sigma, seed, {"ball": (p == 1, True), "ground": (p == 0, True)})
    for L in (3.0, 5.0, 8.0):
        smp = T.sinusoid(8000, wavelength_spacings=L, seed=seed)
        run(f"sin L{L}", smp, sigma, seed, {"in": (smp.interior, True)})

def cls_double(seed, sigma):
    for d in (0.3, 1.0, 2.0):
        for base in (spaced(sphere(12000, seed=seed), 4*np.pi), spaced(torus(12000, seed=seed), 8*np.pi**2)):
            smp = T.double_sheet(base, d, seed=seed)
            run(f"double {base.name} d{d}", smp, sigma, seed, {"all": (smp.interior, True)})

if __name__ == "__main__":
    seeds = [int(x) for x in sys.argv[2].split(",")] if len(sys.argv) > 2 else [0, 1]
    sig = [float(x) for x in sys.argv[3].split(",")] if len(sys.argv) > 3 else SIGMAS
    for seed in seeds:
        for sigma in sig:
            globals()["cls_" + sys.argv[1]](seed, sigma)
