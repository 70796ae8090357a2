"""Writing point clouds and curvature results: PLY (binary), text or VTK XML PolyData, always atomically."""

from __future__ import annotations

import os
import pathlib
import re
from collections.abc import Mapping
from functools import partial
from typing import BinaryIO

import numpy as np
from numpy.typing import ArrayLike

from . import ply, text, vtp_write
from .atomic import atomic_write
from .cloud import NORMAL_NAMES, CloudFileError, file_path
from .formats import WRITE_FORMATS, resolve_format

_WRITERS = {
    "ply": ply.write_ply,
    "csv": partial(text.write_text, delimiter=",", header=True),
    "xyz": partial(text.write_text, delimiter=" ", header=False),
    "txt": partial(text.write_text, delimiter=" ", header=False),
    "vtp": vtp_write.write_vtp,
}
assert set(_WRITERS) == {ext[1:] for ext in WRITE_FORMATS}

_RESERVED = ("x", "y", "z", "nx", "ny", "nz")
_NAME = re.compile(r'^[^\s,;"#]+$')
#: the per-point attributes of a curvature result written by :func:`write_result`, in order
RESULT_FIELDS = ("k1", "k2", "e1", "e2", "gaussian", "mean", "valid")
#: the per-point flags written after them, where the result has them: name in the file ->
#: attribute (the neighbourhood size and model degree chosen, the border of the sampled
#: surface, the orientation's confidence, outliers, creases, the sampling anisotropy and
#: its stripe flag, the point type code of :data:`core.TYPE_NAMES`, -1 where invalid)
RESULT_FLAGS = {"k": "k_point", "degree": "degree_point", "border": "border",
                "orientation_confidence": "orientation_confidence", "outlier": "outlier",
                "outlier_score": "outlier_score", "crease": "crease", "anisotropy": "anisotropy",
                "striped": "striped", "point_type": "point_type"}


def write_cloud(path: str | os.PathLike | BinaryIO, points: ArrayLike, *, normals: ArrayLike | None = None,
                fields: Mapping[str, ArrayLike] | None = None, format: str | None = None) -> pathlib.Path | BinaryIO:
    """Write points (with optional normals and per-point fields) to a PLY, text or VTP file.

    Parameters
    ----------
    path : str, path-like, or a binary stream (then ``format`` is required)
    points : (N, 3) array_like
    normals : (N, 3) array_like, optional
    fields : dict, optional
        name -> (N,) or (N, 3) array (numeric or bool); an (N, 3) array is written as
        name_x, name_y, name_z. Names must not contain whitespace, ``,;"#``, nor equal
        x y z nx ny nz or each other ignoring case.
    format : {"ply", "csv", "xyz", "txt", "vtp"}, optional
        By default from the extension. PLY is binary little-endian (bool -> uint8); CSV has
        a header line; XYZ/TXT are space-separated columns, preceded by a ``# names`` line
        only when there is more than x y z [nx ny nz]; VTP (ParaView) is binary with a vertex
        cell per point, normals as its Normals and (N, 3) fields as 3-component arrays.

    Returns
    -------
    pathlib.Path
        ``path``. The file is written to a temporary file first and renamed over ``path``:
        on failure (or SIGTERM) no partial file is left and an existing file is untouched.
        A device or FIFO is written into; a read-only existing file is refused.

    Raises
    ------
    ValueError
        Invalid ``points``, ``normals`` or ``fields``.
    CloudFileError
        Unsupported format, or the file cannot be written (missing directory, permissions).
    """
    if hasattr(path, "write"):  # an open binary stream, e.g. sys.stdout.buffer
        if format is None:
            raise ValueError("format= is required when writing to a stream (e.g. format='csv')")
        fmt = resolve_format(pathlib.Path("<stream>"), format, WRITE_FORMATS, "writing")
        _WRITERS[fmt](path, _columns_for(fmt, points, normals, fields))
        return path
    path = file_path(path)
    fmt = resolve_format(path, format, WRITE_FORMATS, "writing")
    columns = _columns_for(fmt, points, normals, fields)
    try:
        with atomic_write(path) as f:
            _WRITERS[fmt](f, columns)
    except OSError as exc:
        folder = path.parent
        if isinstance(exc, FileNotFoundError) and not folder.is_dir():
            raise CloudFileError(path, f"cannot be written: {exc.strerror} (the folder {str(folder)!r} does not "
                                       "exist)") from exc
        raise CloudFileError(path, f"cannot be written: {exc.strerror or exc}") from exc
    return path


