"""Darboux core: differential geometry of unorganized point clouds.

The augmented Darboux frame (p, n, e1, e2, k1, k2) of every point by the normal-fitting
method of Cheng & Zhang (2009) and the baselines it is compared with. numpy/scipy only.
"""

from . import io, metrics, noise, shapes
from ._progress import Cancelled
from .estimate import estimate
from .methods import METHODS, Method, get_method
from .neighbours import Neighbours, build_neighbours
from .planning import EstimatePlan, plan
from .result import SCALAR_FIELDS, CurvatureResult

__all__ = [
    "estimate", "plan", "EstimatePlan", "build_neighbours", "Neighbours", "CurvatureResult", "METHODS", "Method",
    "get_method", "Cancelled", "SCALAR_FIELDS", "shapes", "noise", "metrics", "io",
]
__version__ = "0.1.0"
