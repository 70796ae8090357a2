"""LAS / LAZ lidar files via laspy (LAZ needs a backend such as lazrs).

The scaled coordinates are the points; every other point dimension (intensity,
classification, gps_time, red, ...) becomes a field; extra-bytes dimensions named
nx/ny/nz or normal_x/... are the normals.
"""

from __future__ import annotations

import contextlib
import os
import struct

import numpy as np

from .cloud import CloudFileError, RawCloud, check_memory, find_normals, split_components
from .las_open import open_reader, point_count, unreadable
from .las_tail import check_partial_record


def read_las(path) -> RawCloud:
    """Points, normals (from extra bytes, if any) and all other point dimensions."""
    las = _read_las_data(path)
    points = np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)])
    names = [n for n in las.point_format.dimension_names if n not in ("X", "Y", "Z")]
    nrm = find_normals(names)
    normals = None if nrm is None else np.column_stack([np.asarray(las[n], dtype=np.float64) for n in nrm])
    fields = {}
    for name in names:
        if name not in (nrm or ()):
            fields.update(split_components(name, np.array(las[name])))
    return RawCloud(points, normals, fields)


def _read_las_data(path):
    """The ``laspy.LasData``, every problem a :class:`CloudFileError`."""
    import laspy

    check_record_counts(path)
    try:
        with rust_panics_refused(path), open_reader(path) as reader:
            _check_header(reader.header, path, laspy)
            return reader.read()
    except CloudFileError:
        raise
    except (laspy.errors.LaspyException, ValueError, EOFError, struct.error) as exc:
        raise unreadable(path, exc) from None
    except RuntimeError as exc:  # lazrs.LazrsError: corrupt or truncated LAZ chunks
        if type(exc).__module__.split(".")[0] != "lazrs":
            raise
        raise CloudFileError(path, f"corrupt or truncated LAZ data: {exc}") from None


@contextlib.contextmanager
def rust_panics_refused(path):
    """A panic of the LAZ decompressor (lazrs, in Rust) on a corrupt file as a
    :class:`CloudFileError`: pyo3 raises it as a ``PanicException``, a ``BaseException``,
    which no ``except Exception`` (the viewer's worker included) catches. The checks before
    a read refuse the panics found (a LASzip record of no items); this catches any other."""
    try:
        yield
    except BaseException as exc:
        if type(exc).__name__ != "PanicException":
            raise
        raise CloudFileError(path, f"corrupt LAZ data: the decompressor failed ({exc})") from None


def _check_header(header, path, laspy) -> None:
    """A LAZ backend for compressed points, usable scales, and enough bytes for the points."""
    compressed = header.are_points_compressed
    if compressed and not laspy.LazBackend.detect_available():
        raise CloudFileError(
            path, "is LAZ-compressed but no LAZ backend is installed; run `pip install lazrs` "
            "(or `pip install 'darboux[las]'`)"
        )
    _check_scales(header, path)
    if compressed:
        _check_memory(path, header.point_count, header.point_format.size)
    need = header.offset_to_point_data + header.point_count * header.point_format.size
    if not compressed and os.path.getsize(path) < need:
        raise CloudFileError(
            path, f"truncated: the header declares {header.point_count} points ({need} bytes) but the file "
            f"has {os.path.getsize(path)} bytes"
        )


def _check_memory(path, n_points: int, record_length: int) -> None:
    """A LAZ file's point count cannot be checked against its size (chunks of any size
    compress to any length): refuse a count whose records, and the float64 coordinates built
    from them, would not fit in the memory available (laspy allocates all of them at once)."""
    need = n_points * (record_length + 3 * 8 * 2)  # the records, the coordinates and one temporary
    check_memory(path, need, f"declares {n_points} points: reading them needs",
                 " (a damaged header, or a file to estimate in tiles: `darboux-cli estimate --tile-points ...`)")


def _check_scales(header, path) -> None:
    """Coordinates are integers x scale + offset: a zero or non-finite scale (or offset)
    would put every point on the offset or at NaN."""
    scales, offsets = np.asarray(header.scales, dtype=float), np.asarray(header.offsets, dtype=float)
    if not (np.isfinite(scales).all() and (scales != 0).all() and np.isfinite(offsets).all()):
        raise CloudFileError(
            path, f"invalid header: coordinate scales {scales.tolist()} and offsets {offsets.tolist()} must be finite "
            "and the scales non-zero",
        )


