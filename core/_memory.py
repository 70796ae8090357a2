"""The memory this machine has free now, for the checks that refuse what would not fit (a
file's declared sizes, :mod:`core.io.vtk`) and the budget of a run in memory (:mod:`core.tiled.cli`)."""

from __future__ import annotations

import os


def available_memory() -> int:
    """Bytes of memory available: psutil's figure (it counts reclaimable caches; it comes with
    dask.distributed, the ``[big]`` extra), else the free physical pages."""
    try:
        import psutil

        return int(psutil.virtual_memory().available)
    except ImportError:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
