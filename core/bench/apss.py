"""MeshLab's APSS curvature (via pymeshlab) as a duck-typed curvature result.

APSS (Guennebaud & Gross 2007, "Algebraic Point Set Surfaces") fits an algebraic sphere
to the points *and their oriented normals* around each point (a Gaussian-like weight of
radius ``filterscale`` x the local point spacing), projects the point onto the implicit
surface and reads the curvature from the gradient and Hessian of the implicit function.
pymeshlab exposes it as ``MeshSet.compute_curvature_and_color_apss_per_vertex``.

pymeshlab is an OPTIONAL benchmark dependency: nothing in :mod:`core` needs it, this module
imports it lazily (:func:`available`, :func:`apss_curvature`), and the accuracy benchmark
skips APSS when it is missing (``pip install pymeshlab``).

Conventions of the filter (checked by ``tests/core/test_bench_accuracy.py`` and printed in
``docs/bench/accuracy.md``; pymeshlab 2025.7):

* The filter writes one scalar per vertex (the vertex "quality"), chosen by
  ``curvaturetype``: ``"Mean"`` is **k1 + k2 (twice H)**, ``"Gauss"`` is K = k1 k2,
  ``"K1"``/``"K2"`` are the principal curvatures **ordered by absolute value**
  (|K1| >= |K2|, not K1 >= K2), ``"ApproxMean"`` the inverse radius of the fitted sphere
  (and no directions).
* Signs follow the input normals: with outward normals a sphere of radius R gives
  Mean = +2/R (the same k = +1/R convention as :mod:`core`); flipping every input normal
  flips Mean and the principal curvatures and leaves Gauss unchanged.
* The principal directions PD1/PD2 (``vertex_curvature_principal_dir{1,2}_matrix``) are
  paired the other way round: **PD1 is the direction of the curvature of smaller |k|**
  (i.e. of K2), PD2 that of the larger |k| (K1).
* Why, from MeshLab's source (``filter_mls/implicits.h``, ``WeingartenMap``): W =
  (I − n nᵀ) Hess(f) / |∇f|; Mean is tr W, Gauss det(W + n nᵀ), K1/K2 come from
  (Mean ± sqrt(Mean² − 4 Gauss))/2 swapped so that |K1| >= |K2| (NaN when the root's
  argument rounds below 0: on an exact sphere, where the colour histogram then aborts the
  process), and the directions from Eigen's ``SelfAdjointEigenSolver`` applied to W — which
  is not symmetric, so only its lower triangle is read — dropping the eigenvector of
  smallest |eigenvalue| as the normal and calling the smaller of the other two PD1. Mean
  and Gauss are therefore exact functions of the fit, but near |k1| = |k2| (H ≈ 0) the
  directions can come out swapped relative to K1/K2 (a 90° error in e1) — a MeshLab quirk
  that APSS's direction errors below include.
* ``"K1"``/``"K2"`` abort the whole process ("double free or corruption") on an exact
  sphere (every point umbilic), so they are never used here: k1, k2 are recovered from
  one "Mean" and one "Gauss" run as H ± sqrt(H² − K), and the direction of the larger
  signed curvature is PD2 where H >= 0 (there the larger k has the larger |k|) and PD1
  where H < 0.
* ``filterscale`` is relative to each vertex's local point spacing ("radius", estimated
  by MeshLab from its nearest neighbours), not to the mean spacing; 2 is MeshLab's default.
* With ``selectiononly`` only the selected vertices are projected and evaluated (the
  surface is still defined by all points); the others keep quality 0 and undefined
  directions. :func:`apss_curvature` uses it for ``evaluate`` subsets.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

INSTALL_HINT = "pip install pymeshlab"


class ApssUnavailable(ImportError):
    """pymeshlab is not installed (or failed to import)."""


def _pymeshlab():
    try:
        import pymeshlab  # noqa: PLC0415 (lazy on purpose: optional dependency)
    except Exception as exc:  # ImportError, or a broken binary wheel (OSError)
        raise ApssUnavailable(f"pymeshlab is not available ({exc}); {INSTALL_HINT}") from exc
    return pymeshlab


def available() -> bool:
    """Whether pymeshlab can be imported."""
    try:
        _pymeshlab()
    except ApssUnavailable:
        return False
    return True


def version() -> str:
    """pymeshlab's version string ("" when unknown or missing)."""
    try:
        from importlib.metadata import version as _v

        return _v("pymeshlab")
    except Exception:
        return ""


@dataclass(frozen=True, eq=False)
class ApssResult:
    """Duck-typed like :class:`core.CurvatureResult` for :func:`core.metrics.summary`.

    ``normals`` are the input normals: APSS's curvature signs follow their orientation.
    ``valid`` is False outside the evaluated subset and where the projection failed.
    """

    points: np.ndarray
    normals: np.ndarray
    k1: np.ndarray
    k2: np.ndarray
    e1: np.ndarray
    e2: np.ndarray
    valid: np.ndarray
    scale: float
    params: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.points)

    @property
    def gaussian(self) -> np.ndarray:
        return self.k1 * self.k2

    @property
    def mean(self) -> np.ndarray:
        return 0.5 * (self.k1 + self.k2)


