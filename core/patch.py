"""Local patches: each point's neighbours expressed in a frame whose z axis is its normal."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .linalg import tangent_basis


@dataclass(frozen=True, eq=False)
class Patch:
    """Neighbourhoods of a chunk of M points, k neighbours each, in local frames.

    Lengths are divided by the per-point scale ``h`` (the distance to the k-th
    neighbour) so every fit is well conditioned; derivatives fitted in these units are
    divided by ``h`` once, in :func:`core.estimate`.

    Attributes
    ----------
    t1, t2, z : (M, 3) local frame (z = current normal of the centre point).
    u, v, w : (M, k) neighbour offsets along t1, t2, z, in units of h.
    X, Y, Z : (M, k) neighbour normal components in the frame, flipped so Z >= 0
        (agreement with the centre normal, paper §4.3).
    weight : (M, k) 1 for usable neighbours, 0 for neighbours without a normal.
    h : (M,) scale.
    """

    t1: np.ndarray
    t2: np.ndarray
    z: np.ndarray
    u: np.ndarray
    v: np.ndarray
    w: np.ndarray
    X: np.ndarray
    Y: np.ndarray
    Z: np.ndarray
    weight: np.ndarray
    h: np.ndarray

    @property
    def dist(self) -> np.ndarray:
        """(M, k) distances to the centre, in units of h."""
        return np.sqrt(self.u**2 + self.v**2 + self.w**2)


def make_patch(points, normals, idx, centres, h) -> Patch:
    """Build the patch of ``centres`` (indices) whose neighbours are ``idx`` (M, k)."""
    z = normals[centres]
    t1, t2 = tangent_basis(z)
    d = points[idx] - points[centres][:, None, :]
    inv_h = 1.0 / h
    u = np.einsum("mkj,mj->mk", d, t1) * inv_h[:, None]
    v = np.einsum("mkj,mj->mk", d, t2) * inv_h[:, None]
    w = np.einsum("mkj,mj->mk", d, z) * inv_h[:, None]
    nb = normals[idx]
    X = np.einsum("mkj,mj->mk", nb, t1)
    Y = np.einsum("mkj,mj->mk", nb, t2)
    Z = np.einsum("mkj,mj->mk", nb, z)
    usable = np.isfinite(Z)
    flip = np.where(Z < 0.0, -1.0, 1.0)
    X = np.where(usable, X * flip, 0.0)
    Y = np.where(usable, Y * flip, 0.0)
    Z = np.where(usable, Z * flip, 1.0)
    return Patch(t1, t2, z, u, v, w, X, Y, Z, usable.astype(np.float64), h)
