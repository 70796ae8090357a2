"""NF: linear fitting of the neighbours' normal components (Cheng & Zhang 2009, §4.3–4.4)."""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..normals import THETA_REACH

#: smallest determinant of the equilibrated 3x3 normal matrix (unit diagonal) accepted
RCOND_DET = 1e-10

NF_DOC = (
    "Normal fitting (§4.3–4.4): in a frame at p, fit X ≈ μ1 + w11·u + w12·v and "
    "Y ≈ μ2 + w21·u + w22·v to the neighbours' normal components by least squares "
    "(eqs. 25–26), enforce the symmetry constraint (eq. 22) by projecting w onto its plane, "
    "and read the Weingarten matrix from w (eq. 21). The refined normal is (μ1, μ2, Z0)."
)
NR_DOC = NF_DOC + " NR repeats the fit with the refined normals of all points (§4.4 end; 1 pass by default)."

#: weights: "uniform" (paper eqs. 25–26) or "theta" (eq. 14's kernel on the distance);
#: constraint: "project" (paper §4.4), "exact" (Lagrange multiplier in the metric of the
#: normal equations) or "none".
DEFAULTS = {"weights": "uniform", "constraint": "project"}
_WEIGHTS = ("uniform", "theta")
_CONSTRAINTS = ("project", "exact", "none")


def fit(chunk, *, weights="uniform", constraint="project"):
    """Fit (mu, W) per point of a :class:`core.patch.Chunk`; see :data:`NF_DOC`."""
    if weights not in _WEIGHTS:
        raise ValueError(f"weights {weights!r} is invalid; must be one of {list(_WEIGHTS)}")
    if constraint not in _CONSTRAINTS:
        raise ValueError(f"constraint {constraint!r} is invalid; must be one of {list(_CONSTRAINTS)}")
    m = len(chunk.centres)
    mu = np.empty((m, 2))
    W = np.empty((m, 2, 2))
    ok = np.empty(m, dtype=bool)
    kernels.normal_fit(
        chunk.points, chunk.normals, chunk.idx, chunk.h, chunk.centres, chunk.t1, chunk.t2, chunk.z,
        THETA_REACH, _WEIGHTS.index(weights), {"none": 0, "project": 1, "exact": 2}[constraint],
        RCOND_DET, mu, W, ok,
    )
    return mu, W, ok
