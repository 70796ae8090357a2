"""``estimate``: the pipeline neighbours -> initial normals -> orientation -> fit -> frame."""

from __future__ import annotations

import numpy as np

from . import kernels, scale
from ._progress import Progress
from ._validate import as_normals, as_points, check_int
from .frame import darboux_frame
from .methods import check_options, get_method
from .neighbours import Neighbours, build_neighbours
from .normals import jet_normals, orient_normals, pca_normals
from .patch import Chunk
from .result import CurvatureResult
from .tuning import (AUTO_PASSES, CREASE_NOISE, CREASE_RATIO, CREASE_SPREAD, MAX_PASSES, OUTLIER_FLOOR, OUTLIER_SCORE,
                     PASS_DECAY, PCA_K)

_CHUNK = 32_768
_ORIENTATIONS = ("auto", "propagate", "outward", "keep")


def estimate(
    points,
    normals=None,
    *,
    k="auto",
    method="nr",
    passes=None,
    tol=None,
    initial="auto",
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
    k : "auto" (default) or int. Neighbourhood size including the point itself (the paper
        uses 15). "auto" (NF/NR only) chooses k per point by a bias–variance rule, see
        :mod:`core.scale`; the result's ``k_point`` holds the choice. Unless set in
        ``options``, "auto" also fits a cubic normal field (``degree=3``), Tukey-robust,
        and NR refines while it removes noise (see ``passes``).
    method : str, one of :data:`core.METHODS` ("nr", "nf", "ct", "qp", "qn", "cf", "cn", "jet").
    passes : int, optional. Normal refinement passes after the first fit (NR, §4.4);
        default: the method's (1 for "nr", 0 otherwise). With k="auto" it is a maximum
        (default 4): a pass is undone, and refinement stops, once it changes the normals by
        more than 0.7x the pass before (smoothing the shape rather than the noise;
        ``params["passes_run"]`` tells how many were kept). 0 gives plain NF.
    tol : float, optional. Stop refining early once the mean change of the normals in a
        pass is below ``tol`` degrees (``passes`` is then the maximum).
    initial : "auto", "pca" or "jet": how normals are estimated when none are given.
        "pca" is the paper's weighted PCA (eqs. 13–14); "jet" refines it with the normal
        of an osculating 2-jet (Cazals & Pouget), markedly closer on curved patches.
        "auto" is "pca" for an integer k (the paper's pipeline) and "jet" for k="auto".
        With k="auto" the initial neighbourhood grows as the square root of the noise,
        measured from the residuals of 2-jets on 15 neighbours (``params["noise"]``, in
        units of their radius; ``params["initial_k"]``; see :data:`core.scale.INITIAL_K0`),
        and in robust mode leaves out the points flagged as outliers.
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
    >>> r = estimate(s.points)
    >>> bool(abs(np.median(r.mean) - 0.5) < 0.01)
    True
    """
    pts, kept = as_points(points, drop_nonfinite=drop_nonfinite)
    n = len(pts)
    if n < 3:
        raise ValueError(f"points must hold at least 3 points, got {n}")
    m = get_method(method)
    opts = check_options(m, options)
    auto = isinstance(k, str) and k == "auto"
    if auto:
        if m.name not in ("nf", "nr"):
            raise ValueError(f'k="auto" is available for methods nf and nr, not {m.name!r}; pass an integer k')
        ks = scale.candidates(n)
        k_search = ks[-1]
        given = options or {}
        if "robust" not in given:
            opts["robust"] = "tukey"  # free on clean data, keeps 3 % outliers from spoiling their neighbours
        if "degree" not in given:  # a cubic normal field, unless the cloud is too small for it
            opts["degree"] = scale.AUTO_DEGREE if ks[0] >= scale.AUTO_KS[0] else 1
        if passes is None and m.default_passes:
            passes = AUTO_PASSES
    else:
        if isinstance(k, str):
            raise ValueError(f'k must be an integer or "auto", got {k!r}')
        k = check_int(k, name="k", low=m.min_k_for(opts), high=n)
        k_search = k
    passes = m.default_passes if passes is None else check_int(passes, name="passes", low=0, high=MAX_PASSES)
    if tol is not None and not (isinstance(tol, (int, float)) and np.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a positive number of degrees or None, got {tol!r}")
    if normals is not None:
        shape = np.shape(normals)
        if shape != (len(kept), 3):
            raise ValueError(f"normals must have shape ({len(kept)}, 3) to match points, got shape {shape}")
        normals = as_normals(np.asarray(normals)[kept], n)
    if initial not in ("auto", "pca", "jet"):
        raise ValueError(f"initial {initial!r} is invalid; must be one of ['auto', 'pca', 'jet']")
    initial = ("jet" if auto else "pca") if initial == "auto" else initial
    view = _check_orientation(orientation)
    report = Progress(progress)

    nb = _neighbours(pts, k_search, neighbours, report.sub(0.0, 0.3))
    idx_p, dist_p = nb.take(min(PCA_K, k_search) if auto else k_search)
    scores = np.full(n, np.nan)
    kernels.outlier_scores(pts, np.ascontiguousarray(idx_p), OUTLIER_FLOOR, scores)
    outlier = scores > OUTLIER_SCORE
    robust = opts.get("robust") is not None
    noise = k_init = None
    if normals is None:
        nrm, has_normal, noise, k_init = _initial_normals(pts, nb, idx_p, dist_p, initial, auto, outlier,
                                                          robust, k_search, report)
        mode = "outward" if isinstance(view, str) and view == "auto" else view
    else:
        nrm, has_normal = normals, np.ones(n, dtype=bool)
        mode = "keep" if isinstance(view, str) and view == "auto" else view
    nrm = orient_normals(pts, nrm, idx_p, mode, ok=has_normal)
    report(0.45, "orientation")

    fit_start = 0.45
    if auto:
        # creases are judged by the paper's linear fit at the initial scale: a cubic over a
        # wide neighbourhood explains half of a step, so its residuals do not show it
        lin = {**opts, "degree": 1, "robust": None}
        *_, v_lin, lin_stats = _fit_all(pts, nrm, idx_p, np.full(n, idx_p.shape[1]), dist_p[:, -1],
                                        has_normal, m, lin, report.sub(0.45, 0.47))
        crease_initial = _creases(v_lin, *lin_stats)
        inliers = has_normal & ~outlier if robust else has_normal  # outliers sit out the choice of k
        kc = scale.choose_k(pts, np.where(inliers[:, None], nrm, np.nan), nb, inliers, ks, opts["degree"],
                            report.sub(0.47, 0.7))
        fit_start = 0.7
    else:
        kc = np.full(n, k, dtype=np.int64)
    idx, dist = nb.take(int(kc.max()))
    h = dist[np.arange(n), kc - 1]

    n_fits = passes + 1
    converged = False
    best = None
    for p in range(n_fits):
        span = (1.0 - fit_start) / n_fits
        sub = report.sub(fit_start + span * p, fit_start + span * (p + 1))
        fit = _fit_all(pts, nrm, idx, kc, h, has_normal, m, opts, sub)
        refined, valid = fit[0], fit[5]
        # mean turn of the normals in this fit: what the adaptive stop and tol compare
        change = _mean_angle_deg(refined, nrm, valid) if auto or tol is not None else None
        if auto and best is not None and change > PASS_DECAY * last_change:
            break  # this pass smoothed the shape rather than the noise: keep the previous fit
        best, best_input, passes_run, last_change = fit, nrm, p, change
        if p == passes or converged:
            break
        new = np.where(valid[:, None], refined, nrm)
        if robust and p == 0:  # outliers leave their neighbours' fits (and are not estimated)
            has_normal = has_normal & ~outlier
            new[outlier] = np.nan
        converged = tol is not None and change < tol
        nrm = new
    refined, k1, k2, e1, e2, valid, stats = best
    nrm = best_input
    if robust and valid[outlier].any():  # kept the first fit, which still estimated them
        valid = valid & ~outlier
        for a in (refined, k1, k2, e1, e2):
            a[outlier] = np.nan
    report(1.0, "done")
    params = dict(
        method=m.name, k="auto" if auto else k, passes=passes, passes_run=passes_run, tol=tol,
        orientation=orientation if isinstance(orientation, str) else "viewpoint",
        options=opts, n_points=n, dropped=int(np.count_nonzero(~kept)),
        normals_given=normals is not None, initial=None if normals is not None else initial,
        initial_k=k_init, noise=noise,
    )
    normals_out = np.where(valid[:, None], refined, nrm)
    crease = valid & crease_initial if auto else _creases(valid, *stats)
    return CurvatureResult(
        points=pts, normals=normals_out, k1=k1, k2=k2, e1=e1, e2=e2, valid=valid,
        k_point=kc, outlier_score=scores, crease=crease,
        method=m.name, k="auto" if auto else k, passes=passes, params=params, neighbours=nb,
    )


def _initial_normals(pts, nb, idx_p, dist_p, initial, auto, outlier, robust, k_max, report):
    """PCA normals (eqs. 13-14), refined by a 2-jet if ``initial == "jet"``, on ``idx_p``;
    with k="auto" on a neighbourhood that grows with the noise the 2-jets on ``idx_p``
    measure (:func:`core.scale.initial_k`), without the known outliers in robust mode.
    Returns (normals, has_normal, noise, k_init); the last two are None for an integer k."""
    nrm, ok = pca_normals(pts, idx_p, dist_p, progress=report.sub(0.3, 0.37))
    if not auto:
        if initial == "jet":
            nrm, _ = jet_normals(pts, nrm, ok, idx_p, dist_p, progress=report.sub(0.37, 0.43))
        return nrm, ok, None, None
    jet, height = jet_normals(pts, nrm, ok, idx_p, dist_p)
    clean = ~outlier[idx_p].any(axis=1)  # an outlier inflates the residuals around it
    noise = scale.noise_ratio(np.where(clean, height, np.nan) if clean.any() else height, dist_p[:, -1])
    k_init = scale.initial_k(noise, idx_p.shape[1], k_max)
    shun = robust and outlier.any()
    if k_init == idx_p.shape[1] and not shun:
        return (jet if initial == "jet" else nrm), ok, noise, k_init
    idx, dist = nb.take_without(k_init, outlier) if shun else nb.take(k_init)
    nrm, ok = pca_normals(pts, idx, dist, progress=report.sub(0.37, 0.4))
    if initial == "jet":
        nrm, _ = jet_normals(pts, nrm, ok, idx, dist, progress=report.sub(0.4, 0.43))
    return nrm, ok, noise, k_init


def _creases(valid, rms, spread):
    """Points where the neighbours' normals turn a lot but not linearly (a step: a crease).

    On a smooth patch the linear model of eq. 23 explains the turning of the normals and
    the residual is a small part of it; across a sharp edge the normals jump and a line
    explains only part of the jump. Measured on the initial (PCA) normals. Noise leaves
    residuals everywhere: a crease must also stand out against the cloud's typical
    residual (its median: creases are a minority of the points), or a noisy scan would
    be flagged all over.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = rms / spread
    seen = rms[valid & np.isfinite(rms)]  # methods without a normal fit report no residual
    typical = np.median(seen) if len(seen) else 0.0
    return valid & (spread > CREASE_SPREAD) & (ratio > CREASE_RATIO) & (rms > CREASE_NOISE * typical)


def _mean_angle_deg(a, b, mask):
    if not mask.any():
        return 0.0
    cos = np.abs(np.einsum("ij,ij->i", a[mask], b[mask]))
    return float(np.degrees(np.arccos(np.clip(cos, 0.0, 1.0))).mean())


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


def _fit_all(pts, nrm, idx, kc, h, has_normal, method, opts, report):
    """One fit of ``method`` over all points in chunks, through the shared frame path."""
    n = len(pts)
    normal = np.full((n, 3), np.nan)
    e1 = np.full((n, 3), np.nan)
    e2 = np.full((n, 3), np.nan)
    k1 = np.full(n, np.nan)
    k2 = np.full(n, np.nan)
    rms = np.full(n, np.nan)
    spread = np.full(n, np.nan)
    valid = np.zeros(n, dtype=bool)
    usable = has_normal & (h > 0)
    for start in range(0, n, _CHUNK):
        centres = np.arange(start, min(n, start + _CHUNK))
        centres = centres[usable[centres]]
        if len(centres):
            hc = h[centres]
            chunk = Chunk.build(pts, nrm, idx[centres], hc, centres, kc[centres])
            mu, W, ok, *diag = method.fit(chunk, **opts)
            c_n, c_k1, c_k2, c_e1, c_e2, ok2 = darboux_frame(chunk.t1, chunk.t2, chunk.z, mu, W / hc[:, None, None])
            good = ok & ok2
            sel = centres[good]
            normal[sel], e1[sel], e2[sel] = c_n[good], c_e1[good], c_e2[good]
            k1[sel], k2[sel] = c_k1[good], c_k2[good]
            if diag and "rms" in diag[0]:
                rms[sel] = diag[0]["rms"][good]
                spread[sel] = diag[0]["spread"][good]
            valid[sel] = True
        report(min(n, start + _CHUNK) / n, method.name)
    return normal, k1, k2, e1, e2, valid, (rms, spread)
