"""Reading point clouds: :func:`read_cloud` and :func:`describe`."""

from __future__ import annotations

import os
import pathlib
import struct

import numpy as np

from . import e57, las, mesh, off, pcd, ply, ptx, text, vtk
from .sniff import refuse_misread_text, refuse_other_content
from .._validate import check_bool
from .cloud import Cloud, CloudFileError, RawCloud, file_path, finalize
from .formats import READ_FORMATS, resolve_format
from .text_tail import warn_if_text_cut

_READERS = {
    "ply": ply.read_ply,
    "xyz": lambda path: text.read_text(path, "xyz"),
    "pts": lambda path: text.read_text(path, "pts"),
    "txt": lambda path: text.read_text(path, "txt"),
    "csv": lambda path: text.read_text(path, "csv"),
    "pcd": pcd.read_pcd,
    "obj": mesh.read_obj,
    "stl": mesh.read_stl,
    "off": off.read_off,
    "vtk": vtk.read_vtk,
    "vtp": vtk.read_vtp,
    "las": las.read_las,
    "laz": las.read_las,
    "e57": e57.read_e57,
    "ptx": ptx.read_ptx,
}
assert set(_READERS) == {ext[1:] for ext in READ_FORMATS}


def read_cloud(path: str | os.PathLike, *, format: str | None = None, drop_nonfinite: bool = False) -> Cloud:
    """Read the points (and normals and other per-point properties) of a file.

    Parameters
    ----------
    path : str or path-like
    format : str, optional
        One of the :data:`READ_FORMATS` names without the dot (``"ply"``, ``"xyz"``, ...);
        by default chosen from the file extension (case-insensitive).
    drop_nonfinite : bool, default False
        Drop points with NaN/inf coordinates (with a warning saying how many) instead of
        raising (True or False only).

    Returns
    -------
    Cloud

    Raises
    ------
    CloudFileError
        Missing, empty, truncated or malformed file, unknown format, no points, or
        non-finite coordinates; the message names the file and the problem.
    """
    drop_nonfinite = check_bool(drop_nonfinite, name="drop_nonfinite")
    path, fmt = _path_and_format(path, format)
    return finalize(_read_raw(path, fmt), path, fmt, drop_nonfinite=drop_nonfinite)


def describe(path: str | os.PathLike, *, format: str | None = None) -> dict:
    """A summary of a point-cloud file, for an ``info`` command.

    Returns
    -------
    dict with keys ``path``, ``format``, ``file_size`` (bytes), ``n_points``,
    ``n_nonfinite`` (points with NaN/inf coordinates), ``has_normals``, ``bbox_min`` and
    ``bbox_max`` (lists of 3 floats over the finite points, None if there are none),
    ``bbox_diagonal`` (float or None), ``fields`` (names of the other properties) and
    ``n_viewpoints`` (the distinct scanner positions an E57 or PTX file gives its points, 0 for
    a file without them).
    """
    path, fmt = _path_and_format(path, format)
    raw = _read_raw(path, fmt)
    points = np.asarray(raw.points, dtype=np.float64).reshape(-1, 3)
    if len(points) == 0:
        raise CloudFileError(path, "contains no points")
    finite = points[np.isfinite(points).all(axis=1)]
    low = finite.min(axis=0) if len(finite) else None
    high = finite.max(axis=0) if len(finite) else None
    return {
        "path": str(path),
        "format": fmt,
        "file_size": path.stat().st_size,
        "n_points": len(points),
        "n_nonfinite": len(points) - len(finite),
        "has_normals": raw.normals is not None,
        "bbox_min": None if low is None else low.tolist(),
        "bbox_max": None if high is None else high.tolist(),
        "bbox_diagonal": None if low is None else float(np.linalg.norm(high - low)),
        "fields": list(raw.fields),
        "n_viewpoints": 0 if raw.viewpoints is None else len(np.unique(np.asarray(raw.viewpoints), axis=0)),
    }


def _path_and_format(path, format):
    path = readable_file(path)
    fmt = resolve_format(path, format, READ_FORMATS, "reading")
    if path.stat().st_size == 0:
        raise CloudFileError(path, "is empty (0 bytes)")
    return path, fmt


def readable_file(path):
    """``path`` as a Path, refused (:class:`CloudFileError`) unless it names a regular file."""
    path = file_path(path)
    if not path.exists():
        if path.is_symlink():  # exists() follows the link
            raise CloudFileError(path, f"is a symbolic link to {os.readlink(path)!r}, which cannot be followed (its "
                                       "target is missing, or the links form a loop)")
        raise CloudFileError(path, "no such file")
    if path.is_dir():
        raise CloudFileError(path, "is a directory, not a file")
    if not path.is_file():  # a FIFO or device has no size to check: it was reported "empty (0 bytes)"
        raise CloudFileError(path, "is not a regular file (a pipe or device); save it to a file first, or pipe it "
                                   "to darboux-cli's standard input (-)")
    return path


#: the extra that installs the optional package a format needs
_EXTRAS = {"las": "las", "laz": "las", "vtk": "viewer", "vtp": "viewer"}  # E57 names its own (core.io.e57)


def _read_raw(path, fmt) -> RawCloud:
    try:
        refuse_other_content(path, fmt)
        refuse_misread_text(path, fmt)
        with np.errstate(all="ignore"):  # a NaN or inf cast (a float32 sNaN, 1e308 as float32) is finalize's to flag
            raw = _READERS[fmt](path)
        warn_if_text_cut(path, fmt)
        return raw
    except ModuleNotFoundError as exc:  # an optional reader dependency is not installed
        extra = _EXTRAS.get(fmt)
        hint = f"pip install 'darboux[{extra}]'" if extra else f"pip install {exc.name}"
        raise CloudFileError(path, f"reading .{fmt} files needs the Python package {exc.name!r}; {hint}") from None
    except OSError as exc:
        raise CloudFileError(path, f"cannot be read: {exc.strerror or exc}") from exc
    except CloudFileError:
        raise
    except (ValueError, IndexError, OverflowError, struct.error) as exc:  # a reader's parse of damaged data
        raise CloudFileError(path, f"malformed .{fmt} data: {exc}") from None
