"""What :func:`core.estimate` decides on the whole cloud before any fit, decided for a tiled
run on the sample its tiles are planned from (:func:`core.tiled.binning.plan_tiles`: every
point of a cloud of up to :data:`core.tiled.plan.SAMPLE`, so there exactly as in memory):

- a cloud no estimate can be made on (:func:`core.degenerate.reason`: too few points, all
  at one place, on a line, coordinates out of float64's range, a float32 grid as coarse as
  the spacing) is refused with the reason, before the points are binned. In memory such a
  cloud gets an all-invalid result; tiles have no whole-cloud view to make one from, and
  without this each tile made its own answer (a valid 3.8e-12 curvature on a 3-point
  cloud, a float32-gridded scan estimated on its rounding, a bare numpy error);
- a cloud of copies is estimated on its distinct positions (:mod:`core.duplicates`):
  where they are fewer than the neighbours a plan searches, k="auto" plans for their count
  and an integer k larger than it is refused, as :func:`core.estimate` does.
"""

from __future__ import annotations

import numpy as np

from .. import degenerate
from ..duplicates import find_duplicates


def refuse_degenerate(sample: np.ndarray, min_k: int, name: str) -> None:
    """ValueError with :func:`core.degenerate.reason` when the cloud sampled as ``sample``
    (m, 3) cannot be estimated. A sample's extent and spacing are those of the cloud at most,
    so the reasons it gives hold for the cloud; a cloud of fewer than ``min_k`` points is
    sampled whole, so its count is the sample's."""
    why = degenerate.reason(np.ascontiguousarray(sample, dtype=np.float64), min_k)
    if why is not None:
        raise ValueError(f"{name}: no point can be estimated: {why}")


def distinct_count(sample: np.ndarray, count: int) -> int:
    """The number of distinct positions when ``sample`` is the whole cloud (``count``
    points), else ``count`` (a larger cloud has more places than any plan searches)."""
    if len(sample) < count:
        return count
    merged = find_duplicates(np.ascontiguousarray(sample, dtype=np.float64))
    return count if merged is None else len(merged.first)


def planned_count(k, count: int, distinct: int, k_search) -> int:
    """The count of points the tiles are planned for: ``distinct`` where the copies leave
    fewer places than ``k_search(count)`` neighbours (k="auto"), else ``count``; an integer
    ``k`` above ``distinct`` is refused with :func:`core.estimate`'s message."""
    if distinct >= count:
        return count
    if not isinstance(k, str) and k > distinct:
        raise ValueError(f"k={k} exceeds the {distinct} distinct positions of the cloud ({count - distinct} of its "
                         f"{count} points are copies of others)")
    return distinct if isinstance(k, str) and k_search(count) > distinct else count
