"""A bounded-memory subsample of a LAS/LAZ file, whole or inside a box, with its fields.

For looking at results larger than memory (the viewer's level-of-detail preview of a
tiled result, :mod:`app.big_result`): :func:`sample_las` streams the file in chunks and
keeps every s-th point (inside the box, if one is given), doubling s whenever more than
``budget`` points are kept, so that memory stays within ``budget`` points plus one chunk
and the sample is uniform over the points it stands for, in file order.

A layered LAZ (point format >= 6, as the tiled run writes) is read in two passes: the
coordinates alone choose the rows (they decompress ~10x faster than the float64 fields),
then only the LAZ chunks holding chosen rows are decompressed whole: a region of a scan
stored in scan order touches few of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._progress import Progress
from .._validate import check_int
from .cloud import CloudFileError
from .las import rust_panics_refused
from .las_open import open_reader
from .las_stream import CHUNK, iter_records, open_las, xyz_of

#: points read after each seek of the second pass: a LAZ chunk as laspy and lazrs write it
BLOCK = 50_000


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
    if info.layered:
        rank, rows, matched, stride = _choose(path, info, budget, lo, hi, stride, chunk, report.sub(0.0, 0.5))
        pts, fields = _fetch(path, info, rows, names, report.sub(0.5, 1.0))
        return LasSample(pts, fields, rows, matched, stride)
    kept: list = []  # per chunk: (match ranks, rows, points, fields), thinned when over budget
    matched = 0
    for start, rec in iter_records(path, chunk=chunk, info=info):
        xyz = xyz_of(rec)
        rank, pick, n_inside = _picks(xyz, lo, hi, matched, stride)
        kept.append((rank, start + pick, xyz[pick], {n: np.array(rec[n])[pick] for n in names}))
        matched += n_inside
        report((start + len(xyz)) / max(info.count, 1), "reading")
        while sum(len(part[0]) for part in kept) > budget:
            stride *= 2
            kept = [_thin(part, stride) for part in kept]
    return _joined(kept, names, matched, stride)


def _picks(xyz, lo, hi, matched, stride):
    """Ranks (among all matches so far) and chunk rows of this chunk's every stride-th
    match, and the number of matches in the chunk."""
    inside = np.arange(len(xyz)) if lo is None else np.flatnonzero(((xyz >= lo) & (xyz <= hi)).all(axis=1))
    rank = matched + np.arange(len(inside))
    take = rank % stride == 0
    return rank[take], inside[take], len(inside)


def _choose(path, info, budget, lo, hi, stride, chunk, report):
    """First pass, coordinates only: the rows of the sample (ranks, rows, matches, stride)."""
    ranks, rows, matched = [], [], 0
    for start, rec in iter_records(path, chunk=chunk, info=info, coordinates_only=True):
        xyz = xyz_of(rec)
        rank, pick, n_inside = _picks(xyz, lo, hi, matched, stride)
        ranks.append(rank)
        rows.append(start + pick)
        matched += n_inside
        report((start + len(xyz)) / max(info.count, 1), "choosing")
        while sum(len(r) for r in ranks) > budget:
            stride *= 2
            keep = [r % stride == 0 for r in ranks]
            ranks, rows = [r[k] for r, k in zip(ranks, keep)], [w[k] for w, k in zip(rows, keep)]
    rank = np.concatenate(ranks) if ranks else np.zeros(0, np.int64)
    return rank, (np.concatenate(rows) if rows else np.zeros(0, np.int64)).astype(np.int64), matched, stride


def _fetch(path, info, rows, names, report):
    """Second pass: the points and fields of ``rows`` (sorted), decompressing only the
    BLOCKs that hold some."""
    import laspy

    parts, blocks = [], np.unique(rows // BLOCK)
    at = where = 0  # the block read, and the reader's position
    try:
        with rust_panics_refused(path), open_reader(path) as reader:
            for i, b in enumerate(blocks):
                at = int(b) * BLOCK
                if where != at:
                    reader.seek(at)
                rec = reader.read_points(min(BLOCK, info.count - at))
                where = at + len(rec)
                lo, hi = np.searchsorted(rows, [at, at + len(rec)])
                pick = rows[lo:hi] - at
                parts.append((xyz_of(rec)[pick], {n: np.array(rec[n])[pick] for n in names}))
                report((i + 1) / len(blocks), "reading")
    except (laspy.errors.LaspyException, ValueError, EOFError, OSError, RuntimeError, IndexError) as exc:
        raise CloudFileError(path, f"unreadable near point {at} of {info.count} (truncated or corrupt "
                                   f"LAS/LAZ): {exc}") from None
    if not parts:
        return np.zeros((0, 3)), {n: np.zeros(0) for n in names}
    return np.concatenate([p for p, _ in parts]), {n: np.concatenate([f[n] for _, f in parts]) for n in names}


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
