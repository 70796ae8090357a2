"""Darboux core: differential geometry of unorganized point clouds.

The augmented Darboux frame (p, n, e1, e2, k1, k2) of every point by the normal-fitting
method of Cheng & Zhang (2009) and the baselines it is compared with. numpy/scipy only.
"""

from ._numba_cache import configure as _configure_numba_cache
from ._pages import configure as _configure_pages
from ._threads import configure as _configure_threads

_configure_numba_cache()  # before any kernel is compiled: a read-only install must still import
_configure_threads()  # before the first parallel loop loads OpenMP: idle workers sleep, not spin
_configure_pages()  # numpy's large arrays on 4 KiB pages: fresh huge pages fault on the host of a VM

from . import io, metrics, noise, shapes  # noqa: E402
from ._progress import Cancelled  # noqa: E402
from .estimate import estimate  # noqa: E402
from .methods import METHODS, Method, get_method  # noqa: E402
from .neighbours import Neighbours, build_neighbours  # noqa: E402
from .planning import EstimatePlan, plan  # noqa: E402
from .result import SCALAR_FIELDS, CurvatureResult  # noqa: E402
from .curvature_lines import curvature_lines  # noqa: E402
from .gauss_bonnet import GaussBonnet, gauss_bonnet, point_areas, total_curvature  # noqa: E402
from .local_fit import LocalFit, local_fit  # noqa: E402
from .point_types import (  # noqa: E402
    ELLIPTIC, HYPERBOLIC, PARABOLIC, PLANAR, TYPE_NAMES, UMBILIC, curvature_scale, point_types,
)

__all__ = [
    "estimate", "plan", "EstimatePlan", "build_neighbours", "Neighbours", "CurvatureResult", "METHODS", "Method",
    "get_method", "Cancelled", "SCALAR_FIELDS", "shapes", "noise", "metrics", "io",
    # teaching: the mathematics around one estimate
    "total_curvature", "gauss_bonnet", "GaussBonnet", "point_areas", "curvature_lines",
    "point_types", "curvature_scale", "TYPE_NAMES", "ELLIPTIC", "HYPERBOLIC", "PARABOLIC",
    "PLANAR", "UMBILIC", "local_fit", "LocalFit",
]
__version__ = "0.1.0"
