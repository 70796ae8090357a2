"""A legacy ``.vtk`` file's declarations that crashed VTK (a segmentation fault), checked before
VTK reads it: its cell arrays' counts and runs, its dataset's FIELD sections, and (through
:mod:`core.io.vtk_binary` and :mod:`core.io.vtk_ascii`) the values of its arrays."""

from __future__ import annotations

import mmap
import re

import numpy as np

from .cloud import CloudFileError
from .vtk_binary import LINE_BUFFER, WORDS, check_arrays, new_cells
from .vtk_messages import first_message, vtk_messages, vtk_output


#: a cell array's line: VTK reads its two counts as words, whatever follows them on the line
#: the patterns that find a keyword at a line's start begin with the newline before it, not ``^`` in
#: MULTILINE mode: re then scans for that byte, where ``^`` was tried at every byte of the binary
#: data (checks of a 224 MB binary file 4.9 -> 1.1 s, of a 127 MB ASCII one 3.0 -> 1.3 s); the first
#: lines are the header
_CELLS = re.compile(rb"\n(VERTICES|LINES|POLYGONS|TRIANGLE_STRIPS|CELLS)[ \t]+(-?\d+)[ \t]+(-?\d+)(?!\d)")


def check_legacy(path) -> None:
    """What a legacy file declares that crashed VTK (a segmentation fault), checked before VTK
    reads it, on one mapping of the file: its cell arrays (:func:`_check_cells`), its dataset's
    field data (:func:`_check_field_data`) and the values of its arrays (points, point and cell
    data, field data: :func:`core.io.vtk_ascii.check_ascii_arrays` counts an ASCII file's numbers,
    :func:`core.io.vtk_binary.check_binary_arrays` a binary file's bytes; VTK returns garbage for
    the missing ones)."""
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        lines, body = _legacy_header(data)
        _check_cell_counts(path, data)
        _check_cells(path, data, lines, body)
        ends = dict(check_arrays(path, data, lines, body))  # the dataset's FIELD sections the walk found
        first = _dataset_field(data, body)  # the first, found wherever VTK reads a word (the walk reads lines)
        starts = ([first] if first is not None else []) + [s for s in ends if first is None or s > first]
        fields = [_field_section(data, lines, start, ends.get(start)) for start in starts]  # a second one crashed VTK too
    for keyword, text in fields:
        _check_field_data(path, keyword, text)


def _check_cells(path, data, lines, body) -> None:
    """A legacy file before version 5.0 stores each cell array as runs of (count, ids...);
    VTK walks the counts without checking them against the array's size, and a corrupt
    count crashes the process. The runs are checked here first (``lines``, ``body``: the
    file's header lines and where its body starts, :func:`_legacy_header`)."""
    if new_cells(lines) or body >= len(data):
        return  # offsets and connectivity, which VTK checks
    binary = lines[2].strip().upper() == b"BINARY"
    for match in _CELLS.finditer(data):
        size, start = int(match.group(3)), match.end()
        if binary:
            start = _binary_start(path, data, match)
            if start + 4 * size > len(data):
                raise CloudFileError(path, f"truncated: {match.group(0).decode().strip()!r} declares {size} "
                                           "cell entries but the file ends first")
            ids = np.frombuffer(data, ">i4", count=size, offset=start).astype(np.int64)
        else:
            try:
                ids = np.array(bytes(data[start : start + 32 * size + 64]).split(maxsplit=size)[:size], np.int64)
            except (ValueError, OverflowError):
                return  # VTK names the bad entry
        problem = _cell_runs_problem(ids, int(match.group(2)), size)
        if problem:
            raise CloudFileError(path, f"corrupt {match.group(1).decode()} section: {problem}")


def _binary_start(path, data, match) -> int:
    """Where VTK starts reading the binary ids of the cell array on ``match``'s line: after the
    line's newline. Bytes between the counts and the newline are skipped: a newline lost in
    a damaged file moves the ids to the next line's end (text read as ids, a segmentation
    fault), so the check reads them where VTK will; 256 bytes or more after the counts without a
    newline are refused (VTK's read of the line fails and leaves the ids unread)."""
    end = data.find(b"\n", match.end(), match.end() + LINE_BUFFER)  # (getline stores up to 255 bytes)
    if end < 0:
        raise CloudFileError(path, f"corrupt {match.group(1).decode()} section: the line "
                                   f"{match.group(0).decode().strip()!r} has no end before its binary data")
    return end + 1


_NEGATIVE_POINTS = re.compile(rb"\nPOINTS[ \t]+-\d+")


