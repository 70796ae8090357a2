"""Darboux core: differential geometry of unorganized point clouds.

The augmented Darboux frame (p, n, e1, e2, k1, k2) of every point by the normal-fitting
method of Cheng & Zhang (2009) and the baselines it is compared with. numpy/scipy only.
"""

from ._numba_cache import configure as _configure_numba_cache

_configure_numba_cache()  # before any kernel is compiled: a read-only install must still import

from . import io, metrics, noise, shapes  # noqa: E402
from ._progress import Cancelled  # noqa: E402
from .estimate import estimate  # noqa: E402
from .methods import METHODS, Method, get_method  # noqa: E402
from .neighbours import Neighbours, build_neighbours  # noqa: E402
from .planning import EstimatePlan, plan  # noqa: E402
from .result import SCALAR_FIELDS, CurvatureResult  # noqa: E402

__all__ = [
    "estimate", "plan", "EstimatePlan", "build_neighbours", "Neighbours", "CurvatureResult", "METHODS", "Method",
    "get_method", "Cancelled", "SCALAR_FIELDS", "shapes", "noise", "metrics", "io",
]
__version__ = "0.1.0"
