"""APSS's sign and pairing conventions, checked on shapes with known answers."""

from __future__ import annotations

import numpy as np

from ... import metrics, shapes
from .. import apss as _apss
from .config import _nanmean


def apss_conventions() -> dict:
    """Run APSS on shapes with known answers and report its sign and pairing conventions.

    Returns numbers (medians) for: an exact sphere of radius 2 with outward and with inward
    normals (H must be +0.5 / -0.5: no crash, k = +1/R outward), and a torus R = 1.5, r = 1
    (H changes sign: the PD1/PD2 pairing must hold on both sides) with exact normals.
    """
    out = {}
    sph = shapes.sphere(2000, radius=2.0, seed=1)
    for sign in (1, -1):
        r = _apss.apss_curvature(sph.points, sign * sph.normals, scale=4.0)
        out[f"sphere_H_{'out' if sign > 0 else 'in'}"] = float(np.median(r.mean[r.valid]))
        out[f"sphere_K_{'out' if sign > 0 else 'in'}"] = float(np.median(r.gaussian[r.valid]))
    tor = shapes.torus(6000, R=1.5, r=1.0, seed=2)
    r = _apss.apss_curvature(tor.points, tor.normals, scale=6.0)
    pe = metrics.point_errors(r, tor)
    neg = tor.mean < -0.05
    pos = tor.mean > 0.05
    out["torus_dir_deg_Hpos"] = _nanmean(pe["direction_deg"][pos])
    out["torus_dir_deg_Hneg"] = _nanmean(pe["direction_deg"][neg])
    out["torus_H_err"] = _nanmean(pe["mean"])
    out["torus_frac_Hneg"] = float(neg.mean())
    d = pe["direction_deg"]
    near = np.abs(tor.mean) < 0.1
    out["torus_swapped_near_H0"] = float(np.mean(d[near & np.isfinite(d)] > 60)) if near.any() else float("nan")
    out["torus_swapped_all"] = float(np.mean(d[np.isfinite(d)] > 60))
    # the pairing the other way round would give ~90 degrees on one side
    out["ok"] = bool(abs(out["sphere_H_out"] - 0.5) < 0.01 and abs(out["sphere_H_in"] + 0.5) < 0.01
                     and out["torus_dir_deg_Hpos"] < 10 and out["torus_dir_deg_Hneg"] < 10)
    return out