def _run(pymeshlab, points, normals, select, curvaturetype, scale, spherical, accuracy, max_iters):
    """One filter run; returns (quality, pd1, pd2) as new arrays."""
    kwargs = dict(vertex_matrix=points, v_normals_matrix=normals)
    if select is not None:
        kwargs["v_scalar_array"] = select.astype(np.float64)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(**kwargs))
    if select is not None:
        ms.compute_selection_by_condition_per_vertex(condselect="q > 0.5")
    ms.compute_curvature_and_color_apss_per_vertex(
        filterscale=float(scale), projectionaccuracy=float(accuracy), maxprojectioniters=int(max_iters),
        sphericalparameter=float(spherical), curvaturetype=curvaturetype, selectiononly=select is not None,
    )
    mesh = ms.current_mesh()
    return (np.array(mesh.vertex_scalar_array(), dtype=np.float64),
            np.array(mesh.vertex_curvature_principal_dir1_matrix(), dtype=np.float64),
            np.array(mesh.vertex_curvature_principal_dir2_matrix(), dtype=np.float64))


def apss_curvature(points, normals, *, scale=2.0, evaluate=None, spherical=1.0, accuracy=1e-4,
                   max_iters=15) -> ApssResult:
    """APSS principal curvatures and directions of a point cloud with oriented normals.

    Parameters
    ----------
    points : (N, 3) coordinates.
    normals : (N, 3) unit normals, consistently oriented (their orientation sets the sign
        of the curvatures, as in :mod:`core`).
    scale : MeshLab's ``filterscale``, in units of the local point spacing (default 2).
    evaluate : (N,) bool, optional: evaluate only these points (the surface is still
        defined by all of them); the others are left invalid.
    spherical, accuracy, max_iters : MeshLab's ``sphericalparameter`` (1 = pure sphere
        fit), ``projectionaccuracy`` and ``maxprojectioniters`` (defaults: MeshLab's).

    Returns
    -------
    ApssResult, with k1 >= k2 and e1, e2 in the :mod:`core` conventions.

    Raises
    ------
    ApssUnavailable if pymeshlab cannot be imported.
    """
    pml = _pymeshlab()
    pts = np.ascontiguousarray(points, dtype=np.float64)
    nrm = np.ascontiguousarray(normals, dtype=np.float64)
    n = len(pts)
    if pts.shape != (n, 3) or nrm.shape != (n, 3):
        raise ValueError(f"points and normals must be (N, 3) arrays, got {pts.shape} and {nrm.shape}")
    if not (np.isfinite(pts).all() and np.isfinite(nrm).all()):
        raise ValueError("points and normals must be finite")
    if not (np.isfinite(scale) and scale > 0):
        raise ValueError(f"scale must be a positive number, got {scale!r}")
    select = None if evaluate is None else np.asarray(evaluate, dtype=bool)
    if select is not None and select.shape != (n,):
        raise ValueError(f"evaluate must be a (N,) bool mask, got shape {select.shape}")
    # never "K1"/"K2": they abort the process on umbilic points (see the module docstring)
    mean2, _, _ = _run(pml, pts, nrm, select, "Mean", scale, spherical, accuracy, max_iters)
    gauss, pd1, pd2 = _run(pml, pts, nrm, select, "Gauss", scale, spherical, accuracy, max_iters)

    H = 0.5 * mean2
    root = np.sqrt(np.maximum(H * H - gauss, 0.0))
    k1, k2 = H + root, H - root
    # PD1 goes with the smaller |k|: that is k2 where H >= 0, k1 where H < 0
    larger_first = (H >= 0)[:, None]
    e1 = np.where(larger_first, pd2, pd1)
    e2 = np.where(larger_first, pd1, pd2)
    with np.errstate(invalid="ignore", divide="ignore"):
        l1 = np.linalg.norm(e1, axis=1)
        l2 = np.linalg.norm(e2, axis=1)
        e1 = e1 / l1[:, None]
        e2 = e2 / l2[:, None]
    # a vertex the filter did not finish (failed projection, not selected) keeps
    # undefined directions: accept only unit ones
    valid = np.isfinite(k1) & np.isfinite(k2) & (np.abs(l1 - 1) < 1e-3) & (np.abs(l2 - 1) < 1e-3)
    if select is not None:
        valid &= select
    nan = np.nan
    k1 = np.where(valid, k1, nan)
    k2 = np.where(valid, k2, nan)
    e1 = np.where(valid[:, None], e1, nan)
    e2 = np.where(valid[:, None], e2, nan)
    return ApssResult(points=pts, normals=nrm, k1=k1, k2=k2, e1=e1, e2=e2, valid=valid, scale=float(scale),
                      params=dict(method="apss", scale=float(scale), spherical=spherical,
                                  evaluated=int(n if select is None else select.sum())))
