"""Clouds no estimate can be made on: too few points, all points at one place, or a scale
where squared distances leave the float64 range. They get a result with ``valid=False``
everywhere (and the reason in ``params["degenerate"]``), never a crash or a made-up number."""

from __future__ import annotations

import numpy as np

from ._validate import as_normals, check_int
from .kernels.bounds import bounds
from .methods import check_options, get_method
from .result import CurvatureResult

#: largest |coordinate|: the fits sum squared distances over up to 226 neighbours and cubic
#: terms in units of the neighbourhood radius. Measured: a unit sphere scaled by 1e150
#: gives H to 3e-6 relative, by 1e160 the kd-tree distances overflow to inf.
MAX_COORD = 1e150
#: smallest extent (bounding-box diagonal): a sphere scaled by 1e-160 is still right, by
#: 1e-200 squared distances underflow to 0 and every normal is undefined.
MIN_EXTENT = 1e-150
#: smallest extent relative to |coordinates|: below it the cloud spans fewer than ~4500
#: float64 steps and its shape is rounding noise.
MIN_RELATIVE_EXTENT = 1e-12
#: a cloud whose second principal spread is below this share of its first lies on a line
#: (no surface passes through it, so no point has a normal). The spreads come from the 3x3
#: scatter matrix, whose rounding leaves a line ~1e-8; a 1000:1 thin tube measures 1e-3.
MIN_WIDTH = 1e-6


def reason(points: np.ndarray, min_k: int) -> str | None:
    """Why no point of ``points`` (N, 3), finite, can be estimated, or None."""
    n = len(points)
    if n < min_k:
        return f"{n} points are fewer than the {min_k} the method needs for one fit"
    lo, hi = np.empty(3), np.empty(3)
    bounds(np.ascontiguousarray(points, dtype=np.float64), lo, hi)  # points.min(axis=0), points.max(axis=0)
    size = float(np.abs(np.concatenate([lo, hi])).max())
    if size > MAX_COORD:
        return f"coordinates up to {size:.3g} exceed {MAX_COORD:g} (squared distances overflow); rescale the cloud"
    extent = float(np.linalg.norm((hi - lo) / max(size, 1e-300))) * size
    if extent == 0.0:
        return "all points are identical"
    if extent < MIN_EXTENT or extent < MIN_RELATIVE_EXTENT * size:
        return (f"the cloud spans only {extent:.3g} at coordinates up to {size:.3g} (too small to resolve "
                "in float64); rescale or re-centre the cloud")
    return _collinear(points)


def _collinear(points: np.ndarray) -> str | None:
    """The reason when every point lies on one straight line (within rounding), else None."""
    centred = points - points.mean(axis=0)
    spread = np.linalg.svd(centred.T @ centred, compute_uv=False) ** 0.5
    if spread[1] <= MIN_WIDTH * spread[0]:
        return "all points lie on one straight line: a surface needs points spread in two directions"
    return None


def invalid_result(points, normals, *, method: str, k, passes, why: str, params: dict) -> CurvatureResult:
    """A result for ``points`` with every point invalid: NaN curvatures and directions;
    the given normals (unit length) or NaN."""
    n = len(points)
    if not (isinstance(k, str) and k == "auto"):
        check_int(k, name="k", low=1)
    nan3 = np.full((n, 3), np.nan)
    nrm = nan3.copy() if normals is None else as_normals(normals, n)
    return CurvatureResult(
        points=points, normals=nrm, k1=np.full(n, np.nan), k2=np.full(n, np.nan), e1=nan3.copy(),
        e2=nan3.copy(), valid=np.zeros(n, dtype=bool), method=method, k=k, passes=passes,
        params={**params, "method": method, "k": k, "passes": passes, "n_points": n, "degenerate": why},
        k_point=np.full(n, -1), outlier_score=np.full(n, np.nan), crease=np.zeros(n, dtype=bool),
    )


def invalid_if_degenerate(points, kept, normals, asked: dict, plan=None) -> CurvatureResult | None:
    """For :func:`core.estimate`: the all-invalid result when no fit can be made on
    ``points`` (validated, after dropping the rows not ``kept``), else None. ``asked``
    holds estimate's k, method, passes and options; a given ``plan`` overrides them."""
    if plan is not None:
        method, options, k, passes = plan.method, dict(plan.options), plan.k, plan.passes
    else:
        method = get_method(asked["method"])
        options = check_options(method, asked["options"])
        k, passes = asked["k"], asked["passes"]
    why = reason(points, method.min_k_for(options))
    if why is None:
        return None
    given = None if normals is None else np.asarray(normals)[kept]
    return invalid_result(points, given, method=method.name, k=k, passes=passes, why=why,
                          params={"dropped": int(np.count_nonzero(~kept))})
