"""What a method sees: a chunk of points with their neighbours and local frames."""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from .kernels import Frames
from .kernels.frame import intrinsic_frames, local_frames


@dataclass(frozen=True, eq=False)
class Chunk:
    """M centre points, their k neighbours and local frames (z = current normal).

    ``points`` and ``normals`` are the whole cloud's arrays (normals NaN where a point
    has none); ``idx`` (M, k) are the centres' neighbours, ``h`` (M,) the distance to the
    k-th neighbour. Fitting methods take a chunk and return ``(mu, W, ok)`` with W in
    units of 1/h (lengths divided by h). With ``rows`` (M,), ``idx`` is a larger graph
    (the whole cloud's) and centre r's neighbours are its row ``rows[r]``: the compiled
    NF kernel reads them in place, without a copy of the chunk's rows (:attr:`row_idx`
    makes one for the numpy methods).
    """

    points: np.ndarray
    normals: np.ndarray
    idx: np.ndarray
    h: np.ndarray
    centres: np.ndarray
    t1: np.ndarray
    t2: np.ndarray
    z: np.ndarray
    kc: np.ndarray
    rows: np.ndarray | None = None

    @classmethod
    def build(cls, points, normals, idx, h, centres, kc=None, rows=None):
        """``kc`` (M,): neighbours used per centre (default: all k columns of ``idx``);
        ``rows`` (M,): the row of ``idx`` of each centre (default: row r for centre r)."""
        centres = np.asarray(centres, dtype=np.int64)
        m = len(centres)
        z, t1, t2 = np.empty((m, 3)), np.empty((m, 3)), np.empty((m, 3))
        local_frames(np.ascontiguousarray(normals, dtype=np.float64), centres, z, t1, t2)  # z and tangent_basis(z)
        if kc is None:
            kc = np.full(len(centres), idx.shape[1], dtype=np.int64)
        if rows is not None:
            rows = np.asarray(rows, dtype=np.int64)
        return cls(points, normals, np.ascontiguousarray(idx), h, centres, t1, t2, z, kc, rows)

    def turning(self, k0: int) -> "Chunk":
        """This chunk in tangent frames that turn with the cloud, t1 along its first ``k0``
        neighbours' offsets (:func:`core.kernels.frame.intrinsic_frames`): for rules that
        compare fitted entries one by one, which in frames fixed to the world's axes give
        a rotated cloud other answers."""
        k0 = min(k0, self.idx.shape[1])
        first = self.idx[:, :k0] if self.rows is None else self.idx[self.rows, :k0]
        t1, t2 = self.t1.copy(), self.t2.copy()
        intrinsic_frames(self.points, self.centres, self.z, np.ascontiguousarray(first), t1, t2)
        return replace(self, t1=t1, t2=t2)

    @property
    def row_idx(self) -> np.ndarray:
        """(M, k) the centres' neighbours (a copy of their rows when ``rows`` is given)."""
        return self.idx if self.rows is None else self.idx[self.rows]

    def kernel_rows(self) -> np.ndarray:
        """(M,) the row of :attr:`idx` of each centre, as the compiled kernels take it."""
        return np.arange(len(self.centres), dtype=np.int64) if self.rows is None else self.rows

    def frames(self) -> Frames:
        """The chunk as the record the compiled kernels take."""
        return Frames(self.points, self.normals, self.idx, self.kc, self.h, self.centres, self.t1, self.t2, self.z)

    @cached_property
    def patch(self) -> "Patch":
        """The neighbourhoods as arrays in the local frames (for the numpy methods)."""
        return make_patch(self)


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


def make_patch(chunk: Chunk) -> Patch:
    """Express each centre's neighbours in its local frame, lengths in units of h."""
    points, normals, idx, centres, h = chunk.points, chunk.normals, chunk.row_idx, chunk.centres, chunk.h
    t1, t2, z = chunk.t1, chunk.t2, chunk.z
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
