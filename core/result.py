"""The frozen result of an estimate: the augmented Darboux frame of every point."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .anisotropy import anisotropy_of, striped
from .border import border_of_valid
from .point_types import point_types
from .tuning import OUTLIER_SCORE


@dataclass(frozen=True, eq=False)
class CurvatureResult:
    """Per-point differential geometry, one row per input point.

    Attributes
    ----------
    points, normals : (N, 3) arrays; normals are the (refined) unit normals.
    k1, k2 : (N,) principal curvatures, k1 >= k2, eigenvalues of dn (k = +1/R on a
        sphere with outward normals).
    e1, e2 : (N, 3) unit principal directions, orthogonal to the normal, e1 x e2 = n; signed by
        one world rule (:func:`core.frame.signed_directions`).
    valid : (N,) bool. Where False the neighbourhood was degenerate (duplicates,
        collinear, rank-deficient fit): k1, k2, e1, e2 are NaN there, never a made-up value.
    k_point : (N,) int, neighbourhood size used at each point (varies with ``k="auto"``).
    degree_point : (N,) int, polynomial degree of the model fitted at each point: of the
        normal field for NF/NR (the highest up to the ``degree`` option that the point's
        neighbourhood determines: on two or three scan lines a cubic falls to 2 or 1), of the position jet where ``k="auto"`` kept a jet (see
        :mod:`core.scale`); -1 for methods without the option.
    outlier_score : (N,) distance of each point from its neighbours' plane in units of
        their spread; ``inf`` for the points of a group of fewer points than a
        neighbourhood, apart from the rest (:func:`core.kernels.isolated_groups`: a floating
        clump whose own points made up its neighbours' plane); :attr:`outlier` is
        ``outlier_score > 4``.
    crease : (N,) bool, points where the linear normal model fails (RMS residual of the
        normal fit > 0.25 of the normals' spread, and > 3x the cloud's median residual, so
        that noise is not taken for edges): sharp edges and corners, flagged rather than trusted.
    border : (N,) bool, valid points on a border of the sampled surface (scan rims,
        holes, silhouettes; see :mod:`core.border`): their fits are one-sided, flagged
        rather than trusted. The estimate computes it from its neighbours when they hold
        enough (k="auto", or k >= 30); otherwise on first access (one more search), so
        the paper's k = 15 pipeline does not pay for it unless it is used.
    orientation_confidence : (N,) float in [0, 1], the evidence-weighted share of a
        point's neighbours whose normal sign agrees with its own (1: all; 0 without a
        normal; see :mod:`core.orientation`).
    anisotropy : (N,) float in [0, 1], the sampling anisotropy of :mod:`core.anisotropy`
        (near 0 where nearest neighbours lie in every direction, near 1 along scan lines);
        :attr:`striped` is ``anisotropy > 0.8``: H there may show the scan pattern. Computed
        on first access.
    method, k, passes, params : what was run (``k`` is an int or "auto").
    neighbours : the :class:`core.Neighbours` used, to pass back for a fast re-estimate.
    """

    points: np.ndarray
    normals: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    valid: np.ndarray
    method: str
    k: object
    passes: int
    params: dict = field(default_factory=dict)
    neighbours: object = field(default=None, repr=False)
    k_point: np.ndarray = None
    degree_point: np.ndarray = None
    outlier_score: np.ndarray = None
    crease: np.ndarray = None
    orientation_confidence: np.ndarray = None
    _border: np.ndarray = field(default=None, repr=False)
    _anisotropy: np.ndarray = field(default=None, repr=False)
    #: :func:`core.creases.crease_residuals` of the fit creases were judged on (tiles re-judge them)
    _crease_residual: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        n = len(self.points)
        if self.k_point is None:
            object.__setattr__(self, "k_point", np.full(n, self.k if isinstance(self.k, int) else -1))
        if self.degree_point is None:
            object.__setattr__(self, "degree_point", np.full(n, -1))
        if self.outlier_score is None:
            object.__setattr__(self, "outlier_score", np.full(n, np.nan))
        if self.crease is None:
            object.__setattr__(self, "crease", np.zeros(n, dtype=bool))
        if self.orientation_confidence is None:
            object.__setattr__(self, "orientation_confidence", np.full(n, np.nan))

    @property
    def border(self) -> np.ndarray:
        """Valid points on a border of the sampled surface (see the class docstring)."""
        if self._border is None:
            object.__setattr__(self, "_border", border_of_valid(self.points, self.normals, self.valid, self.neighbours))
        return self._border

    @property
    def anisotropy(self) -> np.ndarray:
        """Sampling anisotropy per point (see the class docstring)."""
        if self._anisotropy is None:
            object.__setattr__(self, "_anisotropy", anisotropy_of(self.points, self.normals, self.neighbours))
        return self._anisotropy

    @property
    def striped(self) -> np.ndarray:
        """Points sampled much more densely one way than the other (scan lines)."""
        return striped(self.anisotropy)

    @property
    def point_type(self) -> np.ndarray:
        """Type code per point (:func:`core.point_types` with its defaults; -1 where invalid)."""
        return point_types(self)

    def __len__(self) -> int:
        return len(self.points)

    @property
    def n_invalid(self) -> int:
        return int(np.count_nonzero(~self.valid))

    @property
    def outlier(self) -> np.ndarray:
        """Points far off the surface of their neighbours (score > 4)."""
        return np.nan_to_num(self.outlier_score, nan=0.0) > OUTLIER_SCORE

    @property
    def gaussian(self) -> np.ndarray:
        """K = k1 k2."""
        return self.k1 * self.k2

    @property
    def mean(self) -> np.ndarray:
        """H = (k1 + k2) / 2 (the paper's eq. 6 prints k1 + k2: its fraction bar was lost)."""
        return 0.5 * (self.k1 + self.k2)

    @property
    def shape_index(self) -> np.ndarray:
        """Koenderink's shape index (2/pi) arctan((k1 + k2) / (k1 - k2)) in [-1, 1].

        +1 is a cap curving away from the normal like a sphere seen from outside, -1 a cup,
        0 a symmetric saddle; planar points (k1 = k2 = 0) give 0.
        """
        return (2.0 / np.pi) * np.arctan2(self.k1 + self.k2, self.k1 - self.k2)

    @property
    def curvedness(self) -> np.ndarray:
        """Koenderink's curvedness sqrt((k1^2 + k2^2) / 2)."""
        return np.sqrt(0.5 * (self.k1**2 + self.k2**2))

    def to_pyvista(self):
        """A ``pyvista.PolyData`` with the normals and every per-point field as point data
        (pyvista is imported only here; see :func:`core.interop.to_pyvista`)."""
        from .interop import to_pyvista

        return to_pyvista(self, SCALAR_FIELDS)

    def field(self, name: str) -> np.ndarray:
        """A scalar field by name: one of :data:`SCALAR_FIELDS`."""
        if name not in SCALAR_FIELDS:
            raise ValueError(f"field {name!r} is unknown; valid fields are: {', '.join(SCALAR_FIELDS)}")
        return getattr(self, SCALAR_FIELDS[name])


#: the per-point scalar fields of a result, by short name -> attribute
SCALAR_FIELDS = {
    "mean": "mean",
    "gaussian": "gaussian",
    "k1": "k1",
    "k2": "k2",
    "shape_index": "shape_index",
    "curvedness": "curvedness",
    "k_point": "k_point",
    "degree_point": "degree_point",
    "outlier_score": "outlier_score",
    "anisotropy": "anisotropy",
}
