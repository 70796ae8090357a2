"""NF: linear fitting of the neighbours' normal components (Cheng & Zhang 2009, §4.3–4.4)."""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..kernels.algebra import MAX_TERMS
from ..tuning import DEGREE_PIVOT, IRLS_ITERATIONS, RCOND, THETA_REACH, THIN_SPREAD
from ._options import choose
from ._result import MethodFit

NF_DOC = (
    "Normal fitting (§4.3–4.4): in a frame at p, fit X ≈ μ1 + w11·u + w12·v and "
    "Y ≈ μ2 + w21·u + w22·v to the neighbours' normal components by least squares "
    "(eqs. 25–26; option degree 2 or 3 adds higher terms in u, v), enforce the symmetry "
    "constraint (eq. 22) by projecting w onto its plane, and read the Weingarten matrix "
    "from w (eq. 21). The refined normal is (μ1, μ2, Z0)."
)
NR_DOC = NF_DOC + " NR repeats the fit with the refined normals of all points (§4.4 end; 1 pass by default)."

#: weights: "uniform" (paper eqs. 25–26) or "theta" (eq. 14's kernel on the distance);
#: constraint: "project" (paper §4.4), "exact" (Lagrange multiplier in the metric of the
#: normal equations) or "none". Note that core.frame symmetrises the shape operator in an
#: orthonormal basis of the tangent plane in every case, so "none" differs from "project"
#: only by the tilt-dependent metric (measured: < 0.1 % on the torus and saddle).
#: robust: None (least squares), "huber" or "tukey" (IRLS on the normal residuals, scale
#: from the median absolute deviation; outlying neighbours and the far side of a crease
#: lose their weight).
#: degree: of the polynomial in (u, v) fitted to each normal component: 1 is the paper's
#: linear model (eq. 23); 2 and 3 let the normal field curve over the neighbourhood, so
#: W (the slopes at p) is not biased by it and wide, noise-averaging neighbourhoods stay
#: accurate (k="auto" uses 3).
DEFAULTS = {"weights": "uniform", "constraint": "project", "robust": None, "degree": 1}
DEGREES = (1, 2, 3)
_WEIGHTS = ("uniform", "theta")
_CONSTRAINTS = ("none", "project", "exact")  # kernel codes 0, 1, 2
_ROBUST = (None, "huber", "tukey")


def check(*, weights="uniform", constraint="project", robust=None, degree=1):
    """Refuse an option value the fit does not know (before any compiled kernel runs)."""
    choose("weights", weights, _WEIGHTS)
    choose("constraint", constraint, _CONSTRAINTS)
    choose("robust", robust, _ROBUST)
    choose("degree", degree, DEGREES)


def min_k(degree=1, **_):
    """Smallest neighbourhood that determines the fit: one more point than monomials."""
    choose("degree", degree, DEGREES)
    return (degree + 1) * (degree + 2) // 2 + 1


def fit(chunk, *, weights="uniform", constraint="project", robust=None, degree=1, reweightings=IRLS_ITERATIONS, rows=0,
        coefficients=False):
    """Fit (mu, W) per point of a :class:`core.patch.Chunk`; see :data:`NF_DOC`.

    ``reweightings`` (internal, not a user option): IRLS iterations when ``robust``; the
    refinement passes use fewer (:data:`core.tuning.IRLS_LATER`). ``rows`` (internal): 0, or
    the fewest neighbours a centre fits on, every (k // rows)-th (k="auto"'s refinement
    passes: :data:`core.tuning.ROWS_LATER`). ``coefficients`` (internal): also return the
    polynomials of X and Y (``diag["coef"]``), which only the anchors of k="auto" read
    (:mod:`core.anchors`; 160 MB a pass at 1M points).

    Returns a :class:`MethodFit` whose ``diag`` holds the least-squares variances of
    W11, (W12 + W21)/2, W22 ("var", units of 1/h^2), the RMS residual of the normal components ("rms") and
    their RMS deviation from their mean ("spread").
    """
    check(weights=weights, constraint=constraint, robust=robust, degree=degree)
    m = len(chunk.centres)
    mu = np.zeros((m, 2))
    W = np.zeros((m, 2, 2))
    var = np.full((m, 3), np.inf)
    rms = np.full(m, np.nan)
    spread = np.full(m, np.nan)
    fitted = np.zeros(m, dtype=np.int8)
    coef = np.zeros((m, 2, MAX_TERMS if coefficients else 0))
    settings = kernels.Settings(THETA_REACH, _WEIGHTS.index(weights), _CONSTRAINTS.index(constraint),
                                _ROBUST.index(robust), reweightings, degree, RCOND, DEGREE_PIVOT, THIN_SPREAD, rows)
    kernels.normal_fit(chunk.frames(), settings, kernels.Fits(mu, W, var, rms, spread, fitted, coef), chunk.kernel_rows())
    diag = {"var": var, "rms": rms, "spread": spread, "degree": fitted}
    return MethodFit(mu, W, fitted > 0, diag | {"coef": coef} if coefficients else diag)
