"""What every kernel shares: the numba options, the block size, eq. 14's kernel."""

from __future__ import annotations

from numba import njit


OPTS = dict(cache=True, nogil=True)
#: points per parallel work item (scratch arrays are allocated once per block)
BLOCK = 256


@njit(**OPTS, inline="always")
def theta(x):
    """Eq. 14: (1 - x^2)^4 for x < 1, else 0."""
    if x >= 1.0:
        return 0.0
    t = 1.0 - x * x
    return t * t * t * t
