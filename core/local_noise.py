"""Noise that differs across a cloud: the initial scale of k="auto" per region (issue 15).

k="auto" grows its initial neighbourhoods with the noise (:func:`core.scale.initial_k`), and
the fold test of the initial normals compares each point with the cloud's typical agreement
(:func:`core.initial_normals.unfolded`). Both were one number per cloud, a median. Where the
noise differs across a cloud (a scan's near and far ranges, merged scans of two scanners,
materials that return differently) the median is that of neither part: on a torus noise-free
on one half and at 1 spacing of noise on the other, the noisy half got 51 neighbours instead
of 89 and its fold test measured against the clean half's agreement; its K error was 5x, its
H error 2.7x those of the same noise everywhere (0.130 against 0.024, 0.045 against 0.017).

Here each point's noise is pooled over its :data:`POOL` nearest: the lower quartile of their
noise ratios (:func:`core.initial_normals.noise_samples`), then the median of those over the
same nearest, times :data:`CALIBRATION` (the median of a cloud's ratios over the median of these
pooled values: 1.10-1.23 on tori, saddles, cubes and chirps at 0.1-1 spacing of noise): the
noise ratio the point's region would measure alone. A point whose initial k at that noise is
more than :data:`FACTOR` times the cloud's takes it, snapped onto :data:`LADDER` so that the
points of a level share their rows' width and the fold test's typical agreement (the median
over them); the others keep the cloud's. Only upward: a region quieter than the cloud keeps
the cloud's wider initial scale. Moving it down too gained 1-12 % of H on a single-view range
scan (whose far, sparse part has the lower noise ratio) but lost 30-60 % at the quiet end of a
torus whose noise grows from 0 to 1 spacing across it, where any smaller initial k was worse
(levels floored at 15, 20, 28, 40: H 0.00235, 0.00230, 0.00210, 0.00189; the cloud's 60: 0.00168).

Three guards keep a bias from passing for a noisy region:

- a point whose own ratio would ask for more (:func:`suspects`) and whose 2-jet residual grows
  with the radius (:func:`biased`) is left out of the pools: the rims of thin parts and a cube's
  edges, noise-free, read like 0.2-0.5 spacing of noise on 15 neighbours, and pooled as such
  took 40-56 neighbours at 9 % of a thin plate's points (mean |H| error 0.19 -> 0.26);
- a point moves only where most of its pool moves too (a region, not a scattered point);
- a level holds at least :data:`MIN_SHARE` of the cloud.

A cloud of one noise is estimated as before: on tori, saddles, cylinders, ellipsoids, spheres,
planes, chirps and cubes at 0-1 spacing of noise, and on the thin shapes of
:mod:`core.shapes_thin` at 0-0.3, no point moves.
"""

from __future__ import annotations

import numpy as np

from .kernels.pool import pooled_above, pooled_nanmeans
from .scale import initial_k
from .tuning import INITIAL_K0, JET_KS

#: neighbours a point's noise is pooled over (the initial graph's width with k="auto")
POOL = 40
#: the quantile of the noise ratios over a pool (the lower quartile: see the module)
QUANTILE = 0.25
#: the median ratio of a cloud of one noise over the median of its pooled values
CALIBRATION = 1.2
#: a suspect point's 2-jet residual may grow this much from the initial neighbours to
#: :data:`POOL` and still count as noise (noise: 0.7-1.7, median 0.9-1.2, on tori at 0.05-1
#: spacing; the rims of thin plates, wedges, brackets and shells and a cube's edges, noise-free
#: or at 0.1 spacing: median 1.6-3.7)
GROWTH = 1.5
#: a point takes its region's initial k where it is more than this factor times the cloud's
FACTOR = 1.5
#: the least share of the cloud's points a level other than the cloud's must hold
MIN_SHARE = 0.01
#: the pooling is skipped where fewer than MIN_SHARE / SCARCE of the points lie above its bound (:func:`_scarce`)
SCARCE = 8
#: the initial k a region may take (a factor ~sqrt(2) apart): the jets' sizes
LADDER = np.asarray(JET_KS)


def moving_bound(k_cloud) -> float:
    """The noise ratio at which :func:`core.scale.initial_k` asks for :data:`FACTOR` x ``k_cloud``."""
    return (FACTOR * k_cloud / INITIAL_K0) ** 2


