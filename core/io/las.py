"""LAS / LAZ lidar files via laspy (LAZ needs a backend such as lazrs).

The scaled coordinates are the points; every other point dimension (intensity,
classification, gps_time, red, ...) becomes a field; extra-bytes dimensions named
nx/ny/nz or normal_x/... are the normals.
"""

from __future__ import annotations

import os

import numpy as np

from .cloud import CloudFileError, RawCloud, find_normals, split_components


def read_las(path) -> RawCloud:
    """Points, normals (from extra bytes, if any) and all other point dimensions."""
    import laspy

    try:
        with laspy.open(path) as reader:
            header = reader.header
            compressed = header.are_points_compressed
            if compressed and not laspy.LazBackend.detect_available():
                raise CloudFileError(
                    path, "is LAZ-compressed but no LAZ backend is installed; run `pip install lazrs` "
                    "(or `pip install laspy[lazrs]`)"
                )
            _check_scales(header, path)
            need = header.offset_to_point_data + header.point_count * header.point_format.size
            if not compressed and os.path.getsize(path) < need:
                raise CloudFileError(
                    path, f"truncated: the header declares {header.point_count} points ({need} bytes) but the file "
                    f"has {os.path.getsize(path)} bytes"
                )
            las = reader.read()
    except CloudFileError:
        raise
    except (laspy.errors.LaspyException, ValueError, EOFError) as exc:
        raise CloudFileError(path, f"not a readable LAS/LAZ file: {exc}") from None
    except RuntimeError as exc:  # lazrs.LazrsError: corrupt or truncated LAZ chunks
        if type(exc).__module__.split(".")[0] != "lazrs":
            raise
        raise CloudFileError(path, f"corrupt or truncated LAZ data: {exc}") from None
    points = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])
    names = [n for n in las.point_format.dimension_names if n not in ("X", "Y", "Z")]
    nrm = find_normals(names)
    normals = None if nrm is None else np.column_stack([np.asarray(las[n], dtype=np.float64) for n in nrm])
    fields = {}
    for name in names:
        if name not in (nrm or ()):
            fields.update(split_components(name, np.array(las[name])))
    return RawCloud(points, normals, fields)


def _check_scales(header, path) -> None:
    """Coordinates are integers x scale + offset: a zero or non-finite scale (or offset)
    would put every point on the offset or at NaN."""
    scales, offsets = np.asarray(header.scales, dtype=float), np.asarray(header.offsets, dtype=float)
    if not (np.isfinite(scales).all() and (scales != 0).all() and np.isfinite(offsets).all()):
        raise CloudFileError(
            path, f"invalid header: coordinate scales {scales.tolist()} and offsets {offsets.tolist()} must be finite "
            "and the scales non-zero",
        )
