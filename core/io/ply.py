"""Stanford PLY: read the vertex element (ascii or binary), write binary little-endian.

The header is parsed by plyfile. Vertex data made only of scalar properties is then loaded
with numpy directly (plyfile reads ascii rows, and binary elements with list properties
such as faces, one row at a time in Python); anything else falls back to plyfile's element
reader. Faces and other elements are not returned, but their rows are counted: a body
that holds more or fewer rows than the header declares is refused (in ASCII, so is a row
that does not fit its element's properties: core.io.ply_ascii). Non-ASCII bytes are
allowed in ``comment`` and ``obj_info`` lines only. ASCII float coordinates keep their
float64 parse; x, y, z, nx, ny, nz in exact case win over other spellings. Beyond the
eight standard types, int64, uint64 and float16 properties (trimesh writes them) are read.
"""

from __future__ import annotations

import io
import re
import sys
import warnings

import numpy as np
from plyfile import PlyData, PlyElement, PlyListProperty, PlyParseError

from .cloud import NORMAL_NAMES, CloudFileError, RawCloud, is_padding, remaining_bytes
from .ply_ascii import check_ascii_rows, declared as _declared, plural as _plural, read_ascii_vertex
from .ply_types import refuse_repeated_names, restore_types, stand_in_types
from .sniff import UTF8_BOM

_PLY_DTYPES = {np.dtype(t) for t in ("i1", "u1", "i2", "u2", "i4", "u4", "f4", "f8")}
#: how far to look for ``end_header`` before handing the file to plyfile as it is
_HEADER_SCAN = 1 << 20
_END_HEADER = re.compile(rb"(?:^|[\r\n])end_header[ \t]*(?:\r\n|\r|\n)")  # trailing blanks: as RPly, tinyply
_ASCII_ONLY = bytes(range(128)) + b"?" * 128
#: ``obj_info`` starting a header line: plyfile refuses one after an ``element`` line, and a
#: comment is what it is (read as one, it may stand anywhere)
_OBJ_INFO = re.compile(rb"(?<![^\r\n])obj_info(?=[ \t\r\n])")


def read_ply(path) -> RawCloud:
    """Points, normals (nx/ny/nz or normal_x/...) and other scalar vertex properties."""
    with open(path, "rb") as f:
        header = _parse_header(f, path)
        names = [el.name for el in header.elements]
        if "vertex" not in names:
            raise CloudFileError(path, f"has no 'vertex' element (elements: {', '.join(names) or 'none'})")
        if any(el.count < 0 for el in header.elements):
            raise CloudFileError(path, "not a valid PLY header: negative element count")
        start = f.tell()
        _check_declared_size(header, remaining_bytes(f), path)
        if header.text:
            check_ascii_rows(f, header, path)
        else:
            _check_binary_layout(path, header, start)
        props = _read_vertex_fast(f, header, names.index("vertex"), path)
        if props is None:
            props = _read_vertex_plyfile(f, header, start, path)
    return _raw_from_properties(props, path)


def _parse_header(f, path):
    """plyfile's header parser on the header, with non-ASCII bytes in ``comment`` and
    ``obj_info`` lines read as '?' (``obj_info`` lines as comments) and the types int64,
    uint64 and float16 read (:mod:`.ply_types`); non-ASCII bytes on another line are refused
    by line number. A UTF-8 byte-order mark before ``ply`` (a text editor's) is skipped."""
    raw = f.read(_HEADER_SCAN)
    end = _END_HEADER.search(raw)
    if end is None:  # no end_header near the start: plyfile says what is wrong
        f.seek(0)
        stream = f
    else:
        raw = raw[: end.end()].removeprefix(UTF8_BOM)
        for lineno, line in enumerate(raw.splitlines(), start=1):
            if not line.isascii() and line.split()[:1] not in ([b"comment"], [b"obj_info"]):
                raise CloudFileError(path, f"not a valid PLY header: line {lineno} "
                                           f"({line.decode('utf-8', 'replace')[:60]!r}) has non-ASCII bytes; "
                                           "only comment and obj_info lines may")
        text, restore = stand_in_types(_OBJ_INFO.sub(b"comment ", raw.translate(_ASCII_ONLY)))
        refuse_repeated_names(text, path)
        stream = io.BytesIO(text)
    try:
        header = PlyData._parse_header(stream)  # plyfile's own header parser, without the data
    except PlyParseError as exc:
        raise CloudFileError(path, f"not a valid PLY header: {exc}") from None
    except UnicodeDecodeError:
        raise CloudFileError(path, "not a valid PLY header: non-ASCII bytes in the header") from None
    if stream is f:
        return header
    restore_types(header, restore)
    f.seek(end.end())
    return header


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


def _check_declared_size(header, have: int, path) -> None:
    """Refuse element counts the file cannot hold, before anything is allocated for them."""
    for element in header.elements:
        need = element.count * _min_row_bytes(element, header) - bool(header.text and element.count)
        if need > have:  # (an ASCII file's last line may end without a newline)
            raise CloudFileError(
                path, f"truncated: the header declares {element.count} {_plural(element.name)} (at least "
                f"{need} bytes) but only {have} bytes follow the header",
            )