def suspects(ratio, k_cloud) -> np.ndarray:
    """(N,) bool: the points whose own noise ratio alone would ask for more than
    :data:`FACTOR` x ``k_cloud`` initial neighbours: where a bias could pass for noise."""
    with np.errstate(invalid="ignore"):
        return CALIBRATION * ratio > moving_bound(k_cloud)


def biased(height, wide_height) -> np.ndarray:
    """(M,) bool: where a 2-jet's residual ``wide_height`` on :data:`POOL` neighbours exceeds
    :data:`GROWTH` x its ``height`` on the initial ones, or is not finite: the residual of
    a bias (a rim, an edge, a bend) grows with the radius, that of noise does not."""
    with np.errstate(invalid="ignore"):
        return ~(wide_height <= GROWTH * height)


def pooled_noise(ratio, clean, pool, bound) -> np.ndarray:
    """(N,) the noise ratio of each point's region where it exceeds ``bound``: the
    :data:`QUANTILE` of the ``clean`` points' ``ratio`` over each row of ``pool`` (N, m),
    then the median of those over the same rows, each kept only above the bound (a value
    below it, or a row without a clean ratio, counts as 0:
    :func:`core.kernels.pool.pooled_above` selects only the rows that can lie above); NaN
    where it does not exceed it. In the units of the cloud's ratio (:data:`CALIBRATION`)."""
    pool = np.ascontiguousarray(pool)
    values = np.where(clean, ratio, np.nan) * CALIBRATION
    first, second = np.empty(len(pool)), np.empty(len(pool))
    pooled_above(values, pool, QUANTILE, bound, first)
    pooled_above(first, pool, 0.5, bound, second)
    return np.where(second > bound, second, np.nan)


def local_k(ratio, clean, pool, k_cloud, k_min, k_max, n_points) -> np.ndarray | None:
    """(N,) int: the initial k of each point, ``k_cloud`` except where its region's noise
    (:func:`pooled_noise`) asks for more than :data:`FACTOR` times more (then a
    :data:`LADDER` size up to ``k_max``); None where every point keeps ``k_cloud``."""
    low, high = initial_k(0.0, k_min, k_max, n_points), initial_k(1e12, k_min, k_max, n_points)
    bound = moving_bound(k_cloud)
    if high <= FACTOR * k_cloud or _scarce(suspects(np.where(clean, ratio, np.nan), k_cloud)):
        return None
    noise = pooled_noise(ratio, clean, pool, bound)
    above = np.isfinite(noise)
    own = np.where(above, initial_k(np.where(above, noise, 0.0), k_min, k_max, n_points), k_cloud)
    moved = own > FACTOR * k_cloud
    if moved.any():  # a region, not a scattered point or a thin band of bias: most of the pool moves too
        moved &= pool_share(moved.astype(np.float64), pool) > 0.5
    if not moved.any():
        return None
    steps = LADDER[(LADDER >= low) & (LADDER <= high)]
    steps = np.unique(np.concatenate([steps, [low, high]]))
    out = np.full(len(own), k_cloud, dtype=np.int64)
    out[moved] = steps[np.argmin(np.abs(np.log(own[moved, None] / steps[None, :])), axis=1)]
    levels, counts = np.unique(out, return_counts=True)
    small = levels[(counts < MIN_SHARE * len(out)) & (levels != k_cloud)]
    out[np.isin(out, small)] = k_cloud  # too few points for a region of their own
    return None if (out == k_cloud).all() else out


def pool_share(flags, pool) -> np.ndarray:
    """(M,) the mean of ``flags`` (N,) (1.0 or 0.0; NaN left out) over each row of ``pool``
    (M, m): the share of a point's pool that does what it does (a region, not a stray point)."""
    share, _ = np.empty(len(pool)), np.empty(len(pool))
    pooled_nanmeans(flags, flags, np.ascontiguousarray(pool), share, _)
    return share


def _scarce(above) -> bool:
    """Whether too few points are ``above`` (N,) bool the bound (:func:`suspects` among the
    clean) for any region to move: a point moves only where more than half of its pool has
    three quarters of its own pool above, so a level of :data:`MIN_SHARE` of the points needs
    about MIN_SHARE / 2.5 of them above, more where the pools overlap unevenly; fewer than
    MIN_SHARE / :data:`SCARCE` skip the pooling (on a noise-free torus of 100k points it
    cost 5.8 % of the default's time)."""
    return np.count_nonzero(above) < MIN_SHARE * len(above) / SCARCE
