"""VTK legacy (.vtk) and XML PolyData (.vtp) files, read with VTK (imported lazily).

The points of any point set (polydata, unstructured grid, ...) are read; the point data's
normals array (or a 3-component array called normals) gives the normals; other point data
arrays become fields (3 components give name_x/_y/_z). Cells are ignored (a .vtp's are
removed before VTK reads it: see :mod:`.vtp_points`). VTK reports
problems through its output window, which is captured while reading so that a failure
becomes a :class:`CloudFileError` instead of a message on stderr.
"""

from __future__ import annotations

import contextlib
import json
import mmap
import os
import re

import numpy as np

from .._memory import available_memory
from .cloud import CloudFileError, RawCloud, check_memory, split_components
from .vtk_binary import LINE_BUFFER, WORDS, check_arrays, new_cells
from .vtp_blocks import Tags, check_binary_headers
from .vtp_points import check_closed, points_only
from .xml_scan import scan_xml


def read_vtk(path) -> RawCloud:
    """A legacy ``.vtk`` file (ascii or binary)."""
    from vtkmodules.vtkIOLegacy import vtkGenericDataObjectReader

    check_legacy(path)
    reader = vtkGenericDataObjectReader()
    for option in ("ReadAllScalarsOn", "ReadAllVectorsOn", "ReadAllNormalsOn", "ReadAllFieldsOn"):
        getattr(reader, option)()
    return _read(reader, path)


def read_vtp(path) -> RawCloud:
    """An XML PolyData ``.vtp`` file."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    with points_only(path) as copy:  # VTK never reads the cells: damaged ones aborted it
        try:
            check_vtp(copy, available_memory())
            return _read(vtkXMLPolyDataReader(), copy)
        except CloudFileError as error:
            if copy is path:
                raise
            raise CloudFileError(path, error.problem.replace(str(copy), str(path))) from None


def _read(reader, path) -> RawCloud:
    _update_quietly(reader, path)
    data = reader.GetOutputDataObject(0)
    if data is None or not hasattr(data, "GetPoints"):
        kind = "nothing" if data is None else data.GetClassName()
        raise CloudFileError(path, f"contains {kind}, not a point set")
    _check_implicit_points(data, path)
    if data.GetPoints() is None or data.GetNumberOfPoints() == 0:
        return RawCloud(np.empty((0, 3)), None, {})
    from vtkmodules.util.numpy_support import vtk_to_numpy

    points = vtk_to_numpy(data.GetPoints().GetData())
    normals, fields = _point_data(data.GetPointData(), path, len(points))
    return RawCloud(np.array(points), None if normals is None else np.array(normals), fields)


def _update_quietly(reader, path) -> None:
    """Run the reader with VTK's messages captured; an error message is a CloudFileError."""
    reader.SetFileName(str(path))
    with _vtk_messages() as window:
        reader.Update()
    messages = _output(window)
    if "error" in messages.lower():
        raise CloudFileError(path, f"VTK cannot read it: {_first_message(messages)}")