def write_result(path: str | os.PathLike | BinaryIO, result, *, format: str | None = None) -> pathlib.Path | BinaryIO:
    """Write a curvature result: x y z nx ny nz k1 k2 e1_x e1_y e1_z e2_x e2_y e2_z gaussian mean valid,
    then its flags (:data:`RESULT_FLAGS`: k degree border orientation_confidence outlier
    outlier_score crease anisotropy striped point_type; booleans as 0/1).

    ``result`` is anything with the attributes ``points``, ``normals`` and
    :data:`RESULT_FIELDS` (e.g. :class:`core.CurvatureResult`); of the flags, those it has
    are written. See :func:`write_cloud` for ``path`` and ``format``.
    """
    missing = [name for name in ("points", "normals", *RESULT_FIELDS) if not hasattr(result, name)]
    if missing:
        raise TypeError(f"result must have attributes points, normals, {', '.join(RESULT_FIELDS)}; "
                        f"{type(result).__name__} lacks {', '.join(missing)}")
    fields = {name: getattr(result, name) for name in RESULT_FIELDS}
    fields.update({name: getattr(result, attr) for name, attr in RESULT_FLAGS.items()
                   if getattr(result, attr, None) is not None})
    return write_cloud(path, result.points, normals=result.normals, fields=fields, format=format)


def _numeric(values, name: str, shapes: str) -> np.ndarray:
    arr = np.asarray(values)
    if not (arr.dtype == bool or np.issubdtype(arr.dtype, np.integer) or np.issubdtype(arr.dtype, np.floating)):
        raise ValueError(f"{name} must be a numeric or bool array of shape {shapes}, got dtype {arr.dtype}")
    return arr


def _columns(points, normals, fields) -> list:
    """[(name, (N,) array)] in file order, validated; new arrays, inputs untouched."""
    pts = _numeric(points, "points", "(N, 3)")
    if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) == 0:
        raise ValueError(f"points must have shape (N, 3) with N >= 1, got shape {pts.shape}")
    n = len(pts)
    pts = pts.astype(np.float64)
    columns = [(c, pts[:, i]) for i, c in enumerate("xyz")]
    if normals is not None:
        nrm = _numeric(normals, "normals", f"({n}, 3)")
        if nrm.shape != (n, 3):
            raise ValueError(f"normals must have shape ({n}, 3) to match points, got shape {nrm.shape}")
        nrm = nrm.astype(np.float64)
        columns += [(c, nrm[:, i]) for i, c in enumerate(("nx", "ny", "nz"))]
    return columns + _field_columns(fields, n)


def _field_columns(fields, n: int) -> list:
    """The columns of the extra per-point ``fields`` (name -> (N,) or (N, 3) array)."""
    if fields is not None and not isinstance(fields, Mapping):
        raise ValueError(f"fields must be a dict of name -> array, got {type(fields).__name__}")
    extra = []
    for name, values in (fields or {}).items():
        extra += _field_column(name, values, n)
    lower = [name.lower() for name, _ in extra]
    bad = sorted({name for name, _ in extra if lower.count(name.lower()) > 1 or name.lower() in _RESERVED})
    if bad:
        raise ValueError(f"field names {', '.join(bad)} clash with x y z nx ny nz or with each other "
                         "(names are compared ignoring case)")
    return extra


def _columns_for(fmt: str, points, normals, fields) -> list:
    """The columns to write (:func:`_columns`), their names checked for ``fmt``
    (:func:`_check_names_for`) before any file is opened."""
    columns = _columns(points, normals, fields)
    _check_names_for(fmt, columns)
    return columns


def _check_names_for(fmt: str, columns) -> None:
    """Refuse, before any file is opened, field names the format cannot hold (non-ASCII in
    a PLY header) or that its readers would take for the normals (normal_x normal_y normal_z,
    n_x ... without normals=; a VTP array called Normals or normal): the field would come back
    as the cloud's normals, or be lost behind them."""
    names = [name for name, _ in columns]
    lower = [name.lower() for name in names]
    for triple in NORMAL_NAMES if "nx" not in names else ():
        if set(triple) <= set(lower):
            raise ValueError(f"fields {' '.join(triple)} would be read back as the normals, not as fields; pass "
                             "normals as normals=, or rename the field")
    if fmt == "ply" and not all(name.isascii() for name in names):
        bad = next(name for name in names if not name.isascii())
        raise ValueError(f"field name {bad!r} is not ASCII, which a PLY header cannot hold; rename it, or write "
                         ".csv, .xyz or .vtp")
    if fmt == "vtp":
        _check_vtp_names(columns)


def _check_vtp_names(columns) -> None:
    """A VTP array called Normals or normal, other than the normals: the reader takes it for them."""
    fields = [column for column in columns[3:] if column[0] not in ("nx", "ny", "nz")]
    if {"normals", "normal"} & {name.lower() for name, _ in vtp_write.point_arrays(columns[:3] + fields)}:
        raise ValueError("a field called normals or normal (or its _x _y _z columns) would be the VTP file's "
                         "normals; pass normals as normals=, or rename the field")


def _field_column(name, values, n: int) -> list:
    """One field as one column, or three (name_x, name_y, name_z) for an (N, 3) array."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(f"field name {name!r} is invalid; use a non-empty name without whitespace or ,;\"#")
    arr = _numeric(values, f"field {name!r}", f"({n},) or ({n}, 3)")
    if arr.dtype == np.float16:
        arr = arr.astype(np.float32)
    if arr.shape == (n,):
        return [(name, arr.copy())]
    if arr.shape == (n, 3):
        return [(f"{name}_{c}", arr[:, i].copy()) for i, c in enumerate("xyz")]
    raise ValueError(f"field {name!r} must have shape ({n},) or ({n}, 3), got shape {arr.shape}")
