"""The arrays of a legacy VTK file in BINARY that the file ends inside, refused before VTK reads them.

VTK 9.7 reads a binary array as its header's words, the rest of the line (up to 255 bytes), then
count x components x the type's size bytes of big-endian data, whatever follows them: a file
cut inside an array only drew a warning ("Error reading binary data!", naming no section) and
an array of whatever memory held. The sections are walked here as VTK reads them, with the
ASCII walk's structure (:class:`core.io.vtk_ascii._Walk`), each array measured by its bytes
rather than its numbers: an array whose bytes run past the end of the file is refused, naming
its section. The walk stops (refusing nothing) at what it cannot follow: string or variant
arrays, an unknown keyword or type, a header it cannot parse. It also reports the dataset's
FIELD sections, which VTK used even when it failed to read them (a segmentation fault).
"""

from __future__ import annotations

import ctypes
import re

from .vtk_ascii import _Walk, _number, check_ascii_arrays

#: bytes a value of each type takes in a binary file, in the order VTK compares the type's name
#: (``exact``: the whole name, else its start); 0 for bits (a bit each, the array padded to a byte)
_SIZES = ((b"bit", 0, False), (b"char", 1, True), (b"signed_char", 1, True), (b"unsigned_char", 1, False),
          (b"short", 2, False), (b"unsigned_short", 2, False), (b"vtkidtype", 4, False), (b"int", 4, False),
          (b"unsigned_int", 4, False), (b"long", ctypes.sizeof(ctypes.c_long), False),
          (b"unsigned_long", ctypes.sizeof(ctypes.c_long), False), (b"vtktypeint64", 8, False),
          (b"vtktypeuint64", 8, False), (b"float", 4, False), (b"double", 8, False))
#: sections of words only, no data (the others unknown to the walk stop it)
_TEXT = (b"dataset", b"dimensions", b"origin", b"spacing", b"aspect_ratio")
#: cell arrays: before version 5.0 a count line then 4-byte ids, since then OFFSETS and CONNECTIVITY arrays
_CELLS = (b"vertices", b"lines", b"polygons", b"triangle_strips", b"cells")
_SPACE = re.compile(rb"[ \t\r\n\v\f]*")
WORDS = re.compile(rb"[^ \t\r\n\v\f]+")
#: VTK reads the rest of an array's or a cell array's header line into a buffer of 256 bytes (getline
#: stores 255; :func:`core.io.vtk_legacy._binary_start` too)
LINE_BUFFER = 256


def check_arrays(path, data, lines, body) -> list:
    """The arrays' check of an ASCII or a BINARY file (as VTK reads the word, its start); its
    dataset's FIELD sections."""
    kind = lines[2].strip().upper()
    if kind.startswith(b"ASCII"):
        return check_ascii_arrays(path, data, body)
    if kind.startswith(b"BINARY"):
        return check_binary_arrays(path, data, body, not new_cells(lines))
    return []


def new_cells(lines) -> bool:
    """Whether the file's version (5.0 or later) stores its cells as offsets and connectivity."""
    version = re.match(rb"# vtk DataFile Version (\d{1,3})\.\d", lines[0])  # VTK reads "5'1" as no version
    return bool(version and 5 <= int(version.group(1)) <= 99)  # (a garbled version is read as legacy)


def check_binary_arrays(path, data, body: int, legacy_cells: bool) -> list:
    """Each array of the BINARY legacy file ``data`` after ``body`` (where its header lines end)
    holds the bytes it declares: POINTS (or X/Y/Z_COORDINATES), every array of its POINT_DATA
    and CELL_DATA and of every FIELD section; the cell arrays are stepped over (``legacy_cells``:
    the file is older than version 5.0, its ids checked by ``vtk_legacy._check_cells``). Returns the
    dataset's FIELD sections as :func:`core.io.vtk_ascii.check_ascii_arrays` does."""
    walk = _BinaryWalk(path, data, legacy_cells)
    walk.walk(body)
    walk.check_lost_bytes()
    return walk.fields


def _item_size(key: bytes, kind: bytes) -> int | None:
    """Bytes a value of type ``kind`` takes in the array of keyword ``key`` (0: a bit), or None:
    a type VTK refuses or that the walk does not follow (strings, variants)."""
    if key.startswith((b"lookup_table", b"color_scalars")):
        return 1  # RGBA bytes in a binary file, whatever the header says
    kind = kind.lower()
    for name, size, exact in _SIZES:
        if kind == name or (not exact and kind.startswith(name)):
            return size
    return None


