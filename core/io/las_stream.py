"""LAS / LAZ in bounded memory: read points in chunks, write results chunk by chunk.

For scans larger than memory (:mod:`core.tiled`): :func:`open_las` checks the header
(point count, a zero scale, a missing LAZ backend, a truncated LAS) before any work is
done; :func:`iter_las` yields the scaled coordinates (and normals stored as extra bytes)
``chunk`` points at a time (:func:`iter_records`: the raw point records, for other
dimensions); :class:`LasResultWriter` writes a curvature result as LAZ/LAS
with one extra-bytes dimension per result property, named as in the PLY output
(``nx ny nz k1 k2 e1_x .. e2_z gaussian mean valid k``), readable by laspy, PDAL and
CloudCompare.
"""

from __future__ import annotations

import os
import struct
from dataclasses import dataclass

import numpy as np

from .cloud import CloudFileError, find_normals
from .las import check_record_counts, rust_panics_refused
from .las_open import open_reader, unreadable
from .write import RESULT_FLAGS

#: points per chunk read or written (about 30 MB of float64 coordinates)
CHUNK = 1_000_000
#: result dimensions in file order (the flags named as :data:`core.io.write.RESULT_FLAGS`);
#: float64 except the flags' types in _TYPES
RESULT_DIMS = ("nx", "ny", "nz", "k1", "k2", "e1_x", "e1_y", "e1_z", "e2_x", "e2_y", "e2_z",
               "gaussian", "mean", "valid", "k", "degree", "border", "orientation_confidence", "outlier",
               "outlier_score", "crease", "anisotropy", "striped")
_TYPES = {"valid": np.uint8, "k": np.int32, "degree": np.int8, "border": np.uint8, "outlier": np.uint8,
          "crease": np.uint8, "striped": np.uint8, "orientation_confidence": np.float32,
          "outlier_score": np.float32, "anisotropy": np.float32}


@dataclass(frozen=True)
class LasInfo:
    """What the header of a LAS/LAZ file says: point count, bounds, scales, normals."""

    path: str
    count: int
    mins: np.ndarray
    maxs: np.ndarray
    scales: np.ndarray
    offsets: np.ndarray
    normals: tuple | None  # the three dimension names holding normals, if any
    version: str
    dims: tuple = ()  # every dimension name but X, Y, Z (standard and extra bytes)
    layered: bool = False  # LAZ of point format >= 6: coordinates decompress apart from the rest


def open_las(path) -> LasInfo:
    """Read and check the header of a LAS/LAZ file (nothing else is read)."""
    import laspy

    check_record_counts(path)
    try:
        with rust_panics_refused(path), open_reader(path) as reader:
            h = reader.header
            if h.are_points_compressed and not laspy.LazBackend.detect_available():
                raise CloudFileError(path, "is LAZ-compressed but no LAZ backend is installed; run `pip install lazrs`")
            need = h.offset_to_point_data + h.point_count * h.point_format.size
            if not h.are_points_compressed and os.path.getsize(path) < need:
                raise CloudFileError(path, f"truncated: the header declares {h.point_count} points ({need} bytes) "
                                           f"but the file has {os.path.getsize(path)} bytes")
            scales = np.asarray(h.scales, dtype=float)
            if not (np.isfinite(scales).all() and (scales != 0).all()):
                raise CloudFileError(path, f"has an invalid coordinate scale {scales.tolist()} in its header "
                                           "(every scale must be finite and non-zero)")
            names = [n for n in h.point_format.dimension_names if n not in ("X", "Y", "Z")]
            return LasInfo(str(path), int(h.point_count), np.asarray(h.mins, float), np.asarray(h.maxs, float),
                           scales, np.asarray(h.offsets, float), find_normals(names), str(h.version),
                           tuple(names), bool(h.are_points_compressed and h.point_format.id >= 6))
    except CloudFileError:
        raise
    except (laspy.errors.LaspyException, ValueError, EOFError, OSError, struct.error) as exc:
        raise unreadable(path, exc) from None


def iter_las(path, *, chunk: int = CHUNK):
    """Yield ``(start, points, normals)`` chunks of a LAS/LAZ file in file order.

    ``points`` is an (m, 3) float64 array of scaled coordinates, ``normals`` (m, 3) or
    None. A file that ends early (a truncated LAZ) raises :class:`CloudFileError`
    naming the file and the point where it ended.
    """
    info = open_las(path)
    for start, pts in iter_records(path, chunk=chunk, info=info):
        nrm = None
        if info.normals:
            nrm = np.column_stack([np.asarray(pts[n], dtype=np.float64) for n in info.normals])
        yield start, xyz_of(pts), nrm


def iter_records(path, *, chunk: int = CHUNK, info: LasInfo | None = None, coordinates_only: bool = False):
    """Yield ``(start, laspy point record)`` chunks of a LAS/LAZ file in file order; a
    file that ends early raises :class:`CloudFileError` naming it and the point.
    ``coordinates_only`` decompresses only x, y, z of a layered LAZ (the other fields read 0)."""
    import laspy

    info = info or open_las(path)
    start = 0
    select = laspy.DecompressionSelection
    try:
        with rust_panics_refused(path), open_reader(
                path, decompression_selection=select.XY_RETURNS_CHANNEL | select.Z if coordinates_only
                else select.all()) as reader:
            for pts in reader.chunk_iterator(chunk):
                yield start, pts
                start += len(pts)
    except CloudFileError:
        raise
    except (laspy.errors.LaspyException, ValueError, EOFError, OSError, RuntimeError, struct.error) as exc:
        raise CloudFileError(path, f"unreadable after point {start} of {info.count} (truncated or corrupt "
                                   f"LAS/LAZ): {exc}") from None
    if start != info.count:
        raise CloudFileError(path, f"truncated: the header declares {info.count} points but only {start} could be read")


