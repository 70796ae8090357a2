"""The spatial pre-pass: plan the tiles from a sample, then bin every point into its
tile's file on disk, so that each task reads only its own tile and its neighbours'."""

from __future__ import annotations

import numpy as np

from .plan import SAMPLE, TilePlan, make_plan
from .store import TileStore, bin_dtype


def plan_tiles(source, store: TileStore, tile_points: int, progress) -> TilePlan:
    """Load the saved plan, or sample every n-th point of ``source`` and make one."""
    if store.plan_path.exists():
        return TilePlan.load(store.plan_path)
    stride = max(1, source.count // SAMPLE)
    parts = []
    seen = 0
    for start, pts, *_ in source.chunks():
        first = (-start) % stride
        parts.append(pts[first::stride].copy())  # a view would keep each whole chunk alive (1.2 GB at 50M)
        _check_finite(source, start, pts)
        seen = start + len(pts)
        progress(seen / max(source.count, seen), "sampling")
    sample = np.concatenate(parts)
    plan = make_plan(sample, seen, tile_points)  # E57 invalid points are only known once read
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
    for start, pts, nrm, view in source.chunks():
        rec = np.empty(len(pts), dtype=dtype)
        rec["xyz"] = pts
        if source.has_normals:
            rec["n"] = nrm
        if source.has_views:
            rec["view"] = view
        rec["index"] = np.arange(start, start + len(pts))
        tile = plan.assign(pts)
        order = np.argsort(tile, kind="stable")
        cuts = np.searchsorted(tile[order], np.arange(plan.n_tiles + 1))
        for t in np.flatnonzero(np.diff(cuts)):  # appended chunk by chunk: any number of tiles
            with open(store.bin_path(t), "ab") as f:
                rec[order[cuts[t]:cuts[t + 1]]].tofile(f)
        counts += np.diff(cuts)
        progress((start + len(pts)) / plan.n_points, "binning")
    if counts.sum() != plan.n_points:
        raise ValueError(f"{source.name}: {counts.sum()} points were binned but {plan.n_points} were sampled; "
                         "the file changed during the run")
    store.mark_binned(counts)
    return counts.tolist()


def _check_finite(source, start, pts) -> None:
    bad = ~np.isfinite(pts).all(axis=1)
    if bad.any():
        row = start + int(np.flatnonzero(bad)[0])
        raise ValueError(f"{source.name}: point {row} has a non-finite coordinate {pts[row - start].tolist()}; "
                         "tiled estimation needs finite coordinates")
