"""The headers of an XML PolyData (.vtp) file's binary DataArrays, checked before VTK reads them.

A binary array (inline ``format="binary"``, base64; or in ``<AppendedData>``, raw or base64)
starts with a header of UInt32 or UInt64 words (the VTKFile element's ``header_type``, in its
``byte_order``): one word, the byte length, for uncompressed data; for compressed data
(``compressor=`` zlib, LZ4 or LZMA) ``[nblocks, block size, last block size, compressed size
of each block...]``, base64-encoded on its own (padded) before the data when the data are
encoded. VTK allocates what these words declare (a buffer of each block's compressed size,
two of nblocks words) before reading a byte, and a failed allocation aborts the process
(``std::bad_alloc``, not an exception); a block size of 0 divides by zero and a last block
larger than the others reads past its buffer. A header that declares more than the array
holds, more than memory or more than the file, or that cannot be decoded, is refused first.
"""

from __future__ import annotations

import base64
import binascii
import html
import re
import struct
import sys
from dataclasses import dataclass

from .cloud import CloudFileError
from .vtk_ascii import MAX_ARRAYS

_TAG = re.compile(rb"<(/?)([A-Za-z][\w.:-]*)((?:[^<>\"']|\"[^\"<]*\"|'[^'<]*')*)>")
_ATTR = re.compile(rb"([\w.:-]+)\s*=\s*(?:\"([^\"]*)\"|'([^']*)')")
_APPENDED = re.compile(rb"<AppendedData\b([^<>]*)>")
#: the first character of the appended data after white space, which must be VTK's '_'
_MARKER = re.compile(rb"[ \t\r\n]*([^ \t\r\n]?)")
#: the characters of base64 (and its padding), and how many are read at a time when checking them
_BASE64 = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/="
_SCAN = 1 << 24
_COMPRESSORS = {"vtkZLibDataCompressor", "vtkLZ4DataCompressor", "vtkLZMADataCompressor"}
_TYPE_SIZES = {"Int8": 1, "UInt8": 1, "Int16": 2, "UInt16": 2, "Int32": 4, "UInt32": 4, "Int64": 8,
               "UInt64": 8, "Float32": 4, "Float64": 8}
_CELLS = ("Verts", "Lines", "Strips", "Polys")
_SECTIONS = {"Points", "PointData", "CellData", "FieldData", *_CELLS}


@dataclass(frozen=True)
class _Layout:
    """How the file stores its binary data."""

    data: object  # the file, memory-mapped
    word: str  # struct format of one header word, with its byte order
    compressed: bool
    appended: int | None  # where the appended data start (after the '_'), if any; -1: no '_' first
    appended_base64: bool
    available: int  # bytes of memory available

    @property
    def word_size(self) -> int:
        return struct.calcsize(self.word)


@dataclass(frozen=True)
class _Array:
    label: str  # "array 'Normals' in PointData of piece 0"
    format: str
    offset: int | None  # into the appended data
    text: tuple[int, int]  # where its inline text lies
    expected: int | None  # bytes it holds, when the XML says
    why: str  # how ``expected`` was found


def check_binary_headers(data, tags: "Tags", available: int, path) -> None:
    """Raise :class:`CloudFileError` when a binary DataArray's header is one that VTK would
    act on to its harm (see the module docstring). ``data``: the file, memory-mapped;
    ``tags``: what expat read of its XML (:mod:`core.io.xml_scan`, the one parse
    :func:`core.io.vtp_sizes.check_vtp` shares); ``available``: the memory available."""
    if len(tags.arrays) > MAX_ARRAYS:  # VTK's read of n arrays takes n**2 (20,000: 7 s)
        raise CloudFileError(path, f"holds {len(tags.arrays):,} data arrays; a point cloud's file is read with at "
                                   f"most {MAX_ARRAYS:,}")
    end = data.find(b"<AppendedData")
    layout = _layout(data, len(data) if end < 0 else end, available, tags.vtkfile)
    if layout is None:
        return  # no VTKFile element, or a header type / byte order that VTK refuses itself
    for pos, attrs, where, counts in tags.arrays:
        problem = _problem(layout, _array(data, pos, attrs, where, counts))
        if problem:
            raise CloudFileError(path, f"{_label(attrs, where)}: {problem}")


