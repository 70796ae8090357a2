"""Line-segment glyphs for directions (numpy only, any thread).

Principal directions have no sign, so a direction d at p is drawn as the segment
p - d*L/2 .. p + d*L/2 (a "±" glyph), never as an arrow.
"""

from __future__ import annotations

import numpy as np

__all__ = ["subsample", "segments"]


def subsample(n: int, density: float, *, seed: int = 0) -> np.ndarray:
    """Indices of ``round(density * n)`` points, a stable prefix of a fixed permutation.

    Raising the density only adds glyphs; the ones already shown stay put.
    """
    density = float(min(max(density, 0.0), 1.0))
    m = int(round(density * n))
    if m <= 0:
        return np.empty(0, dtype=np.intp)
    order = np.random.default_rng(seed).permutation(n)
    return np.sort(order[:m])


def segments(points: np.ndarray, directions: np.ndarray, index: np.ndarray, length: float):
    """Vertices and VTK line connectivity for ± segments of total ``length``.

    Rows whose direction is not finite (invalid estimates) are skipped.

    Returns
    -------
    vertices : (2M, 3) float array
    lines : (3M,) int array in VTK's ``[2, i, j, 2, ...]`` layout
    """
    p = np.asarray(points, dtype=float)[index]
    d = np.asarray(directions, dtype=float)[index]
    ok = np.isfinite(d).all(axis=1) & np.isfinite(p).all(axis=1)
    p, d = p[ok], d[ok]
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    norm[norm == 0] = 1.0
    half = 0.5 * float(length) * d / norm
    m = len(p)
    vertices = np.empty((2 * m, 3))
    vertices[0::2] = p - half
    vertices[1::2] = p + half
    lines = np.empty((m, 3), dtype=np.int64)
    lines[:, 0] = 2
    lines[:, 1] = np.arange(0, 2 * m, 2)
    lines[:, 2] = lines[:, 1] + 1
    return vertices, lines.ravel()
