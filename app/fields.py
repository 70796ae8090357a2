"""Scalar fields the viewer can colour the cloud by, and their colour limits.

numpy only (runs on the worker thread for :func:`compute_fields`, on the GUI thread
for :func:`robust_limits`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FieldSpec", "FIELDS", "ALIASES", "resolve_field", "compute_fields", "robust_limits", "curvature_floor",
           "is_signed", "colormap_for"]

#: Colormaps: diverging centred on 0 for signed fields, sequential otherwise.
DIVERGING = "RdBu_r"
SEQUENTIAL = "viridis"
ERROR = "magma"


@dataclass(frozen=True)
class FieldSpec:
    """How to show one field.

    ``signed`` fields get a diverging colormap with limits symmetric about 0.
    ``needs`` is "" (always there), "truth" (synthetic shapes only) or "reference"
    (needs reference normals: from the file or the shape).
    """

    name: str
    label: str  # colour-bar title and combo text
    signed: bool
    needs: str = ""
    unit: str = ""

    @property
    def title(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label


FIELDS: dict[str, FieldSpec] = {
    f.name: f
    for f in (
        FieldSpec("mean", "Mean curvature H", True),
        FieldSpec("gaussian", "Gaussian curvature K", True),
        FieldSpec("k1", "Max. principal curvature k1", True),
        FieldSpec("k2", "Min. principal curvature k2", True),
        FieldSpec("shape_index", "Shape index", True),
        FieldSpec("curvedness", "Curvedness", False),
        FieldSpec("k_point", "Neighbourhood size k", False),
        FieldSpec("outlier_score", "Outlier score", False),
        FieldSpec("normal_dev", "Normal deviation", False, "reference", "deg"),
        FieldSpec("err_mean", "Error of H", False, "truth"),
        FieldSpec("err_gaussian", "Error of K", False, "truth"),
        FieldSpec("err_k1", "Error of k1", False, "truth"),
        FieldSpec("err_k2", "Error of k2", False, "truth"),
        FieldSpec("err_normal", "Error of normal", False, "truth", "deg"),
        FieldSpec("err_direction", "Error of principal direction", False, "truth", "deg"),
    )
}

#: Short names accepted on the command line.
ALIASES = {"h": "mean", "k": "gaussian", "si": "shape_index", "c": "curvedness"}


def resolve_field(name: str) -> str:
    """Canonical field name for ``name`` (case-insensitive, aliases allowed)."""
    key = str(name).strip()
    low = key.lower()
    if key in FIELDS:
        return key
    if low in FIELDS:
        return low
    if low in ALIASES:
        return ALIASES[low]
    valid = ", ".join(list(FIELDS) + [a.upper() if len(a) == 1 else a for a in ALIASES])
    raise ValueError(f"field {name!r} is unknown; valid fields: {valid}")


def _angle_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Unsigned angle between lines (normals up to sign), degrees; NaN where either is NaN."""
    with np.errstate(invalid="ignore"):
        na = np.linalg.norm(a, axis=1)
        nb = np.linalg.norm(b, axis=1)
        c = np.abs(np.einsum("ij,ij->i", a, b)) / (na * nb)
        return np.degrees(np.arccos(np.clip(c, 0.0, 1.0)))


def compute_fields(result, *, reference_normals=None, sample=None) -> dict[str, np.ndarray]:
    """Every displayable field for one :class:`core.CurvatureResult` (worker thread).

    Parameters
    ----------
    result : core.CurvatureResult
    reference_normals : (N, 3) array or None
        Normals to measure the estimated normals' deviation against (the file's or
        the shape's exact normals).
    sample : core.shapes.Sample or None
        Ground truth; adds the ``err_*`` fields from :func:`core.metrics.point_errors`.

    Returns
    -------
    dict name -> (N,) float64 array (new arrays; NaN where not defined).
    """
    out = {
        "mean": result.mean,
        "gaussian": result.gaussian,
        "k1": result.k1,
        "k2": result.k2,
        "shape_index": result.shape_index,
        "curvedness": result.curvedness,
        "k_point": result.k_point,
        "outlier_score": result.outlier_score,
    }
    if reference_normals is not None:
        out["normal_dev"] = _angle_deg(result.normals, np.asarray(reference_normals, dtype=float))
    if sample is not None:
        import core.metrics

        errors = core.metrics.point_errors(result, sample)
        mapping = {
            "mean": "err_mean",
            "gaussian": "err_gaussian",
            "k1": "err_k1",
            "k2": "err_k2",
            "normal_deg": "err_normal",
            "direction_deg": "err_direction",
        }
        for src, dst in mapping.items():
            if src in errors:
                out[dst] = errors[src]
    return {name: np.array(values, dtype=float, copy=True) for name, values in out.items()}


def robust_limits(values: np.ndarray, *, signed: bool, clip: float = 2.0, floor: float = 0.0) -> tuple[float, float]:
    """Colour limits that ignore the ``clip`` % most extreme values.

    Signed fields get limits symmetric about 0 (so 0 is the neutral colour), never
    narrower than ``±floor`` (so round-off on a plane is not painted as curvature);
    others the [clip, 100 - clip] percentile range. Never returns an empty range.
    """
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return (-1.0, 1.0) if signed else (0.0, 1.0)
    clip = float(min(max(clip, 0.0), 49.0))
    if signed:
        hi = float(np.percentile(np.abs(finite), 100.0 - clip))
        if not hi > 0:
            hi = float(np.max(np.abs(finite)))
        hi = max(hi, float(floor))
        return (-hi, hi) if hi > 0 else (-1.0, 1.0)
    lo, hi = (float(v) for v in np.percentile(finite, [clip, 100.0 - clip]))
    if not hi > lo:
        span = abs(hi) * 0.05 or 1.0
        lo, hi = lo - span, hi + span
    return (lo, hi)


def curvature_floor(name: str, size: float) -> float:
    """Smallest colour range worth showing for a curvature field of a cloud of
    ``size`` (its bounding radius): a radius of curvature 1000 times the cloud."""
    k = 1e-3 / size if size > 0 else 0.0
    return {"mean": k, "k1": k, "k2": k, "curvedness": k, "gaussian": k * k}.get(name, 0.0)


def is_signed(spec: FieldSpec, values: np.ndarray) -> bool:
    """Signed if the spec says so, or if the data turn out to have negative values."""
    if spec.signed:
        return True
    with np.errstate(invalid="ignore"):
        return bool(np.nanmin(values) < 0) if np.isfinite(values).any() else False


def colormap_for(spec: FieldSpec, signed: bool) -> str:
    if signed:
        return DIVERGING
    return ERROR if spec.needs == "truth" else SEQUENTIAL
