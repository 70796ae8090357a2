"""The :class:`Cloud` read from a file, the error every reader raises, and shared helpers."""

from __future__ import annotations

import os
import pathlib
import warnings
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .._memory import available_memory
from .._validate import MIN_POINTS


def file_path(path, *, name: str = "path") -> pathlib.Path:
    """``path`` (str, bytes or os.PathLike) as a :class:`pathlib.Path`; anything else is a
    TypeError naming the argument (``None`` raised os.fspath's message, which names none)."""
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{name} must be a file path (str or os.PathLike), got {type(path).__name__}")
    text = os.fspath(path)
    if isinstance(text, bytes):
        text = os.fsdecode(text)
    if not text or "\0" in text:  # Path("") is the current folder, and a NUL ends a name in the system's calls
        raise ValueError(f"{name} {'is empty' if not text else f'{text!r} holds a NUL byte'}; give a file's name")
    return pathlib.Path(text)


def require_points(path, n: int) -> None:
    """Refuse a file's cloud of ``n`` points when it is too small to estimate
    (:data:`core._validate.MIN_POINTS`), naming the file ``path``; core.estimate's own
    message names no file."""
    if n < MIN_POINTS:
        raise CloudFileError(path, f"has {n} point{'s' * (n != 1)}; an estimate needs at least {MIN_POINTS}")


class CloudFileError(ValueError):
    """A point-cloud file cannot be read or written; the message names the file and the problem.

    Attributes
    ----------
    path : str
        The file, as given.
    problem : str
        What is wrong, without the file name.
    """

    def __init__(self, path, problem: str):
        self.path = str(path)
        self.problem = _elided(problem)
        super().__init__(f"{self.path}: {self.problem}")

    def __reduce__(self):
        return type(self), (self.path, self.problem)


#: the longest problem a message spells out: a file's own text quoted in it (a names line of
#: 9,000 names, a token of a megabyte) is cut in its middle, keeping where and what is allowed
MAX_PROBLEM = 1000


def _elided(problem: str) -> str:
    """``problem`` cut to about :data:`MAX_PROBLEM` characters in its middle, saying how many went."""
    if len(problem) <= MAX_PROBLEM:
        return problem
    head, tail = MAX_PROBLEM * 2 // 3, MAX_PROBLEM // 4
    return f"{problem[:head]} ... [{len(problem) - head - tail:,} characters cut] ... {problem[-tail:]}"


def check_memory(path, need: int, what: str, hint: str = "") -> None:
    """Refuse a file whose declared sizes need ``need`` bytes, more than the memory available:
    "{path}: {what} about X GB, more than the Y GB of memory available{hint}"."""
    available = available_memory()
    if need > available:
        raise CloudFileError(path, f"{what} about {need / 1e9:.3g} GB, more than the {available / 1e9:.3g} GB of "
                                   f"memory available{hint}")


