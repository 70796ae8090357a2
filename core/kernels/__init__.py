"""Compiled inner loops (numba, ``nogil``): the hot paths of a large estimate, one module
per algorithm.

- :mod:`.pca` weighted-PCA normals (eqs. 13-14); :mod:`.jet` osculating 2-jet normals;
- :mod:`.nf` the normal fit NF (eqs. 21-26) with :mod:`.lstsq` (its least
  squares) and :mod:`.robust` (IRLS weights, median);
- :mod:`.scale` the per-point choice of k (ICI) and the fold test that bounds it;
- :mod:`.sign_evidence` the signed chord evidence and Kruskal signs of :mod:`core.orientation`;
  :mod:`.border` the angular-gap border test; :mod:`.outliers` scores; :mod:`.anisotropy` the
  sampling anisotropy of :mod:`core.anisotropy`; :mod:`.cross` the cross edges of
  :mod:`core.double_scan`;
- :mod:`.kd_order` the spatial order itself, :mod:`.kdtree` the k nearest neighbours of points
  in that order; :mod:`.frame` the
  augmented Darboux frame every fit ends in (:func:`core.frame.darboux_frame`);
- :mod:`.algebra` small dense linear algebra shared by them.

Each kernel is a plain loop over points doing what its docstring's numpy reference says;
they release the GIL so a GUI thread keeps running. Many arrays travel together as small
records (:class:`Frames`, :class:`Settings`, :class:`Fits`) rather than as long
argument lists.
"""

from .jet import jet_normals
from .nf import Fits, Frames, Settings, normal_fit
from .outliers import isolated_groups, outlier_scores
from .pca import normal_spread, pca_normals, pca_normals_at
from .scale import ScaleRule, choose_scales, fold_limits
from .spread import scatter_shapes

__all__ = [
    "pca_normals", "pca_normals_at", "jet_normals", "normal_fit", "Frames", "Settings", "Fits", "ScaleRule", "choose_scales", "fold_limits",
    "outlier_scores", "isolated_groups", "normal_spread", "scatter_shapes",
]