class _BinaryWalk(_Walk):
    """The sections of one binary file read in turn (see check_binary_arrays)."""

    def __init__(self, path, data, legacy_cells: bool):
        super().__init__(path, data)
        self.legacy_cells = legacy_cells
        self.cell_counts = (0, 0)  # the OFFSETS and CONNECTIVITY values of a version 5 cell array
        self.spaced = False  # an array's data were followed by a line end, as VTK writes them
        self.suspect = None  # (header words, values, bytes) of the first array whose data end in a newline

    def section(self, start: int) -> int | None:
        """Check the section at ``start`` (cell arrays stepped over); where the walk goes on, or None."""
        end, words = self._line(start)
        key = words[0].lower()
        if key.startswith(_CELLS):
            n, size = _number(words, 1), _number(words, 2)
            if n is None or size is None:
                return None
            if self.legacy_cells:
                return self._array(words, start, 3, size, b"int")[1]
            self.cell_counts = (n, size)
            return end  # VTK reads OFFSETS next (nothing if the count is below 1)
        if key in (b"offsets", b"connectivity") and len(words) > 1:
            return self._array(words, start, 2, self.cell_counts[key == b"connectivity"], words[1])[1]
        if key.startswith(b"cell_types"):
            n = _number(words, 1)
            return None if n is None else self._array(words, start, 2, n, b"int")[1]
        return super().section(start)

    def _next(self, pos: int) -> int | None:
        """Where the next word starts (VTK reads keywords as words), or None at the file's end."""
        pos = _SPACE.match(self.data, pos).end()
        return pos if pos < len(self.data) else None

    def _gap_floor(self, pos: int) -> int:
        """The white space before a keyword starts after the data (whose bytes may be spaces)."""
        return pos

    def _other(self, key: bytes, end: int) -> int | None:
        """Only words follow a section of _TEXT; after any other, where binary data start is unknown."""
        return end if key.startswith(_TEXT) else None

    def _array(self, words, start: int, header: int, need: int, kind: bytes, field: str = ""):
        """(None, where the walk goes on: after the data) for the array whose header ``words``
        (the first ``header`` of them on the line at ``start``) declare ``need`` values of type
        ``kind``: its data start after the newline that ends that line, and it is refused if
        they run past the end of the file. (None, None) when the walk cannot follow it."""
        self.count_array(words)
        size, last = _item_size(b"" if field else words[0].lower(), kind), self._header_end(start, header)
        if size is None or last is None or need < 0:
            return None, None
        if need == 0:
            return None, last  # VTK reads no line and no data
        newline = self.data.find(b"\n", last, last + LINE_BUFFER)
        if newline < 0:
            return None, None  # VTK's read of the line fails
        nbytes = (need + 7) // 8 if size == 0 else need * size
        held = len(self.data) - newline - 1
        if nbytes > held:
            self._short(words, need, f", {nbytes} bytes, but {held} follow its header before the file ends", field)
        self._note_end(newline + 1 + nbytes, (words, need, nbytes, field))
        return None, newline + 1 + nbytes

    def _note_end(self, end: int, array) -> None:
        """Note how the data of ``array`` end at ``end``: followed by a line end (VTK's writers),
        or their last byte a newline with a word or the file's end right after it."""
        after = self.data[end : end + 1]
        if after in (b"\n", b"\r"):
            self.spaced = True
        elif self.data[end - 1 : end] == b"\n" and self.suspect is None and after not in (b" ", b"\t"):
            self.suspect = array

    def check_lost_bytes(self) -> None:
        """A byte lost inside an array: VTK reads the newline after its data as their last byte and
        every value after the lost one shifted (1e38, 1e304 in points within 3), then the next keyword,
        which needs no newline before it. A file whose data are written without line ends after them
        (read on purpose) may end an array with the byte 10 by chance; one that ends another array
        with a line end does not: there, an array whose data end in a newline is refused."""
        if self.spaced and self.suspect is not None:
            words, need, nbytes, field = self.suspect
            self._short(words, need, f", {nbytes} bytes, whose last is the line end that follows the other arrays' "
                                      "data: a byte short (a byte lost in it shifts every value after it)", field)

    def _header_end(self, start: int, header: int) -> int | None:
        """Where the ``header``-th word of the line at ``start`` ends, or None if the line has fewer."""
        end = self._line(start)[0]
        for i, match in enumerate(WORDS.finditer(self.data, start, end), 1):
            if i == header:
                return match.end()
        return None
