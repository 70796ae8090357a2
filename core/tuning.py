"""Every tuned constant of the library, with why the value and what was measured.

Numbers that are conventions or definitions (the paper's k = 15, eq. 14's kernel,
the 1.345 / 4.685 efficiency constants of Huber and Tukey) are tuning too where a user
could reasonably want another value; structural sizes (how many monomials a cubic has)
live with the code that needs them. The compiled kernels take these values as
arguments, so a change here is seen without clearing numba's cache.
"""

from __future__ import annotations

# ----------------------------------------------------------------------------- linear algebra

#: singularity threshold of an equilibrated (unit-diagonal) normal matrix: its smallest
#: eigenvalue relative to the largest (numpy fits), its determinant (the 3x3 closed form)
#: or its Cholesky pivots (compiled fits). 1e-10 rejects collinear or duplicated
#: neighbourhoods while keeping thin but honest ones (measured: no valid point of the
#: torus, saddle or cube is lost at k = 15).
RCOND = 1e-10

# ----------------------------------------------------------------------------- initial normals

#: k of the initial PCA normals when k is chosen automatically: the paper's k
PCA_K = 15
#: h of eq. 14 in units of the k-th neighbour distance, so no neighbour gets weight 0
THETA_REACH = 1.1
#: a neighbourhood is treated as collinear (no normal) when its middle eigenvalue is
#: this small relative to the largest
COLLINEAR = 1e-10
#: neighbours per point in the orientation graph (Hoppe et al. use a small k too)
ORIENT_K = 8
#: initial normals for k="auto" come from INITIAL_K0 x sqrt(noise) neighbours (at least
#: PCA_K), noise being the cloud's median of (RMS distance of the neighbours from their
#: osculating 2-jet) / (radius of the 15 neighbours). The jet normal's variance falls as
#: noise^2 / k^2 and its bias (third-order terms) grows as k, so the best k grows as
#: sqrt(noise). 182 puts 28 neighbours at noise 0.1 of the mean spacing and 40 at 0.2
#: (the radius of 15 neighbours is ~4.2 spacings): measured best on the torus, saddle and
#: ellipsoid at 0.05-1 spacing of noise.
INITIAL_K0 = 182.0

# ----------------------------------------------------------------------------- automatic k (core.scale)

#: candidate neighbourhood sizes (about x1.4 apart)
AUTO_KS = (20, 28, 40, 56, 80, 113, 160, 226)
#: the candidates stop where N x k would exceed this many cached neighbours (~0.8 GB)
NEIGHBOUR_BUDGET = 64_000_000
#: degree of the normal fit used by k="auto" (a cubic normal field: bias O(h^3))
AUTO_DEGREE = 3
#: width of the confidence intervals in standard deviations. The least-squares variance
#: treats the neighbours' normals as independent, but neighbouring estimated normals
#: share most of their own neighbours, so their errors are correlated and the variance
#: is underestimated; 4 (not the textbook 2) compensates. Measured on the torus, saddle,
#: ellipsoid and a thin torus (r = 0.3) at noise 0-0.2 of the spacing.
GAMMA = 4.0
#: fold test (k stops growing where a ring of neighbours leaves the graph of a function
#: over the local plane; see core.kernels.scale). Share of a ring that may lie off the
#: graph before k stops growing
FOLD_FRACTION = 0.2
#: a neighbour whose normal turns more than 70 degrees from the local mean normal is off the graph
FOLD_COS = 0.34
#: heights within this many RMS heights of the smallest neighbourhood are noise, not a
#: fold. With noise of a whole spacing, a test on the centre's own noisy normal (no
#: margin) stopped a quarter of the points at k = 20.
FOLD_NOISE = 3.0
#: fewest off-graph neighbours that make a fold (a few turned normals in a small ring are noise)
FOLD_MIN_BAD = 3

# ----------------------------------------------------------------------------- the fit and its passes

#: reweighting iterations of the robust fits (each one re-solves the least squares)
IRLS_ITERATIONS = 2
#: most NR refinement passes a user may ask for
MAX_PASSES = 20
#: most NR refinement passes when k is chosen automatically (paper: 1). With the cubic
#: normal fit the refined normals are nearly unbiased, so a pass averages noise further,
#: and the change it makes to the normals decays geometrically. Once a pass changes them
#: by more than PASS_DECAY x the previous one, it is smoothing the shape itself (the
#: drift that remains noise-free) and is undone.
AUTO_PASSES = 4
PASS_DECAY = 0.7
#: |mu|^2 at or above this leaves no upward normal: the fit is rejected (core.frame)
MAX_TILT2 = 1.0 - 1e-6

# ----------------------------------------------------------------------------- per-point flags

#: a point whose distance to its neighbours' plane exceeds this many spreads is an outlier
OUTLIER_SCORE = 4.0
#: the unit of the outlier score adds this share of the neighbours' mean distance to
#: their centroid, so that a clean flat patch does not make every tiny offset look infinite
OUTLIER_FLOOR = 0.05
#: crease: normals spread (RMS, unit normals) above this and a linear fit leaving more
#: than CREASE_RATIO of that spread unexplained
CREASE_SPREAD = 0.15
CREASE_RATIO = 0.25
#: ... and a residual above this many times the cloud's median residual (the noise)
CREASE_NOISE = 3.0
