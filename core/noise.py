"""Reproducible perturbations: Gaussian noise (isotropic or along the normal) and outliers."""

from __future__ import annotations

import numpy as np

from ._validate import as_normals, as_points, word
from .spacing import mean_spacing

_DIRECTIONS = ("isotropic", "normal")
__all__ = ["mean_spacing", "add_noise", "add_outliers"]


def add_noise(points, sigma, *, normals=None, direction="isotropic", relative=True, seed=0, spacing=None):
    """Return a noisy copy of ``points`` (the input is never modified).

    Parameters
    ----------
    sigma : float >= 0, standard deviation; a fraction of the mean spacing when
        ``relative`` (the default), else in the points' units.
    normals : (N, 3), required for ``direction="normal"``.
    direction : "isotropic" (3D Gaussian) or "normal" (Gaussian along each normal).
    seed : int, the same seed and sigma give the same cloud.
    spacing : float, optional, the spacing unit when ``relative`` (default: computed).
    """
    pts, _ = as_points(points)
    sigma = float(sigma)
    if not np.isfinite(sigma) or sigma < 0:
        raise ValueError(f"sigma must be a finite number >= 0, got {sigma}")
    direction = word(direction)
    if direction not in _DIRECTIONS:
        raise ValueError(f"direction {direction!r} is invalid; must be one of {list(_DIRECTIONS)}")
    if relative:
        sigma *= mean_spacing(pts) if spacing is None else float(spacing)
    rng = np.random.default_rng(seed)
    if direction == "isotropic":
        return pts + rng.normal(scale=sigma, size=pts.shape)
    if normals is None:
        raise ValueError('direction="normal" needs normals')
    nrm = as_normals(normals, len(pts))
    return pts + rng.normal(scale=sigma, size=(len(pts), 1)) * nrm


def add_outliers(points, fraction, *, distance=(5.0, 20.0), seed=0, spacing=None):
    """Move a ``fraction`` of the points far off the surface.

    Each chosen point moves in a random direction by a distance drawn uniformly from
    ``distance`` (in mean spacings). Returns ``(new_points, is_outlier)``.
    """
    pts, _ = as_points(points)
    fraction = float(fraction)
    if not 0 <= fraction < 1:
        raise ValueError(f"fraction must be in [0, 1), got {fraction}")
    lo, hi = distance
    if not 0 <= lo <= hi:
        raise ValueError(f"distance must be (low, high) with 0 <= low <= high, got {distance}")
    rng = np.random.default_rng(seed)
    unit = mean_spacing(pts) if spacing is None else float(spacing)
    mask = np.zeros(len(pts), dtype=bool)
    mask[rng.choice(len(pts), size=int(round(fraction * len(pts))), replace=False)] = True
    d = rng.normal(size=(int(mask.sum()), 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    out = pts.copy()
    out[mask] += d * (rng.uniform(lo, hi, size=(len(d), 1)) * unit)
    return out, mask
