"""Osculating jets (Cazals & Pouget 2003/2005): a full polynomial height field fitted to points."""

from __future__ import annotations

import numpy as np

from ..frame import height_field_derivatives
from ..linalg import weighted_lstsq
from ._options import choose
from ._result import MethodFit

DOC = (
    "Osculating jet: fit the full bivariate polynomial z = sum c_ij u^i v^j (i + j <= degree, "
    "constant and linear terms included) to the neighbours in the PCA frame, then take the "
    "normal and Weingarten map of the graph at the origin (Cazals & Pouget 2005). degree 2 or 3."
)
DEFAULTS = {"degree": 2}
DEGREES = (2, 3)


def check(*, degree=2):
    """Refuse a degree the jet does not fit (before any fit runs)."""
    choose("degree", degree, DEGREES, "2 or 3")


def fit(chunk, *, degree=2):
    patch = chunk.patch
    check(degree=degree)
    u, v = patch.u, patch.v
    cols = [np.ones_like(u), u, v, u * u, u * v, v * v]
    if degree == 3:
        cols += [u**3, u * u * v, u * v * v, v**3]
    x, ok = weighted_lstsq(np.stack(cols, axis=2), patch.w)
    mu, W = height_field_derivatives(x[:, 1], x[:, 2], 2 * x[:, 3], x[:, 4], 2 * x[:, 5])
    return MethodFit(mu, W, ok)