#: smallest (extended) variable-length record: its header without data
_VLR_HEADER, _EVLR_HEADER = 54, 60


def check_record_counts(path) -> None:
    """Refuse record counts and sizes the file cannot hold: laspy would loop over a corrupt
    count of 4 billion variable-length records, reading nothing at the end of the file, or
    allocate what a corrupt offset, record length or point count asks for."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(255)
        if len(head) < 111 or not head.startswith(b"LASF"):
            return  # not a LAS header: laspy says what is wrong
        if head[24] != 1 or head[25] > 4:  # laspy read a 1.9 header's fields past its end: "unpack requires ..."
            raise CloudFileError(path, f"its header says LAS version {head[24]}.{head[25]}; versions 1.0 to 1.4 are read")
        header_size, offset, n_vlrs = struct.unpack_from("<HII", head, 94)
        if header_size + n_vlrs * _VLR_HEADER > size:
            raise CloudFileError(path, f"corrupt header: it declares {n_vlrs} variable-length records, more than "
                                       f"the {size} bytes of the file can hold")
        if offset > size:
            raise CloudFileError(path, f"corrupt header: its point data starts at byte {offset}, past the end of "
                                       f"the {size}-byte file")
        if head[24:26] >= bytes([1, 4]) and len(head) >= 247:
            _check_evlrs(path, f, *struct.unpack_from("<QI", head, 235), offset, size)
        _check_point_count(path, head, offset, size)
        vlrs = _read_vlrs(f, header_size, n_vlrs)
        _check_extra_bytes(path, vlrs.get(_EXTRA_BYTES, b""))
        _check_laz_sizes(path, f, head, size, vlrs.get(_LASZIP))
        _check_laz_count(path, f, point_count(head), vlrs.get(_LASZIP), offset)
        _check_laz_layers(path, f, vlrs.get(_LASZIP), offset, size)


def _check_point_count(path, head: bytes, offset: int, size: int) -> None:
    """The header's point count against the records the file holds: laspy reads only the
    points a header declares (more records after them were dropped without a word), and a
    part of a record more is checked for shifted records (:mod:`.las_tail`). A LAS 1.4 count
    of 0 with a legacy count is read with the legacy count (:mod:`.las_open`)."""
    minor, record = head[25], struct.unpack_from("<H", head, 105)[0]
    count = point_count(head)
    if head[104] & 0xC0 or record == 0:  # LAZ: the count is checked while decompressing
        return
    end = min([size] + [start for start in _later_records(head, minor) if start >= offset + count * record])
    held = (end - offset) // record
    if held == count:
        check_partial_record(path, head, offset, count, record, end)
    if held > count:
        raise CloudFileError(path, f"the header declares {count} points but the point data holds {held} records of "
                                   f"{record} bytes; the header's point count is wrong (the file was not finished, "
                                   "or was joined to another): rewrite it with a LAS tool to count every point")


def _later_records(head: bytes, minor: int) -> list:
    """Where records after the point data start: the waveform data (LAS 1.3+) and the extended
    variable-length records (1.4), where the header gives them (0: none)."""
    starts = [struct.unpack_from("<Q", head, 227)[0]] if minor >= 3 and len(head) >= 235 else []
    if minor >= 4 and len(head) >= 247 and struct.unpack_from("<I", head, 243)[0]:
        starts.append(struct.unpack_from("<Q", head, 235)[0])
    return [start for start in starts if start]


def _check_evlrs(path, f, start: int, count: int, offset: int, size: int) -> None:
    """Extended VLRs (LAS 1.4) after the point data, each within the file: laspy reads a
    record's declared length (8 bytes, up to 2**64) in one allocation."""
    if not count:
        return
    if start < offset or start + count * _EVLR_HEADER > size:
        raise CloudFileError(path, f"corrupt header: it declares {count} extended variable-length records "
                                   f"from byte {start}: they must follow the point data (from byte {offset}) and fit in the {size}-byte file")
    pos = start
    for i in range(count):
        f.seek(pos + 20)
        length = struct.unpack("<Q", f.read(8))[0]
        pos += _EVLR_HEADER + length
        if pos > size:
            raise CloudFileError(path, f"corrupt header: extended variable-length record {i} declares {length} "
                                       f"bytes, past the end of the {size}-byte file")