class Tags:
    """What :func:`check_binary_headers` reads of the XML: the VTKFile element's attributes,
    and each DataArray's (position of its '<', attributes, section and piece, the piece's
    attributes)."""

    def __init__(self):
        self.vtkfile, self.arrays = None, []
        self.section, self.piece, self.counts = "", -1, {}

    def start(self, name: str, attrs: dict, pos: int) -> None:
        if name == "VTKFile" and self.vtkfile is None:
            self.vtkfile = attrs
        elif name == "Piece":
            self.piece, self.counts = self.piece + 1, attrs
        elif name in _SECTIONS:
            self.section = name
        elif name == "DataArray":
            self.arrays.append((pos, attrs, f"{self.section or 'the file'} of piece {max(self.piece, 0)}", self.counts))

    def end(self, name: str) -> None:
        self.section = "" if name == self.section else self.section


def _label(attrs: dict, where: str) -> str:
    return f"array {attrs.get('Name', '(unnamed)')!r} in {where}"


def _attrs(text: bytes) -> dict:
    """The attributes of a tag's text (either quotes, references unescaped as XML does)."""
    return {k.decode("latin-1"): html.unescape((a or b).decode("latin-1")) for k, a, b in _ATTR.findall(text)}


def _int(text) -> int | None:
    """The leading digits of an attribute, as VTK reads it (``"3abc"`` is 3), or None."""
    match = re.match(r"\s*\+?(\d+)", text or "")
    return int(match.group(1)) if match else None


def _layout(data, end: int, available: int, attrs) -> _Layout | None:
    if attrs is None:
        return None
    native = "LittleEndian" if sys.byteorder == "little" else "BigEndian"
    order = {"LittleEndian": "<", "BigEndian": ">"}.get(attrs.get("byte_order", native))
    word = {"UInt32": "I", "UInt64": "Q"}.get(attrs.get("header_type", "UInt32"))
    if order is None or word is None:
        return None
    appended, base64_appended = None, False
    tag = _APPENDED.match(data, end) if end < len(data) else None
    if tag is not None:
        first = _MARKER.match(data, tag.end())  # VTK skips white space, then expects its '_'
        appended = first.end() if first and first.group(1) == b"_" else -1
        base64_appended = _attrs(tag.group(1)).get("encoding", "raw") == "base64"
    return _Layout(data, order + word, attrs.get("compressor") in _COMPRESSORS, appended, base64_appended,
                   available)


def _array(data, pos: int, attrs: dict, where: str, counts: dict) -> _Array:
    section = where.split(" of ")[0]
    expected, why = _expected(attrs, section, counts)
    tag = _TAG.match(data, pos)  # expat read the tag: this finds its end, whichever quotes it has
    start = tag.end() if tag else data.find(b">", pos) + 1
    stop = data.find(b"<", start)
    stop = len(data) if stop < 0 else stop
    while start < stop and data[start : start + 1].isspace():
        start += 1
    return _Array(_label(attrs, where), attrs.get("format", "ascii"), _int(attrs.get("offset")), (start, stop), expected, why)


def _expected(attrs: dict, section: str, counts: dict) -> tuple[int | None, str]:
    """The bytes the array holds by the XML (tuples x components x type size), or None."""
    size = _TYPE_SIZES.get(attrs.get("type", ""))
    components = _int(attrs.get("NumberOfComponents", "1"))
    points = _int(counts.get("NumberOfPoints", "0"))
    cells = [_int(counts.get(f"NumberOf{kind}", "0")) for kind in _CELLS]
    tuples = {"Points": points, "PointData": points,
              "CellData": None if None in cells else sum(cells)}.get(section)
    if section in _CELLS and attrs.get("Name") == "offsets":
        count = _int(counts.get(f"NumberOf{section}", "0"))
        tuples = None if count is None else count + 1  # n + 1 offsets from file version 2.0
    declared = _int(attrs.get("NumberOfTuples"))
    if declared is not None:
        tuples = max(tuples or 0, declared)
    if size is None or components is None or tuples is None:
        return None, "its size is not declared"
    return tuples * components * size, f"{tuples} tuples x {components} components x {size} bytes"


