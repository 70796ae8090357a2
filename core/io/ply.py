"""Stanford PLY: read the vertex element (ascii or binary), write binary little-endian.

The header is parsed by plyfile. Vertex data made only of scalar properties is then loaded
with numpy directly (plyfile reads ascii rows, and binary elements with list properties
such as faces, one row at a time in Python); anything else falls back to ``PlyData.read``.
Faces and other elements are ignored.
"""

from __future__ import annotations

import io
import warnings

import numpy as np
from plyfile import PlyData, PlyElement, PlyListProperty, PlyParseError

from .cloud import CloudFileError, RawCloud, find_normals, remaining_bytes

#: numpy type code -> the PLY type name, for messages
_PLY_NAMES = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint",
              "f4": "float", "f8": "double"}
_PLY_DTYPES = {np.dtype(t) for t in ("i1", "u1", "i2", "u2", "i4", "u4", "f4", "f8")}


def read_ply(path) -> RawCloud:
    """Points, normals (nx/ny/nz or normal_x/...) and other scalar vertex properties."""
    with open(path, "rb") as f:
        try:
            header = PlyData._parse_header(f)  # plyfile's own header parser, without the data
        except PlyParseError as exc:
            raise CloudFileError(path, f"not a valid PLY header: {exc}") from None
        except UnicodeDecodeError:
            raise CloudFileError(path, "not a valid PLY header: non-ASCII bytes in the header") from None
        names = [el.name for el in header.elements]
        if "vertex" not in names:
            raise CloudFileError(path, f"has no 'vertex' element (elements: {', '.join(names) or 'none'})")
        if any(el.count < 0 for el in header.elements):
            raise CloudFileError(path, "not a valid PLY header: negative element count")
        _check_declared_size(header, remaining_bytes(f), path)
        props = _read_vertex_fast(f, header, names.index("vertex"), path)
    if props is None:
        props = _read_vertex_plyfile(path)
    return _raw_from_properties(props, path)


def _min_row_bytes(element, header) -> int:
    """The fewest bytes one row of ``element`` can take: its scalars and list counts in
    binary, or one digit and one separator per property in ASCII."""
    if header.text:
        return 2 * len(element.properties)
    order = header.byte_order
    size = 0
    for prop in element.properties:
        if isinstance(prop, PlyListProperty):
            size += np.dtype(prop.list_dtype(order)[0]).itemsize
        else:
            size += np.dtype(prop.dtype(order)).itemsize
    return size


def _plural(name: str) -> str:
    return {"vertex": "vertices", "face": "faces", "edge": "edges"}.get(name, f"{name!r} rows")


def _check_declared_size(header, have: int, path) -> None:
    """Refuse element counts the file cannot hold, before anything is allocated for them."""
    for element in header.elements:
        need = element.count * _min_row_bytes(element, header)
        if need > have:
            raise CloudFileError(
                path, f"truncated: the header declares {element.count} {_plural(element.name)} (at least "
                f"{need} bytes) but only {have} bytes follow the header",
            )


def _read_vertex_fast(f, header, index, path):
    """The vertex properties as a dict of arrays, or None when plyfile must do it."""
    elements = header.elements
    vertex = elements[index]
    if any(isinstance(p, PlyListProperty) for el in elements[: index + 1] for p in el.properties):
        return None
    if header.text:
        return _read_ascii_vertex(f, vertex, path) if index == 0 else None
    order = header.byte_order
    skip = sum(el.count * el.dtype(order).itemsize for el in elements[:index])
    dtype = vertex.dtype(order)
    f.seek(skip, io.SEEK_CUR)
    need, have = vertex.count * dtype.itemsize, remaining_bytes(f)
    if have < need:
        raise CloudFileError(
            path, f"truncated: the header declares {vertex.count} vertices ({need} bytes) but only {have} bytes "
            "of vertex data follow",
        )
    data = np.frombuffer(f.read(need), dtype=dtype)
    return {name: data[name] for name in dtype.names}


def _read_ascii_vertex(f, vertex, path):
    text = io.TextIOWrapper(f, encoding="latin-1", newline=None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(text, dtype=np.float64, comments=None, max_rows=vertex.count, ndmin=2)
    except ValueError:
        return None  # let plyfile locate and name the bad row
    finally:
        text.detach()
    if len(table) < vertex.count:
        raise CloudFileError(
            path, f"truncated: the header declares {vertex.count} vertices but only {len(table)} vertex rows follow"
        )
    if table.shape[1] != len(vertex.properties):
        return None
    return {p.name: _ascii_column(table[:, i], p, path) for i, p in enumerate(vertex.properties)}


def _ascii_column(values: np.ndarray, prop, path) -> np.ndarray:
    """An ASCII column in the declared type; integers out of range or with a fraction are refused
    (a cast would wrap 300 to 44 in a uchar)."""
    dtype = np.dtype(prop.dtype())
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        bad = (values < info.min) | (values > info.max) | (values != np.round(values))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise CloudFileError(
                path, f"vertex {row}: property {prop.name!r} ({_PLY_NAMES.get(prop.val_dtype, prop.val_dtype)}) has the value {values[row]:g}, "
                f"not an integer in [{info.min}, {info.max}]",
            )
    return values.astype(dtype, copy=False)


def _read_vertex_plyfile(path):
    try:
        vertex = PlyData.read(str(path))["vertex"]
    except PlyParseError as exc:
        problem = "truncated" if "end-of-file" in str(exc) else "malformed PLY data"
        raise CloudFileError(path, f"{problem}: {exc}") from None
    except (ValueError, OverflowError) as exc:  # OverflowError: an integer out of its type's range
        raise CloudFileError(path, f"malformed PLY data: {exc}") from None
    return {p.name: vertex.data[p.name] for p in vertex.properties if not isinstance(p, PlyListProperty)}


def _raw_from_properties(props: dict, path) -> RawCloud:
    lower = {name.lower(): name for name in props}
    if not all(c in lower for c in "xyz"):
        raise CloudFileError(path, f"the vertex element has no x, y, z properties (found: {', '.join(props)})")
    xyz = [lower[c] for c in "xyz"]
    points = np.column_stack([props[name] for name in xyz])
    nrm = find_normals(props)
    normals = None if nrm is None else np.column_stack([props[name] for name in nrm])
    used = set(xyz) | set(nrm or ())
    fields = {name: np.array(values) for name, values in props.items() if name not in used}
    return RawCloud(points, normals, fields)


def _ply_column(values: np.ndarray) -> np.ndarray:
    """``values`` in a dtype PLY can store (bool -> uint8, 64-bit int -> 32-bit or double)."""
    if values.dtype == bool:
        return values.astype(np.uint8)
    if values.dtype in _PLY_DTYPES:
        return values
    if np.issubdtype(values.dtype, np.integer):
        for small in (np.int32, np.uint32):
            info = np.iinfo(small)
            if values.size == 0 or (values.min() >= info.min and values.max() <= info.max):
                return values.astype(small)
    return values.astype(np.float64)


def write_ply(f, columns) -> None:
    """Write ``columns`` (list of (name, (N,) array)) as a binary little-endian PLY vertex element."""
    columns = [(name, _ply_column(values)) for name, values in columns]
    table = np.empty(len(columns[0][1]), dtype=[(name, "<" + values.dtype.str[1:]) for name, values in columns])
    for name, values in columns:
        table[name] = values
    element = PlyElement.describe(table, "vertex")
    PlyData([element], text=False, byte_order="<", comments=["written by darboux"]).write(f)
