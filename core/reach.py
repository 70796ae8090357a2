"""Initial neighbourhoods that reach around a bend: where k="auto" must not widen (issue 15).

The initial normals of k="auto" are fitted on a neighbourhood that grows as the square root
of the noise the cloud measures (:func:`core.scale.initial_k`). That rule assumes the bias of
the wide fit grows slowly, as it does where the radius of curvature is many spacings. A tube,
a cable, a handle, a fillet only a few spacings in radius is another matter: on a cylinder
with 12.6 points around (radius 2 spacings, sqrt(area / n)) 40 neighbours (the initial k at
0.2 spacing of noise) reach 106 degrees around it, with 9.4 around 166 degrees, and the 2-jet
on them no longer describes the surface: the initial normals were 10 degrees off (median),
and the default's share of points with H off by more than half was 2-9x that of the paper's
k = 15. Noise-free, the bend passes for noise (9.4 points around: the 2-jets' residual on 15
neighbours reads as 0.03 of their radius, and the initial k became 33).

The test is the one :mod:`core.local_noise` keeps bias out of its pools with: the residual of
noise does not grow with the radius, that of a bias does. Where the 2-jet on the wide
neighbourhood leaves a residual more than :data:`GROWTH` times the noise the point's 15 nearest
measure (the RMS of their own 15-neighbour residuals, so that the bound is not one fit's
chance), and more than :data:`SHARE` of those 15 find the same (a bend is a region), the
point's initial neighbourhood steps down :data:`core.tuning.JET_KS` to the widest size whose
2-jet fits to within that bound, or to the 15 nearest (the normals a fold falls back to). The
same at the cloud's initial k and at a noisy region's own (:mod:`core.local_noise`). Cylinders
and thin tori, two seeds each, share of points with H off by more than half before -> after (k
= 15): 12.6 points around at 0.2 spacing of noise 0.10-0.14 -> 0.034-0.057 (0.015-0.030), 11
around 0.15-0.20 -> 0.11-0.13 (0.04-0.09), 9.4 around noise-free 0.44-0.49 -> 0.27-0.30
(0.19-0.24), at 0.2 spacing 0.35-0.43 -> 0.35-0.41 (0.18-0.26); at 0.2 spacing the initial
normals' median error 6.9-11.8 -> 4.0-8.6 degrees. A thin torus (tube radius 2 spacings) noisy on one half
only: its quiet half took the noisy half's reach, 0.045-0.101 -> 0.005-0.016. The thin shapes
of :mod:`core.shapes_thin` at 0.2 of their spacing (12k points, 2 seeds), mean |H| error: plate
0.72-0.76 -> 0.54-0.60, wedge 0.68-0.77 -> 0.56-0.60, shell 0.31 -> 0.19, bracket 0.64-0.66 ->
0.49-0.55, noise-free the same. No point of the 17 surfaces of the three races steps down at
0.1-1 spacing of noise; the range scan's, with its own noise, do (tuning race: its K at 0.5
spacing 1.01x -> 1.00x the best oracle).

What is left on such tubes: NR's noise floor still widens the fits of the robust
suspects (outlier score above :data:`core.tuning.JET_SCORE`) to the cloud's initial k
without the fold test, and the cubic normal field (:data:`core.tuning.AUTO_DEGREE`) on 20
neighbours that reach 90 degrees around a tube is worse than the paper's plane.
"""

from __future__ import annotations

import numpy as np

from .kernels.pool import MAX_POOL, pooled_nanmeans
from .local_noise import pool_share
from .normals import pca_jet_at
from .tuning import JET_KS

#: a 2-jet's residual on the wide neighbourhood may be this many times the noise its 15
#: nearest measure and still count as noise. The ratio, noise alone (the 6000-point hold-out
#: and tuning surfaces at 0.5 and 1 spacing of noise, on 40-89 neighbours): median 0.84-1.0,
#: 99th percentile 1.25-2.1, 99.9th 1.4-3.2; a cylinder of 12.6 points around at 0.2 / 0.5 /
#: 1 spacing of noise on its initial k (44 / 69 / 89): median 2.9 / 3.5 / 2.2; noise-free
#: cylinders of 9.4-19 points around on 28-40 neighbours: 3.6-9.9.
GROWTH = 2.0
#: ... and a point steps down only where more than this share of its 15 nearest exceeds it too
#: (a bend is a region; a stray fit in noise is not)
SHARE = 0.5


def pooled_height(height, rows) -> np.ndarray:
    """(N,) the RMS over each row of ``rows`` (N, m) of the 2-jets' residual ``height`` (NaN
    left out; NaN where none is finite)."""
    sq = np.ascontiguousarray(height * height, dtype=np.float64)
    rows = np.ascontiguousarray(rows[:, :MAX_POOL])
    mean, _ = np.empty(len(rows)), np.empty(len(rows))
    pooled_nanmeans(sq, sq, rows, mean, _)
    return np.sqrt(mean)


def overreaching(wide, noise, rows, centres=None) -> np.ndarray:
    """(M,) bool: where the wide 2-jet's residual ``wide`` (M,) of the ``centres`` (M,) (default:
    every point, M = N) exceeds :data:`GROWTH` x their ``noise`` (M,) (:func:`pooled_height`),
    and so it does at more than :data:`SHARE` of the centres in the point's ``rows`` (N, m)
    (points that are not centres do not count; NaN, a refused fit, counts as not exceeding)."""
    with np.errstate(invalid="ignore"):
        over = wide > GROWTH * noise
    if not over.any():
        return over
    c = np.arange(len(rows)) if centres is None else centres
    flags = np.full(len(rows), np.nan)
    flags[c] = over
    return over & (pool_share(flags, rows[c, :MAX_POOL]) > SHARE)


def narrowed(pts, normals, ok, centres, noise, sizes, rows):
    """The initial normals of ``centres`` (M,) re-fitted on the widest of ``sizes`` (descending)
    whose 2-jet's residual stays within :data:`GROWTH` x their ``noise`` (M,), each on
    ``rows(centres, k)`` -> (idx, dist) (PCA, then the 2-jet, as the initial normals). Returns
    ``(normals (M, 3), ok (M,), height (M,), left (M,) bool)``: ``left`` where no size fits
    (their rows of ``normals``, ``ok`` and ``height`` are unchanged from the inputs ``normals``,
    ``ok`` (M,) and NaN); the caller gives those the normals of its smallest neighbourhood."""
    m = len(centres)
    out, out_ok, height = normals.copy(), ok.copy(), np.full(m, np.nan)
    left = np.ones(m, dtype=bool)
    for k in sizes:
        at = np.flatnonzero(left)
        if not len(at):
            break
        idx, dist = rows(centres[at], int(k))
        n_c, ok_c, h_c = pca_jet_at(pts, centres[at], idx, dist)
        with np.errstate(invalid="ignore"):
            fits = ok_c & (h_c <= GROWTH * noise[at])
        take = at[fits]
        out[take], out_ok[take], height[take] = n_c[fits], ok_c[fits], h_c[fits]
        left[take] = False
    return out, out_ok, height, left


def sizes_below(k_init, k_min) -> np.ndarray:
    """The sizes of :data:`core.tuning.JET_KS` (as :data:`core.local_noise.LADDER`) above ``k_min`` and
    below ``k_init``, widest first."""
    ladder = np.asarray(JET_KS)
    return ladder[(ladder > k_min) & (ladder < k_init)][::-1]