def _problem(layout: _Layout, array: _Array) -> str | None:
    """What is wrong with the array's header, or None (also when it is not binary)."""
    if array.format == "binary":
        (start, stop), encoded = array.text, True
    elif array.format == "appended" and layout.appended == -1:
        return ("the AppendedData does not start with '_', VTK's marker (VTK warns, then reads what follows as "
                "the arrays' headers: a 3.5 kB file took 10 GB)")
    elif array.format == "appended" and layout.appended is not None and array.offset is not None:
        start, stop, encoded = layout.appended + array.offset, len(layout.data), layout.appended_base64
    else:
        return None  # ascii, or appended data that VTK will not find (it says so)
    limit, allowed = layout.available, f"{layout.available / 1e9:.3g} GB, the memory available"
    if array.expected is not None and array.expected <= limit:
        limit, allowed = array.expected, f"{array.expected} bytes, what the array holds ({array.why})"
    stream = _Stream(layout, start, stop, encoded)
    if layout.compressed:
        return _compressed_problem(stream, limit, allowed)
    head = stream.words(0, 1)
    if head is None:
        return f"its binary data header ({layout.word_size} bytes) cannot be decoded"
    (length,), room = head, stream.room(0) - layout.word_size
    if length > limit:
        return f"its binary data header declares {length} bytes; allowed: at most {allowed}"
    if length > room:
        return f"its binary data header declares {length} bytes, past the end of the data ({room} bytes left)"
    return stream.foreign(-(-(layout.word_size + length) // 3) * 4)  # header and data encoded as one


def _compressed_problem(stream: _Stream, limit: int, allowed: str) -> str | None:
    size = stream.layout.word_size
    head = stream.words(0, 3)
    if head is None:
        return f"its compression header ({3 * size} bytes) cannot be decoded"
    n, block, last = head
    declares = f"its compression header declares {n} block(s) of {block} bytes (the last of {last})"
    if (3 + n) * size > stream.room(0):
        return (f"{declares}: {(3 + n) * size} bytes of header, past the end of the data "
                f"({stream.room(0)} bytes left)")
    if (n > 0 and block == 0) or last > block or (n == 0 and last > 0):
        return f"{declares}; allowed: a block size above 0 and a last block of at most the block size"
    total = 0 if n == 0 else (n - 1) * block + (last or block)
    if total > limit:
        return f"{declares}: {total} bytes uncompressed; allowed: at most {allowed}"
    sizes = stream.words(3, n) if n else ()
    if sizes is None:
        return f"{declares}, and the {n} compressed block sizes that follow cannot be decoded"
    room = stream.room(stream.header_length(3 + n))
    if sum(sizes) > room:
        return (f"{declares}, compressed to {sum(sizes)} bytes (block sizes {list(sizes[:4])}"
                f"{'...' if n > 4 else ''}): past the end of the data ({room} bytes left)")
    return stream.foreign(stream.header_length(3 + n) + -(-sum(sizes) // 3) * 4)  # the blocks encoded as one


class _Stream:
    """The binary data of one array: raw bytes, or base64 text, from ``start`` to at most ``stop``."""

    def __init__(self, layout: _Layout, start: int, stop: int, encoded: bool):
        self.layout, self.start, self.stop, self.encoded = layout, start, stop, encoded

    def header_length(self, words: int) -> int:
        """Characters (or bytes) taken by a header of ``words`` words encoded on its own."""
        n = words * self.layout.word_size
        return -(-n // 3) * 4 if self.encoded else n

    def room(self, skip: int) -> int:
        """Bytes left from ``skip`` (characters or bytes) into the data to the end (at most)."""
        left = max(self.stop - self.start - skip, 0)
        return left * 3 // 4 if self.encoded else left

    def foreign(self, chars: int) -> str | None:
        """Where the first ``chars`` characters of base64 data (all its header and data declare)
        hold one that is not base64, what it is; None for raw data. VTK's decoder skips nothing,
        white space included: the values read after it are shifted or never written (a comma in
        a .vtp's normals: 1e+277, 8e+291 on two reads of one file)."""
        if not self.encoded:
            return None
        for at in range(self.start, self.start + chars, _SCAN):
            window = bytes(self.layout.data[at : min(at + _SCAN, self.start + chars, self.stop)])
            bad = window.translate(None, _BASE64)
            if bad or at + len(window) < min(at + _SCAN, self.start + chars):
                where = at - self.start + (window.index(bad[:1]) if bad else len(window))
                what = f"{bad[:1].decode('latin-1')!r}" if bad else "the end of the text"
                return f"{what} at character {where} of its base64 data, within the {chars} its header declares"
        return None

    def words(self, first: int, count: int) -> tuple | None:
        """Header words ``first`` to ``first + count``, or None if they cannot be decoded.
        Base64 data are decoded from the start (the header is the stream's beginning)."""
        size = self.layout.word_size
        need = (first + count) * size
        chars = self.header_length(first + count)
        raw = bytes(self.layout.data[self.start : min(self.start + chars, self.stop)])
        if self.encoded:
            try:
                raw = base64.b64decode(raw, validate=True)
            except (binascii.Error, ValueError):
                return None
        if len(raw) < need:
            return None
        return struct.unpack(f"{self.layout.word[0]}{first + count}{self.layout.word[1]}", raw[:need])[first:]
