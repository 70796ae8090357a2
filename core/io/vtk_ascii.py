"""The arrays of a legacy VTK file in ASCII that end early, refused before VTK reads them.

VTK 9.7 reads an ASCII array of floats short of its declared count without an error message
or code when the file ends just after a number: the values the file lacks are whatever memory
held (1e+259, 2e-312, NaN or plausible numbers in a file cut inside its POINTS or NORMALS),
garbage that passed as points, normals or fields. (When a newline or the next section follows
the short array, VTK says "Error reading ascii data", naming no section.) The file's sections
are walked here as VTK reads them: each array's numbers are counted up to the next line that
starts with a word, numpy counting a chunk at a time.
"""

from __future__ import annotations

import re

import numpy as np

from .cloud import CloudFileError

#: a line that starts with a word, not a number (nan, inf are numbers): the next section's (the
#: newline before it matched too: a pattern that starts with a byte is searched for several times faster)
_KEYWORD = re.compile(rb"\n[ \t]*(?![+-]?(?:nan|inf))[a-z_]", re.I)
_POINTS = re.compile(rb"^[ \t]*points[ \t]", re.I | re.M)
_WORD = re.compile(rb"[^ \t\r\n\v\f]")
#: the line that ends an array's METADATA block, an empty one
_BLANK = re.compile(rb"^\r?$", re.M)
#: data arrays a file may hold: VTK adds each to its point or field data after a search of the
#: names before it, so reading n of them takes n**2 (40,000 in a 2.4 MB file: 19 s)
MAX_ARRAYS = 10_000
#: bytes counted at a time (1 MB: its temporaries stay in the processor's cache)
_CHUNK = 1 << 20
#: each byte's class for counting numbers: 0 other, 1 white space, 2 sign, 3 digit or point
_CLASS = np.zeros(256, dtype=np.uint8)
_CLASS[list(b" \t\r\n\v\f")] = 1
_CLASS[list(b"+-")] = 2
_CLASS[list(b"0123456789.")] = 3
#: the pairs (class before * 4 + class) that start a number: any byte after white space, a sign
#: after a digit or a point (VTK reads "1-2" as 1 and -2)
_STARTS = np.zeros(16, dtype=bool)
_STARTS[[4 + 0, 4 + 2, 4 + 3, 12 + 2]] = True
_SIGN_AFTER = re.compile(rb"[0-9.][+-]")
#: white space VTK cannot read a keyword after (see _Walk._check_gap), within the bytes looked at before it
_SPACES, _GAP_WINDOW = re.compile(rb"[ \r]{256,}"), 4096
#: point or cell data sections: their first word (VTK compares its start, in this order), values
#: per point or cell, the header word that multiplies them and the one naming their type (if any)
_ATTRIBUTES = ((b"vectors", 3, None, 2), (b"tensors6", 6, None, 2), (b"tensors", 9, None, 2),
               (b"normals", 3, None, 2), (b"texture_coordinates", 1, 2, 3), (b"global_ids", 1, None, 2),
               (b"pedigree_ids", 1, None, 2), (b"edge_flags", 1, None, 2), (b"color_scalars", 1, 2, None))
_STRINGS = (b"string", b"utf8_string")  # (type names VTK compares by their start) one value a line, any text


def check_ascii_arrays(path, data, body: int) -> list:
    """Each array of the ASCII legacy file ``data`` after ``body`` (where its header lines end)
    holds at least the numbers it declares before the next section: the dataset's POINTS (or
    X/Y/Z_COORDINATES), every array of its POINT_DATA and CELL_DATA (SCALARS, NORMALS, VECTORS,
    TENSORS, TEXTURE_COORDINATES, COLOR_SCALARS, ids, LOOKUP_TABLE) and of every FIELD section.
    Where the walk cannot follow the file (an array header it cannot parse) it stops, and the
    first POINTS section after that is still checked. Returns the dataset's FIELD sections (before
    its point and cell data) as (where the line starts, where it ends or None if not followed)."""
    walk = _Walk(path, data)
    pos, last = walk.walk(body)
    if pos is None and not walk.points and (match := _POINTS.search(data, last + 1)):
        walk.section(match.start())
    return walk.fields


