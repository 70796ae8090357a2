"""What every kernel shares: the numba options, the block size, eq. 14's kernel."""

from __future__ import annotations

from numba import njit


#: error_model="numpy": a float division by zero gives inf/NaN (caught by the finite checks
#: that mark a point invalid) instead of raising ZeroDivisionError from inside a kernel
#: (hypothesis found one on a cloud of extent 4e-66)
OPTS = dict(cache=True, nogil=True, error_model="numpy")
#: OPTS without numba's reference counting (``_nrt=False``), for loops and helpers that allocate
#: nothing and copy no array into another: each call of a helper otherwise increments and
#: decrements the count of every array it receives, an atomic instruction each (the jets' ICI
#: spent ~13 % of its time there, docs/performance-log.md); the arithmetic is the same
LEAF = dict(OPTS, _nrt=False)
#: points per parallel work item (scratch arrays are allocated once per block)
BLOCK = 256


@njit(**OPTS, inline="always")
def theta(x):
    """Eq. 14: (1 - x^2)^4 for x < 1, else 0."""
    if x >= 1.0:
        return 0.0
    t = 1.0 - x * x
    return t * t * t * t
