"""Line-segment glyphs for directions (numpy only, any thread), and the colours and sizes
shared by every drawing of a frame: glyphs, the picked frame, lines of curvature, plots.

Principal directions have no sign, so a direction d at p is drawn as the segment
p - d*L/2 .. p + d*L/2 (a "±" glyph), never as an arrow. A normal has one (the cloud's
orientation): it is drawn outward, p .. p + n*L (``centred=False``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["subsample", "segments", "FRAME_COLOURS", "LEGEND", "glyph_width", "even_order", "glyph_index",
           "GLYPH_POINTS"]

#: Glyph positions a view draws at most (the density slider's 100 %), spread evenly over the
#: cloud (:func:`even_order`): like the cloud's own budget (app/lod.py), a frame must not
#: grow with N. Each position is two segments (the glyph and its white halo) per kind shown.
#: Measured with llvmpipe on this 2-core VM, 1200x800 view, 1M-point torus, e1+e2+n at 100 %:
#: all 1M positions froze the GUI thread 5.9 s and made every frame 1.6 s (still and turning;
#: 0.25 / 0.08 s without glyphs). Capped, quiet machine (0.12 / 0.03 s without glyphs):
#: 20k positions still 0.12-0.16 s, turning 0.06-0.07 s, switching all three on 0.1 s of GUI
#: thread; 30k 0.14-0.18 / 0.07-0.09 s; 100k 0.38 / 0.25 s. 20k keeps a turning frame near
#: the stand-in's own, and is already one glyph per ~7x7 pixels of a 1200x800 view.
GLYPH_POINTS = 20_000
#: The even selection thins a uniform random prefix of the cloud this many times the budget
#: (the drawing order of app.geometry): 80k candidates of a 1M torus take 0.06-0.09 s on
#: the loader thread (app.geometry).
_CANDIDATES = 4

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


def segments(points: np.ndarray, directions: np.ndarray, index: np.ndarray, length: float, *,
             centred: bool = True):
    """Vertices and VTK line connectivity for ± segments of total ``length`` (``centred``),
    or for segments from each point along its direction.

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
    along = float(length) * d / norm
    m = len(p)
    vertices = np.empty((2 * m, 3))
    vertices[0::2] = p - 0.5 * along if centred else p
    vertices[1::2] = p + 0.5 * along if centred else p + along
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


def _cells(keys: np.ndarray) -> np.ndarray:
    """One uint64 per row of (M, 3) non-negative cell keys: a hash (a rare collision merges
    two cells, which only thins the selection there)."""
    k = keys.astype(np.uint64)
    return (k[:, 0] * np.uint64(0x9E3779B97F4A7C15) ^ k[:, 1] * np.uint64(0xC2B2AE3D27D4EB4F)
            ^ k[:, 2] * np.uint64(0x165667B19E3779F9))


def _cell_size(p: np.ndarray, target: int) -> float:
    """A voxel size with about ``target`` occupied cells over ``p`` (points from the origin):
    the count falls as size^-2 on a surface, so a few corrections of that law are enough."""
    h = float(p.max()) / np.sqrt(target)
    for _ in range(4):
        occupied = len(np.unique(_cells(np.floor(p / h).astype(np.int64))))
        h *= np.sqrt(max(occupied, 1) / target)
    return h


def even_order(points: np.ndarray, order: np.ndarray, budget: int | None = None) -> np.ndarray:
    """At most ``budget`` (default :data:`GLYPH_POINTS`) point indices spread evenly over
    the cloud, in an order whose every prefix is spread evenly too (so a density is a
    prefix, and raising it only adds glyphs).

    ``order``: the cloud's random drawing order (any prefix a uniform random subset); its
    first ``_CANDIDATES * budget`` points are the candidates. Voxel grids of sizes h, 2h,
    4h, ... (h: about ``budget`` occupied cells) each keep the first candidate of every
    cell; those kept by coarser grids come first (nested: a coarse cell's first is its
    sub-cell's first too). The candidates no grid kept follow. Deterministic.
    """
    budget = GLYPH_POINTS if budget is None else int(budget)
    cand = np.asarray(order)[: _CANDIDATES * budget]
    target = min(budget, len(cand))
    p = np.asarray(points, dtype=float)[cand]
    if target <= 1 or not float(np.ptp(p, axis=0).max()) > 0:
        return cand[:target]
    p = p - p.min(axis=0)
    keys = np.minimum(np.floor(p / _cell_size(p, target)), 2.0 ** 40).astype(np.int64)
    level = np.full(len(cand), -1)
    rows, grid = np.arange(len(cand)), 0
    while len(rows) > 1:  # each grid twice as coarse, on the rows the finer one kept
        _, first = np.unique(_cells(keys[rows] >> grid), return_index=True)
        rows = rows[np.sort(first)]
        level[rows] = grid
        grid += 1
    kept = np.flatnonzero(level >= 0)
    kept = kept[np.lexsort((kept, -level[kept]))]  # coarsest grid first, then the random order
    return cand[np.r_[kept, np.flatnonzero(level < 0)][:budget]]


def glyph_index(order: np.ndarray, density: float) -> np.ndarray:
    """Sorted indices of the first ``round(density * len(order))`` of ``order``
    (:func:`even_order`): the density is a fraction of the budgeted positions."""
    density = float(min(max(density, 0.0), 1.0))
    return np.sort(np.asarray(order)[: int(round(density * len(order)))])
