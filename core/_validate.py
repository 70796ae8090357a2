"""Input validation shared by the public functions: check first, then compute."""

from __future__ import annotations

import numpy as np


#: the fewest points an estimate takes (a surface needs three points to span a plane)
MIN_POINTS = 3


def as_points(points, *, name: str = "points", drop_nonfinite: bool = False):
    """Return ``points`` as a new C-contiguous (N, 3) float64 array.

    Returns ``(array, kept)`` where ``kept`` is the boolean mask of rows kept
    (all True unless ``drop_nonfinite`` dropped rows with NaN/inf).
    """
    drop_nonfinite = check_bool(drop_nonfinite, name="drop_nonfinite")
    try:
        arr = masked_as_nan(points)
    except ValueError as exc:  # ragged nested sequences
        raise ValueError(f"{name} must be an array of shape (N, 3): {exc}") from None
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ValueError(f"{name} must be a numeric array (real) of shape (N, 3), got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"{name} must have shape (N, 3), got shape {arr.shape}")
    arr = np.array(arr, dtype=np.float64, order="C", copy=True)
    finite = np.ones(len(arr), dtype=bool) if np.isfinite(arr).all() else np.isfinite(arr).all(axis=1)
    if not finite.all():
        bad = int((~finite).sum())
        if not drop_nonfinite:
            raise ValueError(
                f"{name} contains {bad} row(s) with NaN or inf{_MASKED * _is_masked(points)} (first at row "
                f"{int(np.flatnonzero(~finite)[0])}); clean them or pass drop_nonfinite=True"
            )
        arr = arr[finite]
    return arr, finite


def as_normals(normals, n_points: int, *, name: str = "normals", repair: bool = False):
    """Validate optional input normals: (N, 3), finite, non-zero; returned unit length.

    With ``repair`` only the dtype and shape are checked and a float64 copy is returned
    as it is: :mod:`core.normal_repair` then fixes the unusable rows one by one.
    """
    arr = masked_as_nan(normals)
    if not (np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ValueError(f"{name} must be a numeric array (real) of shape ({n_points}, 3), got dtype {arr.dtype}")
    if arr.shape != (n_points, 3):
        raise ValueError(f"{name} must have shape ({n_points}, 3) to match points, got shape {arr.shape}")
    arr = np.array(arr, dtype=np.float64, order="C", copy=True)
    if repair:
        return arr
    if not np.isfinite(arr).all():
        raise ValueError(f"{name} contains NaN or inf values{_MASKED * _is_masked(normals)}")
    unit, length = unit_rows(arr)
    tiny = length < 1e-12
    if tiny.any():
        raise ValueError(
            f"{name} has {int(tiny.sum())} zero-length vector(s) (first at row {int(np.flatnonzero(tiny)[0])}); "
            "pass normals=None to estimate them"
        )
    return unit


_MASKED = " (masked entries count as NaN)"


def _is_masked(a) -> bool:
    return isinstance(a, np.ma.MaskedArray)


def masked_as_nan(a) -> np.ndarray:
    """``a`` as an array, a masked array's masked entries NaN (``np.asarray`` would keep the
    values under the mask, and a masked row would be used as a good one)."""
    if isinstance(a, np.ma.MaskedArray):
        if np.ma.getmask(a) is np.ma.nomask or not np.ma.getmaskarray(a).any():
            return np.asarray(a.data)
        if not (np.issubdtype(a.dtype, np.integer) or np.issubdtype(a.dtype, np.floating)):
            return np.asarray(a.data)  # refused as not numeric by the caller
        return np.ma.filled(a.astype(np.float64), np.nan)
    return np.asarray(a)


def unit_rows(arr):
    """``(unit, length)`` of the finite rows of an (N, 3) array: unit vectors (NaN rows
    where the length is 0) and lengths, without overflow or underflow. Each row is scaled
    by its largest component first: the norm of (1e300, 0, 0) would overflow to inf (and the
    vector become 0) and that of (1e-300, 0, 0) underflow to 0."""
    big = np.abs(arr).max(axis=1) if len(arr) else np.zeros(0)
    scaled = arr / np.where(big > 0, big, 1.0)[:, None]
    norm = np.linalg.norm(scaled, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = scaled / np.where(norm > 0, norm, np.nan)[:, None]
    return unit, norm * big


def check_int(value, *, name: str, low: int, high: int | None = None) -> int:
    """``value`` as an int in ``[low, high]``; bool and non-integral values are refused."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    value = int(value)
    if high is not None and high < low:
        raise ValueError(f"{name}={value} cannot be used: it must be at least {low} and at most {high}, "
                         f"so no value is allowed here")
    if value < low or (high is not None and value > high):
        allowed = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name}={value} is out of range; allowed: {allowed}")
    return value


def check_bool(value, *, name: str) -> bool:
    """``value`` as a bool: True or False only (a string such as "no" is truthy)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} must be True or False, got {value!r}")
    return bool(value)


#: what a curvature result has, for the functions that read one (:func:`check_result`)
RESULT_ATTRIBUTES = ("points", "normals", "k1", "k2", "e1", "e2", "valid")


def check_result(res, *, name: str = "res"):
    """``res`` itself when it has the attributes of a :class:`core.CurvatureResult`, else a
    TypeError naming the argument (an array passed for a result raised a bare AttributeError)."""
    missing = [a for a in RESULT_ATTRIBUTES if not hasattr(res, a)]
    if missing:
        raise TypeError(f"{name} must be a curvature result (core.estimate's CurvatureResult), got "
                        f"{type(res).__name__}, which has no {', '.join(missing)}")
    return res


def word(value):
    """A keyword argument's string in its canonical spelling (stripped, lower case), as
    MeshLab and CloudCompare users type "NR" or "Auto"; anything else unchanged."""
    return value.strip().lower() if isinstance(value, str) else value


def check_choice(value, *, name: str, choices) -> str:
    value = word(value)
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} {value!r} is invalid; must be one of {sorted(choices)}")
    return value