@dataclass(frozen=True, eq=False)
class Cloud:
    """Points (and optional normals and per-point scalars) read from a file.

    Attributes
    ----------
    points : (N, 3) float64 C-contiguous array.
    normals : (N, 3) float64 array, or None when the file has none. Kept as stored
        (not renormalised; zero-length normals are left for the estimator to reject).
    path : the file read, or None.
    format : short format name, e.g. ``"ply"``, ``"xyz"``, ``"las"``.
    fields : other per-point properties, name -> (N,) array in the file's dtype
        (text formats give float64). May be empty.
    viewpoints : (N, 3) float64 array, or None: where each point was seen from (E57: the
        scanner position of its scan), in the points' coordinates.
    """

    points: np.ndarray
    normals: np.ndarray | None = None
    path: pathlib.Path | None = None
    format: str = ""
    fields: dict = field(default_factory=dict)
    viewpoints: np.ndarray | None = None

    def __post_init__(self):
        pts = np.ascontiguousarray(self.points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ValueError(f"points must have shape (N, 3), got shape {pts.shape}")
        object.__setattr__(self, "points", pts)
        if self.normals is not None:
            nrm = np.ascontiguousarray(self.normals, dtype=np.float64)
            if nrm.shape != pts.shape:
                raise ValueError(f"normals must have shape {pts.shape} to match points, got shape {nrm.shape}")
            object.__setattr__(self, "normals", nrm)
        if self.viewpoints is not None:
            views = np.ascontiguousarray(self.viewpoints, dtype=np.float64)
            if views.shape != pts.shape:
                raise ValueError(f"viewpoints must have shape {pts.shape} to match points, got shape {views.shape}")
            object.__setattr__(self, "viewpoints", views)
        for name, values in self.fields.items():
            if np.shape(values)[:1] != (len(pts),):
                raise ValueError(f"field {name!r} must have {len(pts)} rows, got shape {np.shape(values)}")
        if self.path is not None:
            object.__setattr__(self, "path", pathlib.Path(self.path))

    def __len__(self) -> int:
        return len(self.points)

    @property
    def n_points(self) -> int:
        return len(self.points)

    def __repr__(self) -> str:
        return (
            f"Cloud(n_points={len(self)}, format={self.format!r}, normals={self.normals is not None}, "
            f"fields={list(self.fields)}, path={str(self.path) if self.path else None!r})"
        )


class RawCloud(NamedTuple):
    """What a format reader returns, before validation: arrays in any numeric dtype."""

    points: np.ndarray
    normals: np.ndarray | None
    fields: dict
    viewpoints: np.ndarray | None = None


class Scan(NamedTuple):
    """One scan of a file of registered scans (E57, PTX): its points in world coordinates
    (m, 3), its fields (name -> (m,) array) and its scanner position (3,), in world coordinates."""

    points: np.ndarray
    fields: dict
    viewpoint: np.ndarray


def joined_scans(scans, names) -> RawCloud:
    """The ``scans`` one after another: the fields ``names`` (every scan with points has
    them), ``scan`` (int32, the scan's index) and each point's viewpoint, its scan's scanner
    position."""
    sizes = [len(scan.points) for scan in scans]
    fields = {name: np.concatenate([scan.fields[name] for scan in scans if len(scan.points)]) for name in names}
    fields["scan"] = np.repeat(np.arange(len(scans), dtype=np.int32), sizes)
    viewpoints = np.repeat(np.array([scan.viewpoint for scan in scans]), sizes, axis=0)
    return RawCloud(np.concatenate([scan.points for scan in scans]), None, fields, viewpoints)


# Property names meaning a normal component, lower-cased, in x, y, z order.
NORMAL_NAMES = (
    ("nx", "ny", "nz"),
    ("normal_x", "normal_y", "normal_z"),
    ("normalx", "normaly", "normalz"),
    ("n_x", "n_y", "n_z"),
)


def find_normals(names) -> tuple[str, str, str] | None:
    """The three names (as spelled in ``names``) holding normal x, y, z, or None."""
    lower = {str(n).lower(): n for n in names}
    for triple in NORMAL_NAMES:
        if all(t in lower for t in triple):
            return tuple(lower[t] for t in triple)
    return None


def split_components(name: str, values: np.ndarray) -> dict:
    """Per-point scalar fields from an (N,) or (N, C) array: C = 3 gives name_x/_y/_z."""
    values = np.asarray(values)
    if values.ndim == 1:
        return {name: values}
    values = values.reshape(len(values), -1)
    if values.shape[1] == 1:
        return {name: values[:, 0]}
    suffixes = "xyz" if values.shape[1] == 3 else range(values.shape[1])
    return {f"{name}_{s}": values[:, i] for i, s in enumerate(suffixes)}


def finalize(raw: RawCloud, path: pathlib.Path, fmt: str, *, drop_nonfinite: bool) -> Cloud:
    """Validate a reader's output and build the :class:`Cloud` (new arrays, inputs untouched)."""
    points = np.array(raw.points, dtype=np.float64, order="C")
    if points.ndim != 2 or points.shape[1] != 3:
        raise CloudFileError(path, f"expected (N, 3) coordinates, got shape {points.shape}")
    n = len(points)
    if n == 0:
        raise CloudFileError(path, "contains no points")
    normals = None if raw.normals is None else np.array(raw.normals, dtype=np.float64, order="C")
    fields = {name: np.array(values) for name, values in raw.fields.items()}
    views = None if raw.viewpoints is None else np.array(raw.viewpoints, dtype=np.float64, order="C")
    finite = np.isfinite(points).all(axis=1)
    if not finite.all():
        bad = n - int(finite.sum())
        if not drop_nonfinite:
            raise CloudFileError(
                path,
                f"{bad} of {n} points have non-finite coordinates (NaN or inf), first at point "
                f"{int(np.flatnonzero(~finite)[0])}; pass drop_nonfinite=True to drop them",
            )
        if bad == n:
            raise CloudFileError(path, f"all {n} points have non-finite coordinates (NaN or inf)")
        warnings.warn(f"{path}: dropped {bad} of {n} points with non-finite coordinates", UserWarning, stacklevel=3)
        points = points[finite]
        normals = None if normals is None else normals[finite]
        views = None if views is None else views[finite]
        fields = {name: values[finite] for name, values in fields.items()}
    return Cloud(points=points, normals=normals, path=path, format=fmt, fields=fields, viewpoints=views)


def is_padding(tail, allowed: bytes = b" \t\r\n\0") -> bool:
    """Whether the bytes after a binary file's last record are a writer's padding: NULs and
    white space (a newline) only by default, or none."""
    return not bytes(tail).strip(allowed)


def remaining_bytes(f) -> int:
    """Bytes between the position of the open binary file ``f`` and its end."""
    return os.fstat(f.fileno()).st_size - f.tell()


def format_number(value) -> str:
    """``value`` for a message: an integral number exactly (4294967296, not 4.29497e+09), others with %g."""
    value = float(value)
    return str(int(value)) if value.is_integer() and abs(value) < 1e20 else f"{value:g}"
