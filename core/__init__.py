"""Darboux core: differential geometry of unorganized point clouds.

The augmented Darboux frame (p, n, e1, e2, k1, k2) of every point by the normal-fitting
method of Cheng & Zhang (2009) and the baselines it is compared with. numpy/scipy only.
"""

from . import io, metrics, noise, shapes
from ._progress import Cancelled
from .curvature_lines import curvature_lines
from .estimate import estimate
from .gauss_bonnet import GaussBonnet, gauss_bonnet, point_areas, total_curvature
from .local_fit import LocalFit, local_fit
from .methods import METHODS, Method, get_method
from .neighbours import Neighbours, build_neighbours
from .point_types import (ELLIPTIC, HYPERBOLIC, PARABOLIC, PLANAR, TYPE_NAMES, UMBILIC,
                          curvature_scale, point_types)
from .result import FIELDS, CurvatureResult

__all__ = [
    "estimate", "build_neighbours", "Neighbours", "CurvatureResult", "METHODS", "Method",
    "get_method", "Cancelled", "FIELDS", "shapes", "noise", "metrics", "io",
    # teaching: the mathematics around one estimate
    "total_curvature", "gauss_bonnet", "GaussBonnet", "point_areas", "curvature_lines",
    "point_types", "curvature_scale", "TYPE_NAMES", "ELLIPTIC", "HYPERBOLIC", "PARABOLIC",
    "PLANAR", "UMBILIC", "local_fit", "LocalFit",
]
__version__ = "0.1.0"
