"""Line-segment glyphs for directions (numpy only, any thread), and the colours and sizes
shared by every drawing of a frame: glyphs, the picked frame, lines of curvature, plots.

Principal directions have no sign, so a direction d at p is drawn as the segment
p - d*L/2 .. p + d*L/2 (a "±" glyph), never as an arrow.
"""

from __future__ import annotations

import numpy as np

__all__ = ["subsample", "segments", "FRAME_COLOURS", "LEGEND", "glyph_width"]

#: One colour per frame vector, everywhere (glyphs, picked frame, curvature lines, plots):
#: near-black e1 and green e2 read over both the diverging and the sequential colour maps;
#: purple n is neither.
FRAME_COLOURS = {"e1": "#111111", "e2": "#1a9850", "n": "#7b3294"}
#: glyph legend entries (label, colour) for saved figures
LEGEND = (("e1 (direction of k1)", FRAME_COLOURS["e1"]), ("e2 (direction of k2)", FRAME_COLOURS["e2"]),
          ("normal n", FRAME_COLOURS["n"]))


def glyph_width(n_points: int) -> float:
    """Line width in pixels: 3 for sparse clouds (a few thousand points), down to 1.5 for dense
    ones, where wider glyphs merge into a carpet."""
    return float(np.clip(3.0 - 0.5 * np.log10(max(n_points, 1) / 5000.0), 1.5, 3.0))


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


def polylines(lines) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and VTK connectivity ``[m, i0, ..., i(m-1), ...]`` for a list of (m, 3) polylines."""
    lines = [np.asarray(line, dtype=float) for line in lines if len(line) >= 2]
    if not lines:
        return np.empty((0, 3)), np.empty(0, dtype=np.int64)
    vertices = np.concatenate(lines)
    cells, start = [], 0
    for line in lines:
        cells.append(np.concatenate([[len(line)], np.arange(start, start + len(line))]))
        start += len(line)
    return vertices, np.concatenate(cells).astype(np.int64)