def _check_binary_layout(path, header, start: int) -> None:
    """Refuse a binary body whose bytes do not match the declared counts: every element is
    walked (list lengths read) from the end of the header, and data left after the last
    one (a vertex record or more) is refused too."""
    data = np.memmap(path, dtype=np.uint8, mode="r")[start:]
    pos, vstart = 0, None  # where the vertex element starts, once reached
    for element in header.elements:
        vstart = pos if element.name == "vertex" else vstart
        size = _element_bytes(data, pos, element, header.byte_order)
        if size is None:
            raise CloudFileError(path, _layout_problem(data, header, vstart, f"the {_plural(element.name)} run past "
                                                       "the end of the file"))
        pos += size
    extra = len(data) - pos
    if extra >= max(_min_row_bytes(header["vertex"], header), 1):  # a vertex of no properties takes 0 bytes
        raise CloudFileError(path, _layout_problem(data, header, vstart, f"{extra} bytes are left after the "
                                                   f"last {header.elements[-1].name} row"))
    if not is_padding(data[pos : pos + (1 << 16)], b"\r\n"):  # bytes inserted into the rows shifted those after them
        raise CloudFileError(path, f"{extra} bytes are left after the last {header.elements[-1].name} row, less than "
                                   "a row and not a newline: bytes were inserted into the data, shifting "
                                   "the rows after them, or the header's counts are wrong; the file is damaged")


def _layout_problem(data, header, vstart: int, what: str) -> str:
    """The message for counts that do not match the data, with the vertices found when that
    can be told (vertices last, or followed by one element of rows with one list)."""
    vertex = header["vertex"]
    found = None if vstart is None else _found_vertices(data, header, vstart)
    if found is not None and found != vertex.count:
        rest = [el for el in header.elements if el.name != "vertex"]
        others = f" (and its {_declared(rest)})" if rest else ""
        return (f"the header declares {vertex.count} vertices but the file holds {found}{others}; "
                "the vertex count does not match the data")
    return f"the header declares {_declared(header.elements)} but the data does not match these counts: {what}"


def _found_vertices(data, header, vstart: int):
    """The vertex count that makes the data end exactly at the end of the file, when the
    vertices (of scalars only) are last, or followed by one element of scalars and one list."""
    elements, order = header.elements, header.byte_order
    index = [el.name for el in elements].index("vertex")
    vertex, later = elements[index], elements[index + 1 :]
    size, have = vertex.dtype(order).itemsize, len(data) - vstart
    if not size or any(isinstance(p, PlyListProperty) for p in vertex.properties) or len(later) > 1:
        return None
    if not later:
        return have // size if have % size == 0 else None
    fits = _vertices_before_list(data, vstart, size, later[0], order)
    return fits[0] if len(fits) == 1 else None


