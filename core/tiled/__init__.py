"""Estimate clouds of any size: spatial tiles with halos, on Dask, resumable.

:func:`estimate_tiled` gives every point the answer of :func:`core.estimate` on the whole
cloud while holding only a tile and its halo in memory: a pre-pass bins the points into
tiles sized by point count (:mod:`.plan`, :mod:`.binning`), each Dask task reads its own
tile and a halo proven wide enough for every neighbourhood its answers depend on
(:mod:`.halo`, :mod:`.task`), tiles agree on normal signs through their overlaps
(:mod:`.signs`), and the result is assembled atomically in input order (:mod:`.assemble`).
With k="auto" (the default) the whole cloud's medians are fixed first (:mod:`.wholecloud`)
and the refinement pass kept is chosen for the whole cloud (:mod:`.auto`).
"""

from .run import DEFAULT_MEMORY, TiledRun, bytes_per_point, default_tile_points, estimate_tiled, parse_memory

__all__ = ["estimate_tiled", "TiledRun", "bytes_per_point", "default_tile_points", "parse_memory", "DEFAULT_MEMORY"]