def xyz_of(points) -> np.ndarray:
    """(m, 3) float64 scaled coordinates of a laspy point record."""
    return np.column_stack([np.asarray(points.x, float), np.asarray(points.y, float), np.asarray(points.z, float)])


def quantisation(lo, hi):
    """LAS scales and offsets for points within [lo, hi] from a non-LAS source: the finest
    power of ten with the extent within 1e9 steps (int32 holds 2.1e9), offsets on it."""
    extent = float(np.max(np.asarray(hi, float) - np.asarray(lo, float)))
    scale = 10.0 ** np.ceil(np.log10((extent if extent > 0 else 1.0) * 1e-9))
    return np.full(3, scale), np.floor(np.asarray(lo, float) / scale) * scale


#: LAS 1.4 point formats by the colour fields they hold (RGB: 7, RGB and NIR: 8)
_FORMATS = ((("red", "nir"), 8), (("red",), 7), ((), 6))
#: LAS 1.0-1.3's whole-degree scan angle and the 1.4 formats' 0.006-degree steps
_SCAN_ANGLE_STEPS = 1.0 / 0.006


def carried_layout(like):
    """``(point format, [(output field, input field, factor)], [(extra field, type)])``: what
    a result written for an input with the laspy header ``like`` (or None) carries over. The
    output is LAS 1.4 format 6, 7 with colours, 8 with near infrared; every standard field
    of it the input has (a 1.0-1.3 ``scan_angle_rank`` as ``scan_angle``), and every
    extra-bytes field of the input whose name the result does not write."""
    import laspy

    if like is None:
        return 6, [], []
    have = set(like.point_format.dimension_names)
    fmt = next(f for need, f in _FORMATS if all(n in have for n in need))
    standard = []
    for name in laspy.PointFormat(fmt).dimension_names:
        if name in ("X", "Y", "Z"):
            continue
        if name in have:
            standard.append((name, name, 1))
        elif name == "scan_angle" and "scan_angle_rank" in have:
            standard.append((name, "scan_angle_rank", _SCAN_ANGLE_STEPS))
    extra = [(d.name, d.dtype) for d in like.point_format.extra_dimensions
             if d.name not in RESULT_DIMS and d.num_elements == 1]
    return fmt, standard, extra


def result_columns(res) -> dict:
    """The :data:`RESULT_DIMS` columns of a whole :class:`core.CurvatureResult`, as
    :class:`LasResultWriter` writes them (the tiled run assembles the same from its tiles)."""
    cols = {"k1": res.k1, "k2": res.k2, "gaussian": res.gaussian, "mean": res.mean, "valid": res.valid,
            "k": res.k_point}
    for name, arr in (("n", res.normals), ("e1_", res.e1), ("e2_", res.e2)):
        cols.update({f"{name}{c}": arr[:, j] for j, c in enumerate("xyz")})
    cols.update({name: getattr(res, attr) for name, attr in RESULT_FLAGS.items() if name in RESULT_DIMS})
    return cols


class LasResultWriter:
    """Write points and result columns to a LAS/LAZ file chunk by chunk.

    Coordinates keep ``scales``/``offsets`` (those of the input, so the points are the
    input's); LAZ when the path ends in ``.laz``. With ``like``, the input's laspy header,
    the input's own point fields are carried over (:func:`carried_layout`): a classified
    scan keeps its classes, intensity, returns, GPS time and colours. Use as a context manager on an open
    binary file object (e.g. from :func:`core.io.atomic.atomic_write`).
    """

    def __init__(self, fileobj, *, scales, offsets, laz: bool, like=None):
        import laspy

        fmt, self._standard, extra = carried_layout(like)
        header = laspy.LasHeader(point_format=fmt, version="1.4")
        header.scales = np.asarray(scales, float)
        header.offsets = np.asarray(offsets, float)
        header.add_extra_dims([laspy.ExtraBytesParams(name=n, type=t) for n, t in extra]
                              + [laspy.ExtraBytesParams(name=n, type=_TYPES.get(n, np.float64)) for n in RESULT_DIMS])
        self._carried = [n for n, _ in extra]
        self._header = header
        self._writer = laspy.open(fileobj, mode="w", header=header, do_compress=laz, closefd=False)

    def write(self, points: np.ndarray, columns: dict, carried=None) -> None:
        """Append points (m, 3) and ``columns``: name -> (m,) array for every RESULT_DIMS name;
        ``carried``: the input's laspy records of the same points (with ``like``)."""
        import laspy

        rec = laspy.ScaleAwarePointRecord.zeros(len(points), header=self._header)
        rec.x, rec.y, rec.z = points[:, 0], points[:, 1], points[:, 2]
        if carried is not None:
            for out, src, factor in self._standard:
                values = np.asarray(carried[src])
                rec[out] = values if factor == 1 else np.round(values * factor).astype(np.int16)
            for name in self._carried:
                rec[name] = np.asarray(carried[name])
        for name in RESULT_DIMS:
            rec[name] = np.asarray(columns[name]).astype(_TYPES.get(name, np.float64))
        self._writer.write_points(rec)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._writer.close()
        return False
