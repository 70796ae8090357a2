"""Which pages numpy's large arrays get, chosen at ``import core``: 4 KiB pages, not
transparent huge pages.

numpy madvises every allocation of 4 MiB or more as MADV_HUGEPAGE (on Linux, where THP is
in ``madvise`` mode, the common default). An estimate's large arrays live for one stage and
are freed; on a virtual machine that returns freed memory to its host (free page
reporting, virtio-balloon; Firecracker, many cloud guests) a huge page carved from such
memory faults on the host again, at 2-4 ms a 2 MiB page: a fresh 80 MB array cost 0.19-0.42
CPU s to fill seconds after the last free, 0.03-0.05 s with 4 KiB pages (see
:data:`core.tuning.NUMPY_HUGEPAGES` for an estimate's figures). The environment's
``NUMPY_MADVISE_HUGEPAGE`` wins (numpy reads it itself). Only where memory comes from
changes, never a number.
"""

from __future__ import annotations

import os

import numpy as np

from .tuning import NUMPY_HUGEPAGES


def configure() -> bool | None:
    """Set numpy's huge-page advice to :data:`core.tuning.NUMPY_HUGEPAGES` unless the
    environment chose (``NUMPY_MADVISE_HUGEPAGE``); returns the advice in force, None
    where this numpy has no such switch."""
    multiarray = getattr(getattr(np, "_core", None), "multiarray", None) or getattr(np.core, "multiarray", None)
    switch = getattr(multiarray, "_set_madvise_hugepage", None)
    if switch is None:
        return None
    if "NUMPY_MADVISE_HUGEPAGE" in os.environ:
        return bool(multiarray._get_madvise_hugepage()) if hasattr(multiarray, "_get_madvise_hugepage") else None
    switch(NUMPY_HUGEPAGES)
    return NUMPY_HUGEPAGES