def _check_cell_counts(path, data) -> None:
    """A negative count on a cell array's line: VTK read the binary offsets and connectivity
    of a version 5 file (from a count of -1) past their array, a segmentation fault."""
    for match in _CELLS.finditer(data):
        if match.group(2).startswith(b"-") or match.group(3).startswith(b"-"):
            raise CloudFileError(path, f"corrupt {match.group(1).decode()} section: "
                                       f"{match.group(0).decode().strip()!r} declares a negative count")
    points = _NEGATIVE_POINTS.search(data)  # -2147483649 points in a binary file: the same crash
    if points:
        raise CloudFileError(path, f"corrupt POINTS section: {points.group(0).decode().strip()!r} declares a "
                                   "negative count")


def _legacy_header(data) -> tuple[list, int]:
    """The first 3 lines of a legacy file (version, title, ASCII or BINARY) as VTK reads them
    (up to 255 bytes each, the rest of a line skipped), and where the line after them starts.
    A line may be of any length: a header that did not fit in 512 bytes skipped the checks."""
    lines, pos = [], 0
    for _ in range(3):
        end = data.find(b"\n", pos)
        end = len(data) if end < 0 else end
        lines.append(bytes(data[pos : min(end, pos + 255)]))
        pos = end + 1
    return lines, min(pos, len(data))


def _cell_runs_problem(ids, n_cells: int, size: int) -> str | None:
    """What is wrong with ``n_cells`` runs of (count, ids...) in ``ids``, or None."""
    step = int(ids[0]) + 1 if len(ids) else 0
    if step > 0 and len(ids) == n_cells * step and (ids[::step] == step - 1).all():
        return None  # cells of one size (all vertices, all triangles...): no walk needed
    ids = ids.tolist()
    i = 0
    for cell in range(n_cells):
        if i >= len(ids):  # it said "cell 11 declares None point ids"
            return f"cell {cell} of {n_cells} has no entries left: {len(ids)} of the {size} declared entries follow"
        count = ids[i]
        if count < 0 or i + 1 + count > len(ids):
            return (f"cell {cell} declares {count} point ids where {max(len(ids) - i - 1, 0)} of the {size} "
                    "entries remain")
        i += 1 + count
    if i != len(ids):  # VTK walks the runs to the end of the array, not for n_cells: a count left over is read as one
        return f"the {n_cells} cells take {i} of the {size} entries; the rest would be read as more cells"
    return None


#: a dataset's own field data: a FIELD keyword (VTK compares 5 letters; a word anywhere in a
#: line, as VTK reads words) before POINT_DATA and CELL_DATA
_DATASET_FIELD = re.compile(rb"[\n \t](field\w*)[ \t\r\n]", re.I)
_ATTRIBUTES = re.compile(rb"\n[ \t]*(point_data|cell_data)\b", re.I)


def _dataset_field(data, body: int) -> int | None:
    """Where the keyword of the dataset's first FIELD section (before its point and cell data) starts, or None."""
    attributes = _ATTRIBUTES.search(data, body - 1)  # from the newline that ends the header
    match = _DATASET_FIELD.search(data, body - 1, attributes.start() + 1 if attributes else len(data))
    return None if match is None else match.start(1)


def _field_section(data, lines, start: int, end: int | None) -> tuple[str, bytes]:
    """(keyword, text) of the FIELD section whose keyword starts at ``start``: the file's 3 header
    lines, then the section up to ``end`` (where the array walk found it ends; None: the rest of
    the file), what :func:`_check_field_data` hands VTK's field parser. Bounded, a 192 MB binary
    file's check peaked at 905 MB: the rest of the file copied twice, then by VTK."""
    keyword = WORDS.match(data, start).group(0)
    return keyword.decode("latin-1"), b"\n".join([*lines, data[start + len(keyword) : end]])


def _check_field_data(path, keyword, text) -> None:
    """VTK's legacy dataset readers use a dataset's FIELD section even when they failed to
    read it (fewer arrays than declared, a bad array header): a segmentation fault, the second
    such section too. The section (``text``, :func:`_field_section`) is read first on its own
    with VTK's own field data parser. (A FIELD inside POINT_DATA or CELL_DATA that VTK fails
    to read is dropped: its reader checks.)"""
    from vtkmodules.vtkIOLegacy import vtkDataReader

    reader = vtkDataReader()
    reader.ReadFromInputStringOn()
    reader.SetBinaryInputString(text, len(text))
    with vtk_messages() as window:
        read = reader.OpenVTKFile() and reader.ReadHeader() and reader.ReadFieldData() is not None
        reader.CloseVTKFile()
    if not read:
        raise CloudFileError(path, f"corrupt {keyword} section (the dataset's field data): VTK cannot read it: "
                                   f"{first_message(vtk_output(window))}")
