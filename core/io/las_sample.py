"""A bounded-memory subsample of a LAS/LAZ file, whole or inside a box, with its fields.

For looking at results larger than memory (the viewer's level-of-detail preview of a
tiled result, :mod:`app.big_result`): :func:`sample_las` streams the file in chunks and
keeps every s-th point (inside the box, if one is given), doubling s whenever more than
``budget`` points are kept, so that memory stays within ``budget`` points plus one chunk
and the sample is uniform over the points it stands for, in file order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._progress import Progress
from .._validate import check_int
from .las_stream import CHUNK, iter_records, open_las, xyz_of


@dataclass(frozen=True)
class LasSample:
    """Every ``stride``-th of the ``matched`` file points in the box, in file order.

    Attributes
    ----------
    points : (m, 3) float64 scaled coordinates, m <= the budget.
    fields : name -> (m,) array of each requested dimension (its stored dtype).
    rows : (m,) int64 rows of the sampled points in the file.
    matched : file points inside the box (all of them without a box).
    stride : the sample keeps one point in ``stride`` of those.
    """

    points: np.ndarray
    fields: dict
    rows: np.ndarray
    matched: int
    stride: int


def sample_las(path, budget: int, *, names=None, box=None, chunk: int = CHUNK, progress=None) -> LasSample:
    """At most ``budget`` evenly spread points of a LAS/LAZ file (in ``box`` if given).

    Parameters
    ----------
    path : LAS/LAZ file.
    budget : largest number of points returned (>= 1).
    names : dimensions to return with the points (default: every extra-bytes and
        standard dimension but X, Y, Z); a name the file does not have raises ValueError.
    box : ((3,), (3,)) lower and upper corners, optional: only points inside (bounds
        included) are sampled.
    chunk : points read at a time.
    progress : callable(fraction, stage) -> None | False, optional; called after each
        chunk, False cancels (:class:`core.Cancelled`).

    Raises
    ------
    CloudFileError
        The file is unreadable, truncated or has an invalid header (names it).
    ValueError
        A bad budget, box or dimension name.
    """
    budget = check_int(budget, name="budget", low=1, high=10**10)
    report = Progress(progress)
    info = open_las(path)
    names = _names(path, info, names)
    lo, hi = _box(box)
    stride = 1 if box is not None else max(1, -(-info.count // budget))  # the whole file: known count
    kept: list = []  # per chunk: (match ranks, rows, points, fields), thinned when over budget
    matched = 0
    for start, rec in iter_records(path, chunk=chunk, info=info):
        xyz = xyz_of(rec)
        inside = np.arange(len(xyz)) if lo is None else np.flatnonzero(((xyz >= lo) & (xyz <= hi)).all(axis=1))
        rank = matched + np.arange(len(inside))
        take = rank % stride == 0  # every stride-th match
        pick = inside[take]
        kept.append((rank[take], start + pick, xyz[pick], {n: np.array(rec[n])[pick] for n in names}))
        matched += len(inside)
        report((start + len(xyz)) / max(info.count, 1), "reading")
        while sum(len(part[0]) for part in kept) > budget:
            stride *= 2
            kept = [_thin(part, stride) for part in kept]
    return _joined(kept, names, matched, stride)


def _names(path, info, names) -> list:
    names = list(info.dims if names is None else names)
    missing = [n for n in names if n not in info.dims]
    if missing:
        raise ValueError(f"{path}: no dimension {missing[0]!r}; the file has {list(info.dims)}")
    return names


def _joined(kept, names, matched, stride) -> LasSample:
    if not kept:
        return LasSample(np.zeros((0, 3)), {n: np.zeros(0) for n in names}, np.zeros(0, np.int64), 0, stride)
    rows = np.concatenate([part[1] for part in kept]).astype(np.int64)
    pts = np.concatenate([part[2] for part in kept])
    fields = {n: np.concatenate([part[3][n] for part in kept]) for n in names}
    return LasSample(pts, fields, rows, matched, stride)


def _thin(part, stride):
    """Keep the points of ``part`` whose rank among the matches is a multiple of ``stride``."""
    rank, rows, pts, fields = part
    keep = rank % stride == 0
    return rank[keep], rows[keep], pts[keep], {n: v[keep] for n, v in fields.items()}


def _box(box):
    if box is None:
        return None, None
    try:
        lo, hi = (np.asarray(c, dtype=float).reshape(3) for c in box)
    except (TypeError, ValueError):
        raise ValueError(f"box {box!r} is invalid; give two corners (x, y, z), lower then upper") from None
    if not (np.isfinite(lo).all() and np.isfinite(hi).all() and (lo <= hi).all()):
        raise ValueError(f"box {box!r} is invalid; the corners must be finite with lower <= upper")
    return lo, hi