def _vertices_before_list(data, vstart: int, size: int, element, order) -> list:
    """Every vertex count (records of ``size`` bytes) after which ``element``, rows of scalars
    and one list, ends exactly at the end of the file."""
    layout = _row_layout(element, order)
    kinds = [kind for kind, _ in layout]
    if kinds.count("list") != 1:
        return []
    head = sum(b for kind, b in layout[: kinds.index("list")] if kind == "scalar")
    count_dt, item = layout[kinds.index("list")][1]
    n = np.arange((len(data) - vstart) // size + 1)
    n = n[vstart + n * size + head + count_dt.itemsize <= len(data)]
    at = vstart + n * size + head
    lengths = data[at[:, None] + np.arange(count_dt.itemsize)].view(count_dt)[:, 0].astype(np.int64)
    row = sum(b for kind, b in layout if kind == "scalar") + count_dt.itemsize + lengths * item
    starts = vstart + n[vstart + n * size + element.count * row == len(data)] * size
    return [(int(s) - vstart) // size for s in starts if _element_bytes(data, int(s), element, order) == len(data) - s]


def _row_layout(element, order) -> list:
    """[("scalar", bytes) or ("list", (count dtype, item bytes))] for the properties of a row."""
    layout = []
    for prop in element.properties:
        if isinstance(prop, PlyListProperty):
            count_dt, item_dt = prop.list_dtype(order)
            layout.append(("list", (np.dtype(count_dt), np.dtype(item_dt).itemsize)))
        else:
            layout.append(("scalar", np.dtype(prop.dtype(order)).itemsize))
    return layout


def _element_bytes(data, pos: int, element, order):
    """The bytes the rows of ``element`` take from ``data[pos:]``, or None past the end."""
    layout = _row_layout(element, order)
    if all(kind == "scalar" for kind, _ in layout):
        size = element.count * sum(n for _, n in layout)
        return size if pos + size <= len(data) else None
    row = _rows_bytes(data, pos, layout, min(element.count, 1))
    if row and pos + element.count * row <= len(data) and _uniform(data, pos, layout, row, element.count):
        return element.count * row
    return row if row is None or element.count <= 1 else _rows_bytes(data, pos, layout, element.count)


def _rows_bytes(data, pos: int, layout, count: int):
    """The bytes of ``count`` rows from ``data[pos:]`` read one by one (lists of different
    lengths), or None past the end or at a negative list length."""
    buf, end = memoryview(data), pos
    big = {">": "big", "=": sys.byteorder}
    steps = [(spec, None, "", False) if kind == "scalar" else
             (spec[0].itemsize, spec[1], big.get(spec[0].byteorder, "little"), spec[0].kind == "i")
             for kind, spec in layout]
    for _ in range(count):
        for width, item, byteorder, signed in steps:
            if item is not None:
                length = int.from_bytes(buf[end : end + width], byteorder, signed=signed)
                if length < 0 or end + width > len(buf):
                    return None
                end += length * item
            end += width
        if end > len(buf):
            return None
    return end - pos


def _uniform(data, pos: int, layout, row: int, count: int) -> bool:
    """Whether all ``count`` rows from ``pos`` have the lists of the first (``row`` bytes each)."""
    offset = 0
    for kind, spec in layout:
        if kind == "list":
            first = data[pos + offset : pos + offset + spec[0].itemsize].view(spec[0])[0]
            counts = np.lib.stride_tricks.as_strided(data[pos + offset :], shape=(count, spec[0].itemsize),
                                                     strides=(row, 1))
            if not (np.ascontiguousarray(counts).view(spec[0])[:, 0] == first).all():
                return False
            spec = spec[0].itemsize + int(first) * spec[1]
        offset += spec
    return True


def _read_vertex_fast(f, header, index, path):
    """The vertex properties as a dict of arrays, or None when plyfile must do it."""
    elements = header.elements
    vertex = elements[index]
    if any(isinstance(p, PlyListProperty) for el in elements[: index + 1] for p in el.properties):
        return None
    if header.text:
        return read_ascii_vertex(f, vertex, path) if index == 0 else None
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
    data = np.frombuffer(f.read(need), dtype=dtype, count=vertex.count)  # a count: records of no properties are 0 bytes
    return {name: data[name] for name in dtype.names}


def _read_vertex_plyfile(f, header, start: int, path):
    """The vertex properties read by plyfile's element reader, every element in turn from ``start``."""
    f.seek(start)
    stream = io.TextIOWrapper(f, "ascii") if header.text else f
    name = None
    try:
        with np.errstate(over="raise"), warnings.catch_warnings():  # an ASCII 1e300 in a float: inf, and a warning
            warnings.simplefilter("ignore", UserWarning)  # loadtxt's "input contained no data": an empty ASCII list
            for element in header.elements:
                name = element.name
                element._read(stream, header.text, header.byte_order, "c")  # what PlyData.read does
        vertex = header["vertex"]
    except FloatingPointError:
        raise CloudFileError(path, f"malformed PLY data: element {name!r} holds a value beyond the range of "
                                   "its property's type") from None
    except UnicodeDecodeError:
        raise CloudFileError(path, "malformed PLY data: non-ASCII bytes in the ASCII body") from None
    except PlyParseError as exc:
        problem = "truncated" if "end-of-file" in str(exc) else "malformed PLY data"
        raise CloudFileError(path, f"{problem}: {exc}") from None
    except OverflowError as exc:  # an ASCII integer out of its type's range
        raise CloudFileError(path, f"malformed PLY data: element {name!r} holds an integer beyond the range of "
                                   f"its property's type ({exc})") from None
    except ValueError as exc:
        raise CloudFileError(path, f"malformed PLY data: {exc}") from None
    finally:
        if stream is not f:
            stream.detach()  # f stays open for its ``with``; the wrapper is not left to be collected
    return {p.name: vertex.data[p.name] for p in vertex.properties if not isinstance(p, PlyListProperty)}


def _property(props, wanted: str, path):
    """The property named ``wanted``: in exact case, else the one spelling that differs in
    case only (X for x); None if there is none, refused if there are several (Nx and NX)."""
    if wanted in props:
        return wanted
    matches = [name for name in props if name.lower() == wanted]
    if len(matches) > 1:
        raise CloudFileError(path, f"the vertex properties {', '.join(map(repr, matches))} all name {wanted}; "
                                   f"rename all but one, or add one named exactly {wanted!r}")
    return matches[0] if matches else None


def _normal_names(props, path):
    """The properties holding normal x, y, z (nx ny nz, normal_x ..., in that order), or None."""
    for triple in NORMAL_NAMES:
        found = [_property(props, name, path) for name in triple]
        if None not in found:
            return found
    return None


def _raw_from_properties(props: dict, path) -> RawCloud:
    xyz = [_property(props, c, path) for c in "xyz"]
    if None in xyz:
        raise CloudFileError(path, f"the vertex element has no x, y, z properties (found: {', '.join(props)})")
    points = np.column_stack([props[name] for name in xyz])
    nrm = _normal_names(props, path)
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