@contextlib.contextmanager
def _vtk_messages():
    """VTK's messages captured in the vtkStringOutputWindow yielded, not printed."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

    window, previous = vtkStringOutputWindow(), vtkOutputWindow.GetInstance()
    verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    vtkOutputWindow.SetInstance(window)
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        yield window
    finally:
        vtkOutputWindow.SetInstance(previous)
        vtkLogger.SetStderrVerbosity(vtkLogger.ConvertToVerbosity(verbosity))


def _output(window) -> str:
    messages = window.GetOutput()
    if isinstance(messages, bytes):  # VTK hands back bytes when a message is not valid UTF-8
        messages = messages.decode("utf-8", "replace")
    return messages


def _point_data(point_data, path, n: int):
    """``(normals or None, fields)``: the normals array (or a 3-component array called
    normals) and every other numeric point-data array; each must hold a tuple per point (a
    legacy file's FIELD inside its POINT_DATA may declare any number, which VTK keeps)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    normals_array = point_data.GetNormals()
    normals = None if normals_array is None else vtk_to_numpy(normals_array)
    fields = {}
    for i in range(point_data.GetNumberOfArrays()):
        array = point_data.GetArray(i)  # None for string arrays
        if array is None or array is normals_array:
            continue
        name = array.GetName() or f"array{i}"
        if array.GetNumberOfTuples() != n:
            raise CloudFileError(path, f"point data array {name!r} holds {array.GetNumberOfTuples()} tuples "
                                       f"for {n} points")
        values = vtk_to_numpy(array)
        if normals is None and name.lower() in ("normals", "normal") and values.ndim == 2 and values.shape[1] == 3:
            normals = values
            continue
        fields.update(split_components(name, values))
    return normals, fields


def _first_message(text: str) -> str:
    """The first VTK message without its 'ERROR: In file, line N' and 'vtkClass (0x...):' prefixes."""
    for line in text.splitlines():
        line = line.strip()
        if not line or re.match(r"^(ERROR|Warning|Generic Warning|Generic Error): In ", line):
            continue
        return re.sub(r"^vtk\w+ \(0x[0-9a-fA-F]+\): ", "", line)
    return "unknown VTK error"


def _check_implicit_points(data, path) -> None:
    """Image data and rectilinear grids do not store their points: a 100-byte header can
    declare 10**15, and building their coordinates would take the machine's memory."""
    if data.IsA("vtkPointSet"):
        return
    n = data.GetNumberOfPoints()
    need = n * 3 * 8 * 4  # float64 coordinates and numpy's temporaries while building them
    check_memory(path, need, f"a {data.GetClassName()} of {n} points: building their coordinates needs")


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
    with _vtk_messages() as window:
        read = reader.OpenVTKFile() and reader.ReadHeader() and reader.ReadFieldData() is not None
        reader.CloseVTKFile()
    if not read:
        raise CloudFileError(path, f"corrupt {keyword} section (the dataset's field data): VTK cannot read it: "
                                   f"{_first_message(_output(window))}")


_COUNT = re.compile(r"[ \t\r\n]*([0-9]+)[ \t\r\n]*")  # a count, with the white space XML allows
_LARGEST = 2**63 - 1  # VTK's counts are vtkIdType


def check_vtp(path, available: int) -> None:
    """VTK allocates what an XML file's NumberOf... attributes declare before reading any
    data, and a failed allocation aborts the process (std::bad_alloc, not an exception); a
    huge NumberOfComponents kept it busy for minutes, and it read NumberOfPoints="1e12" as 1.
    The XML VTK parses is parsed here first, once, by expat as in VTK (any quotes, spaces,
    character references, comments): each NumberOf... must be decimal digits, and the arrays
    they declare must fit in memory (``available`` bytes) and, when not compressed, in the
    file; then the binary arrays' headers are checked on the same parse
    (:func:`core.io.vtp_blocks.check_binary_headers`)."""
    if os.path.getsize(path) == 0:
        return
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        sizes, tags = _Sizes(path, len(data)), Tags()
        scan_xml(data, _Both(sizes, tags), path)
        sizes.check()
        check_binary_headers(data, tags, available, path)
        check_closed(data, path)  # after the checks above, which say more of a file cut in its arrays


class _Both:
    """Two :func:`core.io.xml_scan.scan_xml` handlers on one parse (the second one's end tags too)."""

    def __init__(self, first, second):
        self.first, self.second = first, second

    def start(self, name: str, attrs: dict, pos: int) -> None:
        self.first.start(name, attrs, pos)
        self.second.start(name, attrs, pos)

    def end(self, name: str) -> None:
        self.second.end(name)


class _Sizes:
    """The sizes an XML file declares, read from each start tag expat reports (see check_vtp)."""

    def __init__(self, path, file_size: int):
        self.path, self.file_size = path, file_size
        self.largest = ("NumberOfPoints", 0)  # the largest count but NumberOfComponents
        self.components = 3  # the most components of an array (or 3, the points')
        self.compressed = False  # binary data are compressed: they can take less than a byte a value
        self.points = 0  # the current piece's NumberOfPoints
        self.unheld = None  # why the file cannot hold the first array that it cannot

    def start(self, element: str, attrs: dict, pos: int) -> None:
        counts = {name: self._count(element, name, value) for name, value in attrs.items()
                  if name.startswith("NumberOf")}
        for name, value in counts.items():
            if name == "NumberOfComponents":
                self.components = max(self.components, value)
            elif value > self.largest[1]:
                self.largest = (name, value)
        if element == "VTKFile":
            self.compressed = bool(attrs.get("compressor"))
        elif element == "Piece":
            self.points = counts.get("NumberOfPoints", 0)
        elif element in ("DataArray", "Array") and self.unheld is None:
            self.unheld = self._unheld(element, attrs, counts)

    def _count(self, element: str, name: str, value: str) -> int:
        match = _COUNT.fullmatch(value)
        digits = (match.group(1).lstrip("0") or "0") if match else ""
        if 0 < len(digits) <= 19 and int(digits) <= _LARGEST:
            return int(digits)
        shown = json.dumps(value if len(value) <= 40 else value[:40] + "...", ensure_ascii=False)
        raise CloudFileError(self.path, f"<{element}> declares {name}={shown}; allowed: a count in decimal digits "
                                        f"(no sign, point or exponent) of at most {_LARGEST}")

    def _unheld(self, element: str, attrs: dict, counts: dict) -> str | None:
        """Why the file cannot hold the array, or None: uncompressed, a value takes a byte (a bit
        for type Bit) or more; compressed (binary data with a compressor), any size."""
        if self.compressed and attrs.get("format") != "ascii":
            return None
        tuples = max(counts.get("NumberOfTuples", 0), self.points)
        components = counts.get("NumberOfComponents", 1)
        held = self.file_size * (8 if attrs.get("type") == "Bit" else 1)
        if tuples * components <= held:
            return None
        source = "NumberOfTuples" if tuples == counts.get("NumberOfTuples") else "NumberOfPoints"
        return (f"<{element}> {json.dumps(attrs.get('Name', '(unnamed)'))} declares {tuples * components} values "
                f'({source}="{tuples}" x NumberOfComponents="{components}"), uncompressed; allowed: at most '
                f"{held}, what the file's {self.file_size} bytes can hold")

    def check(self) -> None:
        """Refuse arrays that would not fit in memory, then one that does not fit in the file."""
        (name, value), components = self.largest, self.components
        declared = f' (NumberOfComponents="{components}")' if components > 3 else ""
        check_memory(self.path, 8 * value * components,
                     f'declares {name}="{value}" with arrays of up to {components} components{declared}:')
        if self.unheld:
            raise CloudFileError(self.path, self.unheld)
