"""The spatial pre-pass: plan the tiles from a sample, then bin every point into its
tile's file on disk, so that each task reads only its own tile and its neighbours'.

A file is decompressed once: the sampling pass also spills the records, in input order,
to ``bins/spill.bin`` (raw, 32 bytes a point), and the binning pass reads them back as a
memory map (a LAZ chunk of 1M points costs ~0.5 CPU s to decompress, its spill ~0.02 s to
write and read). A run resumed without the spill (it was interrupted while spilling) reads
the source again.
"""

from __future__ import annotations

import contextlib

import numpy as np

from ..io.las_stream import CHUNK
from . import wholechecks
from .plan import SAMPLE, TilePlan, make_plan
from .store import TileStore, bin_dtype


def plan_tiles(source, store: TileStore, tile_points, progress, min_k: int = 1) -> TilePlan:
    """Load the saved plan, or sample every n-th point of ``source`` and make one (spilling
    the records of a file for :func:`bin_points`); ``tile_points``: an int, or a function of
    (sample, point count) giving it. A cloud no estimate can be made on
    (fewer than ``min_k`` points, all at one place, ...) is refused first
    (:mod:`core.tiled.wholechecks`)."""
    if store.plan_path.exists():
        return TilePlan.load(store.plan_path)
    stride = max(1, source.count // SAMPLE)
    parts = []
    seen = 0
    dtype = bin_dtype(source.has_normals, source.has_views)
    spill = store.spill_path.with_suffix(".tmp") if source.is_file else None
    with open(spill, "wb") if spill else contextlib.nullcontext() as f:
        for start, pts, nrm, view in source.chunks():
            first = (-start) % stride
            parts.append(pts[first::stride].copy())  # a view would keep each whole chunk alive (1.2 GB at 50M)
            _check_finite(source, start, pts)
            if f is not None:
                _append(_records(dtype, start, pts, nrm, view), f, spill)
            seen = start + len(pts)
            progress(seen / max(source.count, seen), "sampling")
    if spill:
        spill.replace(store.spill_path)
    sample = np.concatenate(parts)
    wholechecks.refuse_degenerate(sample, min_k, source.name)
    if callable(tile_points):  # sized on the sample (core.tiled.sizing)
        tile_points = tile_points(sample, seen)
    plan = make_plan(sample, seen, tile_points, wholechecks.distinct_count(sample, seen))  # E57: seen, once read
    tmp = store.plan_path.with_name("plan.tmp.npz")
    plan.save(tmp)
    tmp.replace(store.plan_path)
    return plan


def bin_points(source, store: TileStore, plan: TilePlan, progress) -> list:
    """Write each tile's own points (in input order) to its bin file; returns the counts.

    Redone from scratch unless a previous run completed it (``bins/done.json``).
    """
    if store.binned():
        return store.bin_counts()
    counts = np.zeros(plan.n_tiles, dtype=np.int64)
    dtype = bin_dtype(source.has_normals, source.has_views)
    store.set_bin_dtype(dtype)
    for t in range(plan.n_tiles):  # start empty (a previous, interrupted binning may have left some)
        store.bin_path(t).write_bytes(b"")
    for rec in _binned_chunks(source, store, dtype, plan.n_points):
        if len(rec) == 0:
            continue
        pts = rec["xyz"]
        start = int(rec["index"][0])
        tile = plan.assign(pts)
        order = np.argsort(tile, kind="stable")
        cuts = np.searchsorted(tile[order], np.arange(plan.n_tiles + 1))
        for t in np.flatnonzero(np.diff(cuts)):  # appended chunk by chunk: any number of tiles
            with open(store.bin_path(t), "ab") as f:
                _append(rec[order[cuts[t]:cuts[t + 1]]], f, store.bin_path(t))
        counts += np.diff(cuts)
        progress((start + len(pts)) / plan.n_points, "binning")
    if counts.sum() != plan.n_points:
        raise ValueError(f"{source.name}: {counts.sum()} points were binned but {plan.n_points} were sampled; "
                         "the file changed during the run")
    store.mark_binned(counts)
    store.spill_path.unlink(missing_ok=True)
    return counts.tolist()


def _append(records: np.ndarray, f, path) -> None:
    """``records`` written at the end of the open file ``f`` (``path``); a short write (numpy
    says only "N requested and M written") is an OSError that names the file and the likely
    cause."""
    try:
        records.tofile(f)
    except OSError as e:
        short = OSError(f"{path}: cannot be written ({e.strerror or e}); the disk of the work directory may be "
                        "full: give --work-dir on a disk with room")
        short.errno = e.errno
        raise short from e


def _records(dtype, start, pts, nrm, view) -> np.ndarray:
    """Bin records of one chunk: coordinates, normals and viewpoints if any, input rows."""
    rec = np.empty(len(pts), dtype=dtype)
    rec["xyz"] = pts
    if "n" in dtype.names:
        rec["n"] = nrm
    if "view" in dtype.names:
        rec["view"] = view
    rec["index"] = np.arange(start, start + len(pts))
    return rec


def _binned_chunks(source, store, dtype, n_points):
    """The records to bin, chunk by chunk: from the sampling pass's spill (complete: one
    record for each of the plan's points), or the source."""
    path = store.spill_path
    if path.exists() and path.stat().st_size == n_points * dtype.itemsize:
        spilled = np.memmap(path, dtype=dtype, mode="r")
        for start in range(0, len(spilled), CHUNK):
            yield np.array(spilled[start:start + CHUNK])
        del spilled
        return
    for start, pts, nrm, view in source.chunks():
        yield _records(dtype, start, pts, nrm, view)




def _check_finite(source, start, pts) -> None:
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        row = start + int(np.flatnonzero(bad)[0])
        raise ValueError(f"{source.name}: point {row} has a non-finite coordinate {pts[row - start].tolist()}; "
                         "tiled estimation needs finite coordinates")
