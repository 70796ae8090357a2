"""Errors of an estimate against an analytic :class:`core.shapes.Sample`."""

from __future__ import annotations

import numpy as np

#: principal directions are not compared where |k1 - k2| < UMBILIC x max(|k1|, |k2|)
UMBILIC = 0.1


def _angle_deg(a, b):
    cos = np.abs(np.einsum("ij,ij->i", a, b))
    return np.degrees(np.arccos(np.clip(cos, 0.0, 1.0)))


def aligned(result, sample):
    """Estimated (k1, k2, e1, e2, flipped) expressed with the sample's normal orientation.

    Where the estimated normal points the other way, the curvatures change sign and
    swap, and so do the directions (SPEC conventions). Orientation is reported apart.
    """
    flipped = np.einsum("ij,ij->i", result.normals, sample.normals) < 0
    k1 = np.where(flipped, -result.k2, result.k1)
    k2 = np.where(flipped, -result.k1, result.k2)
    e1 = np.where(flipped[:, None], result.e2, result.e1)
    e2 = np.where(flipped[:, None], result.e1, result.e2)
    return k1, k2, e1, e2, flipped


def point_errors(result, sample):
    """Per-point absolute errors (NaN where the result is invalid or not comparable).

    Keys: "k1", "k2", "gaussian", "mean", "normal_deg" (sign-free angle), "direction_deg"
    (angle between e1 and the true e1, sign-free, NaN near umbilics).
    """
    if len(result.points) != len(sample.points):
        raise ValueError(
            f"result has {len(result.points)} points but sample has {len(sample.points)}"
        )
    k1, k2, e1, _, _ = aligned(result, sample)
    err = {
        "k1": np.abs(k1 - sample.k1),
        "k2": np.abs(k2 - sample.k2),
        "gaussian": np.abs(k1 * k2 - sample.gaussian),
        "mean": np.abs(0.5 * (k1 + k2) - sample.mean),
        "normal_deg": _angle_deg(result.normals, sample.normals),
    }
    scale = np.maximum(np.abs(sample.k1), np.abs(sample.k2))
    umbilic = (sample.k1 - sample.k2) <= UMBILIC * scale
    err["direction_deg"] = np.where(umbilic, np.nan, _angle_deg(e1, sample.e1))
    for key in err:
        err[key] = np.where(result.valid, err[key], np.nan)
    return err


def summary(result, sample, *, mask=None):
    """Mean absolute errors over valid interior points, plus invalid and flipped fractions."""
    err = point_errors(result, sample)
    use = sample.interior.copy() if mask is None else (np.asarray(mask, bool) & sample.interior)
    out = {}
    for key, val in err.items():
        v = val[use & np.isfinite(val)]
        out[key] = float(v.mean()) if len(v) else float("nan")
    out["invalid_fraction"] = float(np.mean(~result.valid[use])) if use.any() else float("nan")
    _, _, _, _, flipped = aligned(result, sample)
    out["flipped_fraction"] = float(np.mean(flipped[use & result.valid])) if use.any() else float("nan")
    return out
