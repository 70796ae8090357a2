"""``estimate``: the pipeline neighbours -> initial normals -> orientation -> fit -> frame."""

from __future__ import annotations

import numpy as np

from ._progress import Progress
from ._validate import as_normals, as_points, check_int
from .frame import darboux_frame
from .methods import check_options, get_method
from .neighbours import Neighbours, build_neighbours
from .normals import orient_normals, pca_normals
from .patch import Chunk
from .result import CurvatureResult

_CHUNK = 32_768
_ORIENTATIONS = ("auto", "propagate", "outward", "keep")
MAX_PASSES = 20


def estimate(
    points,
    normals=None,
    *,
    k=15,
    method="nr",
    passes=None,
    orientation="auto",
    neighbours=None,
    options=None,
    drop_nonfinite=False,
    progress=None,
) -> CurvatureResult:
    """Estimate normals, principal curvatures and directions of a point cloud.

    Parameters
    ----------
    points : (N, 3) array_like of finite coordinates.
    normals : (N, 3) array_like, optional. Used as the initial normals (their signs are
        kept); otherwise weighted PCA (eqs. 13–14) estimates them.
    k : int, neighbourhood size including the point itself (the paper uses 15).
    method : str, one of :data:`core.METHODS` ("nr", "nf", "ct", "qp", "qn", "cf", "cn", "jet").
    passes : int, optional. Normal refinement passes after the first fit (NR, §4.4);
        default: the method's (1 for "nr", 0 otherwise). 0 gives plain NF.
    orientation : "auto" (keep given normals; orient estimated ones outward), "propagate"
        (Hoppe et al. 1992), "outward", "keep", or a (3,) viewpoint.
    neighbours : :class:`core.Neighbours`, optional, from :func:`build_neighbours` on the
        same points with ``k_max >= k``; reused instead of a new search.
    options : dict, optional, method options (see ``core.METHODS[name].options``).
    drop_nonfinite : bool. If True rows with NaN/inf are dropped (and counted in
        ``params["dropped"]``) instead of raising.
    progress : callable(fraction, stage) -> None | False, optional. Returning False
        cancels: :class:`core.Cancelled` is raised.

    Returns
    -------
    CurvatureResult

    Examples
    --------
    >>> from core import estimate, shapes
    >>> s = shapes.sphere(2000, radius=2.0, seed=1)
    >>> r = estimate(s.points, k=15)
    >>> bool(abs(np.median(r.mean) - 0.5) < 0.01)
    True
    """
    pts, kept = as_points(points, drop_nonfinite=drop_nonfinite)
    n = len(pts)
    if n < 3:
        raise ValueError(f"points must hold at least 3 points, got {n}")
    m = get_method(method)
    opts = check_options(m, options)
    k = check_int(k, name="k", low=m.min_k, high=n)
    passes = m.default_passes if passes is None else check_int(passes, name="passes", low=0, high=MAX_PASSES)
    if normals is not None:
        normals = as_normals(np.asarray(normals)[kept] if drop_nonfinite else normals, n)
    view = _check_orientation(orientation)
    report = Progress(progress)

    nb = _neighbours(pts, k, neighbours, report.sub(0.0, 0.3))
    idx, dist = nb.take(k)
    if normals is None:
        nrm, has_normal = pca_normals(pts, idx, dist, progress=report.sub(0.3, 0.4))
        mode = "outward" if view == "auto" else view
    else:
        nrm, has_normal = normals, np.ones(n, dtype=bool)
        mode = "keep" if view == "auto" else view
    nrm = orient_normals(pts, nrm, idx, mode, ok=has_normal)
    report(0.45, "orientation")

    h = dist[:, -1]
    n_fits = passes + 1
    for p in range(n_fits):
        sub = report.sub(0.45 + 0.55 * p / n_fits, 0.45 + 0.55 * (p + 1) / n_fits)
        out = _fit_all(pts, nrm, idx, h, has_normal, m, opts, sub)
        refined, k1, k2, e1, e2, valid = out
        if p < passes:  # refinement: the refined normals become the input normals
            nrm = np.where(valid[:, None], refined, nrm)
    params = dict(
        method=m.name, k=k, passes=passes, orientation=orientation if isinstance(orientation, str) else "viewpoint",
        options=opts, n_points=n, dropped=int(np.count_nonzero(~kept)),
        normals_given=normals is not None,
    )
    normals_out = np.where(valid[:, None], refined, nrm)
    return CurvatureResult(
        points=pts, normals=normals_out, k1=k1, k2=k2, e1=e1, e2=e2, valid=valid,
        method=m.name, k=k, passes=passes, params=params, neighbours=nb,
    )


def _check_orientation(orientation):
    if isinstance(orientation, str):
        if orientation not in _ORIENTATIONS:
            raise ValueError(
                f"orientation {orientation!r} is invalid; must be one of {list(_ORIENTATIONS)} or a (3,) viewpoint"
            )
        return orientation
    view = np.asarray(orientation, dtype=float)
    if view.shape != (3,) or not np.isfinite(view).all():
        raise ValueError(f"orientation as a viewpoint must be 3 finite numbers, got {orientation!r}")
    return view


def _neighbours(pts, k, neighbours, report) -> Neighbours:
    if neighbours is None:
        return build_neighbours(pts, k, progress=report)
    if not isinstance(neighbours, Neighbours):
        raise ValueError(f"neighbours must be a core.Neighbours, got {type(neighbours).__name__}")
    if neighbours.k_max < k:
        raise ValueError(f"neighbours were built with k_max={neighbours.k_max} < k={k}; rebuild them")
    if not neighbours.matches(pts):
        raise ValueError("neighbours were built on different points; rebuild them")
    return neighbours


def _fit_all(pts, nrm, idx, h, has_normal, method, opts, report):
    """Run one fit of ``method`` over all points in chunks; returns the frame arrays."""
    n = len(pts)
    normal = np.full((n, 3), np.nan)
    e1 = np.full((n, 3), np.nan)
    e2 = np.full((n, 3), np.nan)
    k1 = np.full(n, np.nan)
    k2 = np.full(n, np.nan)
    valid = np.zeros(n, dtype=bool)
    usable = has_normal & (h > 0)
    for start in range(0, n, _CHUNK):
        centres = np.arange(start, min(n, start + _CHUNK))
        centres = centres[usable[centres]]
        if len(centres):
            hc = h[centres]
            chunk = Chunk.build(pts, nrm, idx[centres], hc, centres)
            mu, W, ok = method.fit(chunk, **opts)
            c_n, c_k1, c_k2, c_e1, c_e2, ok2 = darboux_frame(chunk.t1, chunk.t2, chunk.z, mu, W / hc[:, None, None])
            good = ok & ok2
            sel = centres[good]
            normal[sel], e1[sel], e2[sel] = c_n[good], c_e1[good], c_e2[good]
            k1[sel], k2[sel] = c_k1[good], c_k2[good]
            valid[sel] = True
        report(min(n, start + _CHUNK) / n, method.name)
    return normal, k1, k2, e1, e2, valid