class _Walk:
    """The sections of one file read in turn (see check_ascii_arrays). What differs between
    ASCII and binary files (:class:`core.io.vtk_binary._BinaryWalk`): where the next section
    starts (:meth:`_next`), how an array is measured (:meth:`_array`) and what the walk does
    with a section it does not check (:meth:`_other`)."""

    def __init__(self, path, data):
        self.path, self.data = path, data
        self.count, self.owner = None, ""  # the current POINT_DATA or CELL_DATA count and its line
        self.points = False  # a POINTS section was checked
        self.fields = []  # the dataset's FIELD sections: (start, end or None)
        self.arrays = 0  # the arrays measured so far

    def walk(self, pos: int):
        """Check the sections from ``pos``: (None if the walk stopped, where the last one starts)."""
        last, arrays = pos, self.arrays
        while pos is not None and (keyword := self._next(pos)) is not None:
            if self.arrays > arrays:  # after an array's data
                self._check_gap(pos, _WORD.search(self.data, keyword).start())
            last, arrays, pos = keyword, self.arrays, self.section(keyword)
        if pos is not None and self.arrays > arrays:
            self._check_gap(pos, len(self.data))
        return pos, last

    def _gap_floor(self, pos: int) -> int:
        """Where the white space before the next keyword can start: after the last number (in ASCII)."""
        return 0

    def _check_gap(self, pos: int, stop: int) -> None:
        """Refuse a run of 256 or more spaces and carriage returns in the white space between an
        array's data and the keyword at ``stop`` (or the file's end): VTK's reader never returned
        (a tab, a newline or a number between shorter runs, such a run inside the data or after
        a header line, read)."""
        window = bytes(self.data[max(self._gap_floor(pos), stop - _GAP_WINDOW) : stop])
        run = _SPACES.search(window, len(window.rstrip(b" \t\r\n\v\f")))
        if run:
            before = "the file's end" if stop == len(self.data) else repr(_shown(self._line(stop)[1]))
            raise CloudFileError(self.path, f"holds a run of {run.end() - run.start()}+ spaces (or carriage returns) "
                                            f"before {before}, at byte {stop - len(window) + run.start()}: VTK's reader "
                                            "never returns from one where it reads a keyword; allowed: fewer than 256")

    def _next(self, pos: int) -> int | None:
        """Where the next section starts: the first line from ``pos`` that starts with a word."""
        return _next_keyword(self.data, pos)

    def _other(self, key: bytes, end: int) -> int | None:
        """Where the walk goes on after a section it does not check (cells, dimensions...): its
        numbers are skipped to the next keyword."""
        return end

    def section(self, start: int) -> int | None:
        """Check the section whose line starts at ``start``; where the walk goes on, or None."""
        end, words = self._line(start)
        key = words[0].lower()
        if key.startswith((b"point_data", b"cell_data")):
            self.count, self.owner = _number(words, 1), _shown(words)
            return end
        if key.startswith(b"metadata"):
            return self._after_metadata(start)
        if key.startswith(b"field"):
            after = self._field(words, end)
            if self.count is None:
                self.fields.append((start, after))
            return after
        if key.startswith(b"scalars"):
            return self._scalars(words, start, end)
        declared = _declared(key, words, self.count)
        if declared is None:
            return self._other(key, end)
        self.points = self.points or key.startswith(b"points")
        return self._array(words, start, *declared)[1]

    def _scalars(self, words, start: int, end: int) -> int | None:
        """SCALARS name type [components], then LOOKUP_TABLE name (on the next line, as written)."""
        lowered = [word.lower() for word in words]
        table = lowered.index(b"lookup_table") if b"lookup_table" in lowered else len(words)
        components = _number(words, 3) if table > 3 else 1
        header = table + 2  # the values follow the table's name
        if table == len(words):
            start, header = self._next(end), 2
            if start is None:
                return None
            if not self._line(start)[1][0].lower().startswith(b"lookup_table"):
                return start  # VTK refuses scalars without a lookup table
        if not 0 < (components or 0) < 2**31 or self.count is None or table < 3:  # VTK reads an int, or stops
            return self._other(b"", self._line(start)[0])
        return self._array(words, start, header, self.count * components, words[2])[1]

    def _field(self, words, end: int) -> int | None:
        """FIELD name nArrays, each array 'name numComponents numTuples dataType' then its values."""
        arrays, field, pos = _number(words, 2), _shown(words), end
        for _ in range(max(arrays or 0, 0)):
            head = _WORD.search(self.data, pos)
            if head is not None and self.data[head.start() : head.start() + 8].lower() == b"metadata":
                head = _WORD.search(self.data, self._after_metadata(head.start()) or len(self.data))
            if head is None:
                return None
            array = self._line(head.start())[1]
            if array[0] == b"NULL_ARRAY":
                pos = head.start() + len(array[0])
                continue
            components, tuples = _number(array, 1), _number(array, 2)
            if components is None or tuples is None or len(array) < 4:
                return None  # VTK refuses it, or reads what this walk cannot follow
            have, pos = self._array(array, head.start(), 4, components * tuples, array[3], field)
            if pos is None or (have is not None and have > components * tuples):
                return None  # the next array's header is among these numbers: a name that starts with a digit?
        return pos

    def _array(self, words, start: int, header: int, need: int, kind: bytes, field: str = ""):
        """(numbers, where the walk goes on) for the array whose header ``words`` (the first
        ``header`` of them its own) start at ``start``: refused if fewer than ``need`` numbers
        follow before the next keyword. VTK reads words: values on the header's line count."""
        self.count_array(words)
        line_end = self._line(start)[0]
        if kind.lower().startswith(_STRINGS):  # the rest of the header's line, then a line each
            return None, _after_lines(self.data, line_end, need)
        if kind.lower().startswith(b"variant"):
            return None, None  # a type and a word for each value: not followed
        after = _next_keyword(self.data, line_end)
        stop = len(self.data) if after is None else after
        have = _words(self.data, start, stop) - header
        if have < need:
            where = "before the file ends" if after is None else f"before {_shown(self._line(after)[1])!r}"
            self._short(words, need, f" but {have} follow {where}", field)
        return have, stop

    def count_array(self, words) -> None:
        """One array more; refused beyond :data:`MAX_ARRAYS`, before VTK's quadratic read of them."""
        self.arrays += 1
        if self.arrays > MAX_ARRAYS:
            raise CloudFileError(self.path, f"holds more than {MAX_ARRAYS:,} data arrays (the next: {_shown(words)!r}); "
                                            f"a point cloud's file is read with at most {MAX_ARRAYS:,}")

    def _short(self, words, need: int, held: str, field: str):
        """Refuse the array of header ``words`` that declares ``need`` values: ``held`` says what follows."""
        key = words[0].lower()
        if field:
            title, per = f"FIELD array {_shown(words)!r} of {field!r}", "values"
        elif key.startswith(b"points") or key[1:].startswith(b"_coordinates"):
            title, per = f"{_shown(words[:1])} section: {_shown(words)!r}", "coordinates"
        else:
            title = f"{_shown(words[:1])} section: {_shown(words)!r}"
            per = "values" if key.startswith(b"lookup_table") or not self.owner else f"values ({self.owner})"
        raise CloudFileError(self.path, f"truncated or corrupt {title} declares {need} {per}{held}")

    def _after_metadata(self, start: int) -> int | None:
        """Where the METADATA block (after an array) starting at ``start`` ends: component names,
        information keys, any text up to an empty line."""
        blank = _BLANK.search(self.data, self._line(start)[0])
        return min(blank.end() + 1, len(self.data)) if blank else None

    def _line(self, start: int):
        """(where the line from ``start`` ends, after its newline; its words, at least one)."""
        end = self.data.find(b"\n", start)
        end = len(self.data) if end < 0 else end + 1
        return end, bytes(self.data[start : min(end, start + 4096)]).split() or [b""]


