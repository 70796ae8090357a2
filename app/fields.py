"""Scalar fields the viewer can colour the cloud by, and their colour limits.

numpy only (runs on the worker thread for :func:`compute_fields`, on the GUI thread
for :func:`robust_limits`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from core.anisotropy import STRIPED
from core.tuning import JET_DEGREES

__all__ = ["FieldSpec", "FIELDS", "ALIASES", "resolve_field", "compute_fields", "robust_limits", "curvature_floor",
           "is_signed", "colormap_for", "Colouring", "colouring", "RGB", "FILE_PREFIX", "is_file_field"]

#: Colormaps: diverging centred on 0 for signed fields, sequential otherwise.
DIVERGING = "RdBu_r"
SEQUENTIAL = "viridis"
ERROR = "magma"
#: A field that may be signed (k1, k2) is drawn diverging only when over this share of its
#: values lie on the minority side of 0: k1 on a convex shape (an ellipsoid: all > 0) gets
#: a sequential map over its own range, k1 on a torus (29 % < 0... of k2) a diverging one.
MINORITY_SIGN = 0.05
#: Qualitative maps of the categorical fields (a file's small integers: scan index, class),
#: one colour a value: the first up to 10 values, the second up to 20.
CATEGORICAL = ("tab10", "tab20")
#: The field that draws a file's own colours, and the prefix of its other fields
#: ("file:intensity"); these come with the cloud (:mod:`app.file_fields`), not the estimate.
RGB = "rgb"
FILE_PREFIX = "file:"


@dataclass(frozen=True)
class FieldSpec:
    """How to show one field.

    ``signed`` fields (True) get a diverging colormap with limits symmetric about 0; None
    means "signed if the data are" (k1, k2: see :data:`MINORITY_SIGN`). ``needs`` is ""
    (always there), "truth" (synthetic shapes only) or "reference" (needs reference normals:
    from the file or the shape). ``scale`` is "linear", "log" (sizes such as the chosen k)
    or "threshold": a diverging map centred on ``threshold`` over [0, 2 x threshold] (the
    outlier score: inliers blue, the threshold white, outliers red). ``span``, where set,
    is the fixed range of a bounded field (the sampling anisotropy, [0, 1]).

    A file's own per-point data (:mod:`app.file_fields`) have ``needs`` "file" and are never
    drawn diverging; ``scale`` "categorical" draws small integers (a scan index) one colour a
    value over ``span`` (lowest - 0.5, highest + 0.5), "rgb" the file's colours as they are.
    """

    name: str
    label: str  # colour-bar title and combo text
    signed: bool | None
    needs: str = ""
    unit: str = ""
    scale: str = "linear"
    threshold: float = 0.0
    span: tuple | None = None

    @property
    def title(self) -> str:
        return f"{self.label} [{self.unit}]" if self.unit else self.label


FIELDS: dict[str, FieldSpec] = {
    f.name: f
    for f in (
        FieldSpec("mean", "Mean curvature H", True),
        FieldSpec("gaussian", "Gaussian curvature K", True),
        FieldSpec("k1", "Max. principal curvature k1", None),
        FieldSpec("k2", "Min. principal curvature k2", None),
        FieldSpec("shape_index", "Shape index", True),
        FieldSpec("curvedness", "Curvedness", False),
        FieldSpec("k_point", "Neighbourhood size k", False, scale="log"),
        FieldSpec("degree_point", "Polynomial degree of the fit", False,
                  span=(1.0, float(max(3, *(d for d, _ in JET_DEGREES))))),  # NR's normal field 1-3, the jets 3+
        FieldSpec("outlier_score", "Outlier score", False, scale="threshold", threshold=4.0),
        FieldSpec("anisotropy", f"Anisotropy (> {STRIPED:g}: stripes)", False, span=(0.0, 1.0)),
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
    """Canonical field name for ``name`` (case-insensitive, aliases allowed). A file's
    fields are known once it is read: "rgb" (its colours) and "file:NAME" (NAME as given)
    are taken here and checked against the file then (:func:`app.file_fields.find`)."""
    key = str(name).strip()
    low = key.lower()
    if key in FIELDS:
        return key
    if low in FIELDS:
        return low
    if low in ALIASES:
        return ALIASES[low]
    if low == RGB or (low.startswith(FILE_PREFIX) and key[len(FILE_PREFIX):].strip()):
        return RGB if low == RGB else FILE_PREFIX + key[len(FILE_PREFIX):].strip()
    valid = ", ".join(list(FIELDS) + [a.upper() if len(a) == 1 else a for a in ALIASES])
    raise ValueError(f"field {name!r} is unknown; valid fields: {valid}, and a file's own {RGB} (its colours) "
                     f"and {FILE_PREFIX}NAME (its field NAME: intensity, scan, ...)")


def is_file_field(name) -> bool:
    """Whether ``name`` is a field of the file rather than of the estimate ("rgb", "file:...")."""
    return isinstance(name, str) and (name == RGB or name.startswith(FILE_PREFIX))


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
        "k_point": np.where(np.asarray(result.k_point) > 0, result.k_point, np.nan),  # -1: no fit, not a size
        "degree_point": np.where(np.asarray(result.degree_point) > 0, result.degree_point, np.nan),  # -1: none
        "outlier_score": result.outlier_score,
        "anisotropy": result.anisotropy,
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


#: Above this many values the automatic limits are percentiles of a fixed random subset:
#: the rank error of a 98th percentile from 200k values is ~0.03 %, and it saves the GUI
#: thread ~50 ms per recolour of a 1M-point cloud (measured: np.percentile on 1M, 2 cores).
LIMIT_SAMPLE = 200_000


@lru_cache(maxsize=4)
def _random_index(n: int, m: int) -> np.ndarray:
    # with replacement: as unbiased a sample; the loader draws it (prepare_sampling), not the GUI
    return np.sort(np.random.default_rng(0).integers(0, n, size=m))


def prepare_sampling(n: int) -> None:
    """Draw the sample index of a cloud of ``n`` points ahead (the loader thread calls it:
    ~15 ms at 1M, seen as a GUI-thread step of the first colouring in the 1M profile)."""
    if n > LIMIT_SAMPLE:
        _random_index(int(n), LIMIT_SAMPLE)


def subsample(values: np.ndarray, m: int) -> np.ndarray:
    """``values`` itself, or a fixed random sample of ``m`` of them (drawn with replacement;
    the same for every array of that length; random, not strided: a scan's invalid rows can
    repeat with a period)."""
    return values if len(values) <= m else values[_random_index(len(values), int(m))]


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


def is_signed(spec: FieldSpec, values: np.ndarray, floor: float = 0.0) -> bool:
    """Signed if the spec says so; for a may-be-signed spec (None) if more than
    :data:`MINORITY_SIGN` of the values beyond ``floor`` have the minority sign; otherwise if
    the data turn out to have negative values."""
    if spec.signed:
        return True
    if spec.needs == "file":  # a file's intensity or height: its own range, whatever its sign
        return False
    finite = np.asarray(values, dtype=float)
    finite = finite[np.isfinite(finite)]
    if not finite.size:
        return False
    if spec.signed is None:
        pos, neg = np.mean(finite > floor), np.mean(finite < -floor)
        return bool(min(pos, neg) > MINORITY_SIGN)
    return bool(finite.min() < 0)


def colormap_for(spec: FieldSpec, signed: bool) -> str:
    if spec.scale == "categorical":
        return CATEGORICAL[bands(spec) > 10]
    if signed or spec.scale == "threshold":
        return DIVERGING
    return ERROR if spec.needs == "truth" else SEQUENTIAL


def bands(spec: FieldSpec) -> int:
    """Colours of a categorical field (one a value of its span), 0 for a continuous one."""
    return int(round(spec.span[1] - spec.span[0])) if spec.scale == "categorical" else 0


@dataclass(frozen=True)
class Colouring:
    """How a field is drawn: colour limits, colour map, logarithmic scale, and ``bands``
    colours (a categorical field's, one a value) or 0 (a continuous map)."""

    clim: tuple
    cmap: str
    log: bool = False
    bands: int = 0


def colouring(spec: FieldSpec, values: np.ndarray, *, clip: float = 2.0, floor: float = 0.0,
              clim=None) -> Colouring:
    """Limits and map that fit the field (automatic limits unless ``clim`` is given):
    diverging and centred on 0 for signed fields, sequential over their own range for
    one-signed ones (errors and angles from 0), the outlier score around its threshold,
    sizes on a log scale."""
    values = np.asarray(values, dtype=float)
    sample = subsample(values, LIMIT_SAMPLE)
    signed = is_signed(spec, sample, floor)
    cmap = colormap_for(spec, signed)
    log = spec.scale == "log"
    if clim is not None:
        lo, hi = clim
        return Colouring((lo, hi), cmap, log and lo > 0)
    if spec.scale == "threshold":
        return Colouring((0.0, 2.0 * spec.threshold), cmap)
    if spec.span is not None:
        return Colouring(spec.span, cmap, bands=bands(spec))
    if log:
        positive = values[np.isfinite(values) & (values > 0)]
        if positive.size:
            lo, hi = float(positive.min()), float(positive.max())
            return Colouring((lo, hi if hi > lo else 2.0 * lo), cmap, True)
    lo, hi = robust_limits(sample, signed=signed, clip=clip, floor=floor)
    if not signed and (spec.unit == "deg" or spec.needs == "truth"):
        lo, hi = 0.0, max(hi, 1e-12)  # errors and angles start at 0
    return Colouring((lo, hi), cmap)
