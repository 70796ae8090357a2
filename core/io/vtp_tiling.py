"""The raw appended data of a .vtp file, checked to hold its arrays one after another.

Each array in raw ``<AppendedData>`` is found by its ``offset`` and holds a header word (its
byte length) and that many bytes. Bytes inserted into or deleted from an array leave its
header's length as it was: VTK reads the points shifted (1e+291 for points within 1), and
the arrays after it start elsewhere than their offsets say. VTK and every writer of the
format put the arrays end to end, the last ending where the appended data end (before
``</AppendedData>``): arrays that do not meet so are refused, naming the first that does
not begin where the one before it ends. Only uncompressed raw data are checked (a
compressed array's header is checked against its blocks by :mod:`.vtp_blocks`); a file cut
short, whose arrays run past its end, is left to the checks that say so.
"""

from __future__ import annotations

import re
import struct
import sys

from .cloud import CloudFileError
from .vtp_blocks import _attrs

_APPENDED = re.compile(rb"<AppendedData\b([^<>]*)>[ \t\r\n]*_")
_CLOSE = re.compile(rb"[ \t\r\n]*</AppendedData\s*>")
_ARRAY = re.compile(rb"<DataArray\b((?:[^<>\"']|\"[^\"<]*\"|'[^'<]*')*)>")
_SECTIONS = (b"Points", b"PointData", b"CellData", b"FieldData", b"Verts", b"Lines", b"Strips", b"Polys")
_VTKFILE = re.compile(rb"<VTKFile\b((?:[^<>\"']|\"[^\"<]*\"|'[^'<]*')*)>")


def check_tiling(data, path) -> None:
    """Refuse raw appended arrays that do not lie end to end (see the module's text)."""
    layout = _raw_layout(data)
    if layout is None:
        return
    start, stop, word = layout
    pos, before = 0, None
    for offset, name, read in _appended_arrays(data, start):
        if offset != pos:
            _refuse(path, f"array {name!r} starts", offset, before, pos)
        length = word.unpack_from(data, start + offset)[0] if start + offset + word.size <= stop else stop
        if start + offset + word.size + length > stop:
            if read:
                return  # an array VTK reads: the checks of each array (.vtp_blocks) name it
            raise CloudFileError(path, f"array {name!r} declares {length} bytes, past the end of its appended data "
                                       f"({stop - start - offset - word.size} bytes left); the file is damaged")
        pos, before = offset + word.size + length, name
    if before is not None and pos != stop - start:
        _refuse(path, "the data end", stop - start, before, pos)


def _appended_arrays(data, start: int) -> list:
    """(offset, name, whether VTK reads it: a point or point-data array) of each raw appended
    DataArray before ``start``, in offset order (one per offset)."""
    arrays = {}
    for match in _ARRAY.finditer(data, 0, start):
        attrs = _attrs(match.group(1))
        if attrs.get("format") == "appended" and re.fullmatch(r"\s*\d+\s*", attrs.get("offset", "")):
            section = max(_SECTIONS, key=lambda name: data.rfind(b"<" + name, 0, match.start()))
            arrays.setdefault(int(attrs["offset"]), (attrs.get("Name", "(unnamed)"), section in (b"Points", b"PointData")))
    return [(offset, *arrays[offset]) for offset in sorted(arrays)]


def _raw_layout(data):
    """(where the appended data start after '_', where they end, the header word), or None
    when the file has no raw, uncompressed appended data closed by ``</AppendedData>``."""
    head = _VTKFILE.search(data, 0, 1 << 16)
    tag = _APPENDED.search(data)
    if head is None or tag is None or _attrs(tag.group(1)).get("encoding", "raw") != "raw":
        return None
    attrs = _attrs(head.group(1))
    order = {"LittleEndian": "<", "BigEndian": ">"}.get(attrs.get("byte_order", sys.byteorder.title() + "Endian"))
    word = {"UInt32": "I", "UInt64": "Q"}.get(attrs.get("header_type", "UInt32"))
    if "compressor" in attrs or order is None or word is None:
        return None
    close = data.rfind(b"</AppendedData")
    if close < tag.end():
        return None
    stop = close
    while stop > tag.end() and data[stop - 1 : stop] in (b" ", b"\t", b"\r", b"\n"):
        stop -= 1
    return tag.end(), stop, struct.Struct(order + word)


def _refuse(path, what: str, offset: int, before, end: int):
    after = f"array {before!r} ends at byte {end}" if before else "the data begin at byte 0"
    raise CloudFileError(path, f"its appended data do not hold their arrays end to end: {after} of the appended "
                               f"data but {what} at byte {offset}: bytes were inserted or lost, shifting the arrays; "
                               "the file is damaged")