def _next_keyword(data, pos: int) -> int | None:
    """Where the first line from ``pos`` (not before it) that starts with a word starts, or None."""
    match = _KEYWORD.search(data, max(pos - 1, 0))
    return None if match is None else match.start() + 1


def _declared(key: bytes, words, count):
    """(header words, numbers, data type) that an array's header ``words`` declares, or None: not an array
    the walk checks, or one VTK refuses (a count that is not a number)."""
    if key.startswith(b"points") or (key[:1] in (b"x", b"y", b"z") and key[1:].startswith(b"_coordinates")):
        size = _number(words, 1)
        return None if size is None or len(words) < 3 else (3, size * (3 if key[:1] == b"p" else 1), words[2])
    if key.startswith(b"lookup_table"):  # name size, then size RGBA rows
        size = _number(words, 2)
        return None if size is None else (3, 4 * size, b"float")
    return None if count is None else _attribute(key, words, count)


def _attribute(key: bytes, words, count: int):
    """(header words, numbers, data type) of a point or cell data array (see _ATTRIBUTES), or None."""
    spec = next((spec for spec in _ATTRIBUTES if key.startswith(spec[0])), None)
    if spec is None:
        return None
    _, per, factor, kind = spec
    times = 1 if factor is None else _number(words, factor)
    if times is None or (kind is not None and len(words) <= kind):
        return None
    header = 1 + max(i for i in (factor, kind) if i is not None)  # words, the keyword's included
    return header, count * per * times, b"float" if kind is None else words[kind]


def _number(words, i: int) -> int | None:
    try:
        return int(words[i])
    except (IndexError, ValueError):
        return None


def _shown(words) -> str:
    """A header line as its words, for a message (at most 80 characters)."""
    text = b" ".join(words).decode("latin-1")
    return text if len(text) <= 80 else text[:77] + "..."


def _words(data, start: int, stop: int) -> int:
    """The numbers VTK reads in ``data[start:stop]``, counted chunk by chunk: whitespace-separated
    words, and one more for a sign after a digit or a point (a few bytes: counted by bytes' methods)."""
    if stop - start <= 4096:
        text = bytes(data[start:stop])
        return len(text.split()) + len(_SIGN_AFTER.findall(text))
    count, before = 0, 1  # as after white space
    for lo in range(start, stop, _CHUNK):
        kinds = _CLASS[np.frombuffer(data, np.uint8, min(_CHUNK, stop - lo), lo)]
        count += int(np.count_nonzero(_STARTS[kinds[:-1] * np.uint8(4) + kinds[1:]])) + int(_STARTS[4 * before + kinds[0]])
        before = int(kinds[-1])
    return count


def _after_lines(data, start: int, lines: int) -> int | None:
    """Where the ``lines``-th line from ``start`` ends (after its newline), or None if the file ends first."""
    if lines <= 0:
        return start
    for lo in range(start, len(data), _CHUNK):
        ends = np.flatnonzero(np.frombuffer(data, np.uint8, min(_CHUNK, len(data) - lo), lo) == 10)
        if len(ends) >= lines:
            return lo + int(ends[lines - 1]) + 1
        lines -= len(ends)
    return None