#: (user id, record id) of the extra-bytes VLR and of the LASzip VLR
_EXTRA_BYTES, _LASZIP = (b"LASF_Spec", 4), (b"laszip encoded", 22204)
#: the chunk size meaning "variable chunks"
_VARIABLE_CHUNKS = 0xFFFFFFFF
#: a chunk buffer above this is refused when it is also larger than the file's points
_MAX_CHUNK_BYTES = 1 << 30
#: the LASzip compressor of point formats 6-10: each chunk stored as layers (x and y, z, intensity...)
_LAYERED = 3
#: LASzip item type -> the layers of a chunk it takes (point 14, RGB 14, RGB+NIR 14, wave packet 14);
#: item type 14, extra bytes, takes one layer per byte
_ITEM_LAYERS, _EXTRA_BYTES_ITEM = {10: 9, 11: 1, 12: 2, 13: 1}, 14


def _read_vlrs(f, header_size: int, n_vlrs: int) -> dict:
    """(user id, record id) -> data of the variable-length records (their count checked)."""
    f.seek(header_size)
    vlrs = {}
    for _ in range(n_vlrs):
        vlr = f.read(_VLR_HEADER)
        if len(vlr) < _VLR_HEADER:
            break
        user_id, record_id, length = vlr[2:18].split(b"\0")[0], *struct.unpack_from("<HH", vlr, 18)
        vlrs.setdefault((user_id, record_id), f.read(length))
    return vlrs


def _check_extra_bytes(path, data: bytes) -> None:
    """An extra-bytes dimension of data type 0 ("undocumented bytes") takes its size from
    the options byte: 0 bytes made laspy divide by zero."""
    for start in range(0, len(data) - 191, 192):
        if data[start + 2] == 0 and data[start + 3] == 0:
            name = data[start + 4 : start + 36].split(b"\0")[0].decode("latin-1")
            raise CloudFileError(path, f"corrupt extra-bytes record: dimension {name!r} has a size of 0 bytes "
                                       "(data type 0 needs a size of 1 to 255 bytes in its options byte)")


def _check_laz_sizes(path, f, head: bytes, size: int, laszip) -> None:
    """lazrs aborts the process (not an exception) when it cannot allocate what a corrupt
    LASzip record asks for: a chunk of 4 billion points, or a chunk table of 4 billion
    entries; laspy allocates the declared point count at once. Such sizes are refused here
    first: fixed-size chunks hold at most chunk size x chunk count points."""
    if laszip is None or len(laszip) < 16:
        return  # not LASzip-compressed
    offset = struct.unpack_from("<I", head, 96)[0]
    record_length = struct.unpack_from("<H", head, 105)[0]
    n_points = struct.unpack_from("<I", head, 107)[0]
    if head[24:26] >= bytes([1, 4]) and len(head) >= 255:
        n_points = max(n_points, struct.unpack_from("<Q", head, 247)[0])
    item_bytes = sum(item_size for _, item_size in _laszip_items(laszip))
    if item_bytes != record_length:  # lazrs divided by a point size of 0 (a panic, not an exception)
        raise CloudFileError(path, f"corrupt LAZ header: its LASzip record describes points of {item_bytes} bytes "
                                   f"but the point records are {record_length} bytes")
    chunk_size = struct.unpack_from("<I", laszip, 12)[0]
    if chunk_size != _VARIABLE_CHUNKS and chunk_size > n_points and chunk_size * record_length > _MAX_CHUNK_BYTES:
        raise CloudFileError(path, f"corrupt LAZ header: chunks of {chunk_size} points for a file of {n_points}")
    f.seek(offset)
    table = struct.unpack("<q", f.read(8))[0] if offset + 8 <= size else -1
    if not 0 <= table <= size - 8:
        return
    f.seek(table)
    _, n_chunks = struct.unpack("<II", f.read(8))
    if n_chunks > min(size, n_points + 1):
        raise CloudFileError(path, f"corrupt LAZ data: a chunk table of {n_chunks} chunks for {n_points} "
                                   f"points in {size} bytes")
    if chunk_size != _VARIABLE_CHUNKS and n_points > n_chunks * chunk_size:
        raise CloudFileError(path, f"corrupt LAZ header: it declares {n_points} points but its {n_chunks} chunks "
                                   f"of {chunk_size} points hold at most {n_chunks * chunk_size}")


