"""Clouds no estimate can be made on: too few points, all points at one place, on one straight
line, at a scale where squared distances leave the float64 range, or float32 coordinates
rounded to a grid as coarse as their spacing. They get a result with
``valid=False`` everywhere (and the reason in ``params["degenerate"]``), never a crash or a
made-up number; the arguments are checked first, as on any cloud (:func:`checked_plan`)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ._validate import check_int
from .duplicates import find_duplicates
from .kernels.bounds import bounds
from .methods import check_options, get_method
from .neighbours import Neighbours
from .normal_repair import split_normals
from .result import CurvatureResult
from .stages import find_neighbours

#: largest |coordinate|, and the smallest extent (bounding-box diagonal): inside them a cloud
#: scaled by a power of two gives the same bits, its lengths and curvatures scaled exactly
#: (``tests/core/test_degenerate.py``). Measured on a noisy 6000-point torus (extent ~6):
#: the fits and the frames stay exact up to 2^260 (k = 15), but the outlier scores'
#: eigenvalues of the neighbours' scatter go through its 4th power (offsets^8), which leaves
#: float64 from 2^130 (1e39) and 2^-125 (2e-38; NaN from 2^-140), and k="auto" reads those
#: scores (it chose other sizes there); at 1e160 the kd-tree's squared distances overflow.
#: The bounds keep 8 orders of magnitude from the first of these.
MAX_COORD = 1e30
MIN_EXTENT = 1e-30
#: smallest extent relative to |coordinates|: below it the cloud spans fewer than ~4500
#: float64 steps and its shape is rounding noise.
MIN_RELATIVE_EXTENT = 1e-12
#: a cloud whose second principal spread is below this share of its first may lie on a line
#: (then :func:`_straight_runs` decides). The spreads come from the 3x3 scatter matrix,
#: whose rounding leaves a line ~1e-8; a 1000:1 thin tube measures 1e-3.
MIN_WIDTH = 1e-6
#: the scatter matrix is summed over at most ~this many points (every n // SAMPLE-th): a
#: subset that spreads in two directions shows the cloud does (at 1M points 40 -> 4 ms;
#: a subset in line, e.g. one column of a grid, only sends the cloud on to the runs).
SAMPLE = 65536
#: a cloud whose coordinates are float32 values is refused when float32's step at their
#: magnitude exceeds this share of the median distance between nearest points: the points
#: were moved by up to half a step, more than the spacing the fits measure shape at. A step
#: up to about the spacing is rounding the fits take as noise, and data on a grid of their
#: own (whole millimetres, 1/128) are never nearer than their step, so such a grid is not
#: refused wherever it lies (at 0.1 a whole-millimetre cloud 9-17 km from the origin was,
#: 1-8 km out it was not). Measured (unit sphere, 3000 points, float32 steps in one / two
#: axes), mean |H R - 1| of k="auto": step 1x spacing 0.002 / 0.004, 2x 0.004 / 0.013, 3x
#: 0.007 / 0.029, 4x 0.013 / 0.095, 8x 0.16 / 1.1 (k = 15: 0.07 / 0.11 at 1x, 0.11 / 0.22 at 2x)
FLOAT32_STEP_SHARE = 2.0
#: ... or when it is at least half the spacing and rounding left fewer places than this share
#: of the points (every axis coarse: the places are then a step apart, their spacing says nothing)
FLOAT32_COLLAPSED = 0.5
#: float32's step is not compared with the spacing (no neighbour search, ~0.3 s at 1M points)
#: when it is below 1/FLOAT32_PLAUSIBLE of the cloud's extent / sqrt(N), the spacing of an
#: even surface sampling: the flag would then need a median nearest distance 100x below
#: that (a clustered scan's is some times below it; an estimate, not measured on scans)
FLOAT32_PLAUSIBLE = 1e3
#: neighbours read for a point's nearest distinct one (exact copies are skipped)
SPACING_K = 8
#: points per run along the line's direction in :func:`_straight_runs`.
RUN = 16
#: a run is straight when its points' rms distance from their own line parallel to the
#: cloud's is at most this share of their mean gap along it (a line's rounding, or jitter
#: far below its spacing). A surface's runs measure more than 1: 1.3-3 along a 1000:1
#: tube, 100 and more on slices across a sphere or a plane.
LINE_JITTER = 0.1


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
    return _float32_grid(points, lo, hi) or _collinear(points, (lo + hi) / 2)


def _float32_grid(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> str | None:
    """The reason when the coordinates are float32 values (a float32 array or file, read as
    float64: the precision was lost before) whose step at their magnitude is more than
    :data:`FLOAT32_STEP_SHARE` of the distance between nearest points, else None. A unit
    sphere at UTM coordinates in float32 lies on a 0.5 m grid: 3000 points on ~60 places,
    flat curvature. Cheap on float64 clouds (their sample has finer values) and on float32
    ones far finer than any plausible spacing (:data:`FLOAT32_PLAUSIBLE`)."""
    top = np.maximum(np.abs(lo), np.abs(hi))
    if top.max() > np.finfo(np.float32).max:
        return None
    sample = points[:: max(1, len(points) // SAMPLE)]
    if not np.array_equal(sample, sample.astype(np.float32)):
        return None
    step = _float32_step(sample, top)
    if step * FLOAT32_PLAUSIBLE < float(np.linalg.norm(hi - lo)) / np.sqrt(len(points)):
        return None
    spacing = _median_spacing(points)
    if step <= FLOAT32_STEP_SHARE * spacing and not (step >= 0.5 * spacing and _collapsed(sample)):
        return None
    return (f"the coordinates are float32 values: their step {step:.3g} at coordinates up to {top.max():.6g} is "
            f"{step / spacing:.2g}x the median distance between nearest points ({spacing:.3g}): rounding to "
            "float32 moved the points by a large share of their spacing (too coarse to resolve in float32); "
            "re-centre the cloud before converting it to float32, or keep float64 coordinates")


def _collapsed(sample: np.ndarray) -> bool:
    """Whether rounding put most points on top of others (fewer places than half the
    points): then the nearest distinct places are a step apart whatever the spacing was,
    and only the copies tell (an object far smaller than float32's step in every axis)."""
    merged = find_duplicates(np.ascontiguousarray(sample))
    return merged is not None and len(merged.first) < FLOAT32_COLLAPSED * len(sample)


def _float32_step(sample: np.ndarray, top: np.ndarray) -> float:
    """The largest float32 step the coordinates show: per axis, float32's step at its
    largest |value| if some value is an odd multiple of it (else the axis lies on a coarser
    grid of its own, e.g. whole numbers: float32 did not round it)."""
    steps = np.spacing(top.astype(np.float32)).astype(np.float64)
    used = [bool(np.any(np.mod(sample[:, a] / steps[a], 2.0) != 0.0)) for a in range(3)]
    return float(max((steps[a] for a in range(3) if used[a]), default=0.0))


def _median_spacing(points: np.ndarray) -> float:
    """Median distance from a point to its nearest distinct point (a sample of the points
    queried against all; a point whose :data:`SPACING_K` nearest are all copies of it
    does not count, and with none left the spacing is 0)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(points, balanced_tree=False, compact_nodes=False)  # 2.5x faster to build, as fast here
    dist, _ = tree.query(points[:: max(1, len(points) // 4096)], k=min(SPACING_K, len(points)))
    dist = np.where(dist > 0, dist, np.inf).min(axis=1)
    dist = dist[np.isfinite(dist)]
    return float(np.median(dist)) if len(dist) else 0.0


def _collinear(points: np.ndarray, centre: np.ndarray) -> str | None:
    """The reason when every point lies on one straight line (within rounding), else None.

    A cloud is a line only if every part of it is: the whole cloud's spread across its
    principal direction is only a screen (two spheres 1e9 apart are thin next to their
    distance, yet surfaces); :func:`_straight_runs` then judges each part against the
    spacing of its own points."""
    sample = points[:: max(1, len(points) // SAMPLE)] - centre  # centred first: no cancellation far from 0
    mean = np.einsum("ij->j", sample) / len(sample)
    values, vectors = np.linalg.eigh(sample.T @ sample - len(sample) * np.outer(mean, mean))
    spread = np.sqrt(np.maximum(values[::-1], 0.0))
    if spread[1] > MIN_WIDTH * spread[0] or not _straight_runs(points, vectors[:, ::-1]):
        return None
    return "all points lie on one straight line: a surface needs points spread in two directions"


def _straight_runs(points: np.ndarray, frame: np.ndarray) -> bool:
    """Whether every run of :data:`RUN` consecutive points along ``frame[:, 0]`` (the
    cloud's principal direction; ``frame`` orthonormal) is straight: its points' rms
    distance from their own line along it at most :data:`LINE_JITTER` of their mean gap.
    Each run is taken relative to its first point, so parts far from each other (or from
    0) are judged at their own scale; a run across two parts spans their distance and is
    straight, but any run inside a surface (a slice across it) is not."""
    n = len(points)
    m = min(RUN, n)
    order = np.argsort(points @ frame[:, 0])
    rows = np.concatenate([order[: n - n % m], order[n - m:]]) if n % m else order
    runs = np.take(points, rows, axis=0).reshape(-1, m, 3)  # np.take: 3.5x faster than points[rows]
    local = (runs - runs[:, :1]) @ frame  # along, across, across
    across = local[..., 1:]
    centre = np.einsum("rij->rj", across) / m
    width2 = np.einsum("rij,rij->r", across, across) / m - np.einsum("rj,rj->r", centre, centre)
    gap = np.ptp(local[..., 0], axis=1) / (m - 1)
    return bool((width2 <= (LINE_JITTER * gap) ** 2).all())


def min_k_asked(asked: dict) -> int:
    """The fewest points one fit of the asked method (with its options) needs."""
    method = get_method(asked["method"])
    return method.min_k_for(check_options(method, asked["options"]))


def checked_plan(n: int, asked: dict, make_plan, *, planned: bool):
    """:func:`core.estimate`'s request on ``n`` points checked as on any cloud, degenerate or
    not: ``make_plan(n, asked)`` (its ``_plan``: the given plan, or one built from ``asked``;
    a ValueError naming the argument, its value and what is allowed). A cloud of fewer
    points than the method needs for one fit leaves an integer k no allowed value; it gets
    the all-invalid result for any k >= 1 (:func:`reason`) and its other arguments are
    checked by the plan of the smallest cloud the method fits, made for its ``n`` points
    (all of them searched, as k="auto" does). ``planned``: a plan was given."""
    k = asked["k"]
    if not planned and not isinstance(k, str):
        low = min_k_asked(asked)
        if n < low:
            k = check_int(k, name="k", low=1)
            least = make_plan(low, {**asked, "k": low})
            return replace(least, n_points=n, k=k, candidates=(n,), k_search=n, k_initial=n)
    return make_plan(n, asked)


def invalid_result(points, normals, *, method: str, k, passes, why: str, params: dict) -> CurvatureResult:
    """A result for ``points`` with every point invalid: NaN curvatures and directions;
    the given normals (any length, NaN allowed: :func:`core.normal_repair.split_normals`)
    at unit length where they have a direction, else (and without them) NaN."""
    n = len(points)
    if not (isinstance(k, str) and k == "auto"):
        check_int(k, name="k", low=1)
    nan3 = np.full((n, 3), np.nan)
    if normals is None:
        nrm = nan3.copy()
    else:  # a degenerate cloud has no neighbourhoods to estimate a missing normal from
        nrm, _, counts = split_normals(normals)
        params = {**params, "normals_repaired": {**counts, "estimated": 0}}
    return CurvatureResult(
        points=points, normals=nrm, k1=np.full(n, np.nan), k2=np.full(n, np.nan), e1=nan3.copy(),
        e2=nan3.copy(), valid=np.zeros(n, dtype=bool), method=method, k=k, passes=passes,
        params={**params, "method": method, "k": k, "passes": passes, "n_points": n, "degenerate": why},
        k_point=np.full(n, -1), outlier_score=np.full(n, np.nan), crease=np.zeros(n, dtype=bool),
    )


def invalid_if_degenerate(points, kept, given, asked: dict, plan=None, *, neighbours=None) -> CurvatureResult | None:
    """For :func:`core.estimate`: the all-invalid result when no fit can be made on
    ``points`` (validated, after dropping the rows not ``kept``), else None. ``given``: the
    given normals of the points kept, shape checked (any length, NaN allowed), or None.
    ``plan``: the checked request (:func:`checked_plan`), else ``asked`` (estimate's k,
    method, passes and options) gives the method. A given ``neighbours`` graph must be a
    :class:`core.Neighbours` on every cloud (one of copies uses no given graph) and, on a
    degenerate one, is checked as on a cloud that is estimated
    (:func:`core.stages.find_neighbours`: its ``k_max`` and points)."""
    if plan is not None:
        method, options, k, passes = plan.method, dict(plan.options), plan.k, plan.passes
    else:
        method = get_method(asked["method"])
        options = check_options(method, asked["options"])
        k, passes = asked["k"], asked["passes"]
    if neighbours is not None and not isinstance(neighbours, Neighbours):  # on every cloud (copies' use no graph)
        find_neighbours(points, plan, neighbours, None)  # its ValueError naming the type
    why = reason(points, method.min_k_for(options))
    if why is None:
        return None
    if neighbours is not None:
        find_neighbours(points, plan, neighbours, None)
    return invalid_result(points, given, method=method.name, k=k, passes=passes, why=why,
                          params={"dropped": int(np.count_nonzero(~kept))})