def _check_laz_layers(path, f, laszip, offset: int, size: int) -> None:
    """A layered LAZ chunk starts with its first point, its point count and the byte count of
    each layer; lazrs allocates each count (up to 4 GB) before reading the layer, and a failed
    allocation aborts the process (a 1 kB file did). The layers of every chunk must fit in
    the bytes the chunk table gives the chunk."""
    items = _layered_items(laszip)
    if not items:
        return
    n_layers = sum(item_size if kind == _EXTRA_BYTES_ITEM else _ITEM_LAYERS[kind] for kind, item_size in items)
    first = sum(item_size for _, item_size in items) + 4  # the first point and the point count
    start = offset + 8  # after the offset of the chunk table
    for i, length in enumerate(_chunk_lengths(f, laszip, offset, size)):
        f.seek(start + first)
        layers, room = f.read(4 * n_layers), min(length, size - start)  # a chunk past the end: the bytes left
        if len(layers) < 4 * n_layers:
            return  # truncated: lazrs says so
        need = first + len(layers) + sum(struct.unpack(f"<{n_layers}I", layers))
        if need > room:
            raise CloudFileError(path, f"corrupt or truncated LAZ data: chunk {i} declares layers of {need} bytes "
                                       f"(with its header) but has {room}")
        start += length


def _laszip_items(laszip) -> list:
    """(item type, bytes) of the items (point fields) a LASzip record lists."""
    if len(laszip) < 34:
        return []
    n_items = struct.unpack_from("<H", laszip, 32)[0]
    return [struct.unpack_from("<HH", laszip, 34 + 6 * i) for i in range(n_items) if 40 + 6 * i <= len(laszip)]


def _layered_items(laszip) -> list:
    """(item type, bytes) of the items of a layered LASzip record, or [] for another one."""
    if laszip is None or len(laszip) < 34 or struct.unpack_from("<H", laszip, 0)[0] != _LAYERED:
        return []
    items = _laszip_items(laszip)
    if any(kind not in _ITEM_LAYERS and kind != _EXTRA_BYTES_ITEM for kind, _ in items):
        return []  # not items of a layered chunk: laspy or lazrs says what is wrong
    return items


def _check_laz_count(path, f, count: int, laszip, offset: int) -> None:
    """The header's point count against the LAZ chunk table: laspy decompresses only the
    points a header declares, so whole chunks after them were dropped without a word. The
    table gives each chunk's point count (variable chunks) or the chunk size, which every
    chunk but the last holds (fixed chunks): points missing from the count within the last
    chunk cannot be told without decompressing it."""
    if laszip is None or len(laszip) < 16:
        return
    table = _chunk_table(f, laszip, offset)
    if not table:
        return
    chunk_size = struct.unpack_from("<I", laszip, 12)[0]
    if chunk_size == _VARIABLE_CHUNKS:
        held, what = sum(points for points, _ in table), f"its {len(table)} compressed chunks hold"
    else:
        held = (len(table) - 1) * chunk_size + 1
        what = f"its {len(table)} compressed chunks of {chunk_size} hold at least"
    if chunk_size == _VARIABLE_CHUNKS and held < count:
        raise CloudFileError(path, f"truncated: the header declares {count} points but {what} {held}")
    if held > count:
        raise CloudFileError(path, f"the header declares {count} points but {what} {held}; "
                                   "the header's point count is wrong (the file was not finished, or was joined to "
                                   "another): rewrite it with a LAS tool to count every point")


def _chunk_table(f, laszip, offset: int):
    """[(points, bytes)] of each chunk from the chunk table (read by lazrs), or None."""
    try:
        import lazrs
    except ImportError:
        return None  # laspy refuses the file: no LAZ backend
    f.seek(offset)
    try:
        return [(int(points), int(length)) for points, length in lazrs.read_chunk_table(f, lazrs.LazVlr(laszip))]
    except (RuntimeError, ValueError, OSError, TypeError):  # lazrs.LazrsError is a RuntimeError
        return None


def _chunk_lengths(f, laszip, offset: int, size: int) -> list:
    """The bytes of each chunk from the chunk table (read by lazrs), or, without a table lazrs
    can read, the first chunk taking the rest of the file."""
    try:
        import lazrs  # noqa: F401
    except ImportError:
        return []  # laspy refuses the file: no LAZ backend
    table = _chunk_table(f, laszip, offset)
    return [size - offset - 8] if table is None else [length for _, length in table]
