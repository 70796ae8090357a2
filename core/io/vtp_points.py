"""An XML PolyData (.vtp) file without its cells, for VTK to read the points of.

VTK trusts a file's cell topology: an ``offsets`` array whose last value is 10**12 (or
4 * 10**9) makes vtkXMLPolyDataReader allocate that many connectivity entries, and the failed
allocation aborts the process (``std::bad_alloc``, not an exception). Darboux reads only the
points and the point data, so VTK is given a copy of the file in which the ``<Verts>``,
``<Lines>``, ``<Strips>`` and ``<Polys>`` elements (with their inline arrays), the cell data
and the field data are removed and each ``<Piece>`` declares no cells: VTK never reads a cell.
Only the XML before ``<AppendedData>`` changes; the appended data are copied byte for byte
(the offsets of the arrays that remain count from their start), and the input is never
modified.
"""

from __future__ import annotations

import contextlib
import mmap
import os
import re
import tempfile

from .cloud import CloudFileError
from .vtp_tiling import check_tiling

_UNUSED = rb"Verts|Lines|Strips|Polys|CellData|FieldData"
_ELEMENT = re.compile(rb"<(" + _UNUSED + rb"|Piece)(?=[\s/>])((?:[^<>\"']|\"[^\"<]*\"|'[^'<]*')*)>")
_CELL_COUNT = re.compile(rb"(\sNumberOf(?:Verts|Lines|Strips|Polys)\s*=\s*)(\"[^\"]*\"|'[^']*')")
_LEFT_COUNT = re.compile(rb"NumberOf(?:Verts|Lines|Strips|Polys)(?=[\s=])(?!\s*=\s*\"0\")")
# what must not remain in the XML VTK parses: an unused element, a piece not rewritten, or a
# document type (whose entities could spell an element without writing it)
_LEFT = re.compile(rb"<(?:" + _UNUSED + rb"|Piece)(?=[\s/>])|<!DOCTYPE")
_CHUNK = 1 << 24
#: the root element's close, at the end of the file (white space and NUL padding after it)
_CLOSED, _TAIL = re.compile(rb"</VTKFile\s*>[\s\0]*\Z"), 4096


@contextlib.contextmanager
def points_only(path):
    """The path of a copy of ``path`` without cells, cell data or field data (a temporary file,
    deleted on leaving), or ``path`` itself when it has none; :class:`CloudFileError` when
    they cannot be separated safely."""
    copy = _copy(path)
    try:
        yield path if copy is None else copy
    finally:
        if copy is not None:
            os.unlink(copy)


def _copy(path) -> str | None:
    """The temporary copy's path, or None when the file has nothing to remove."""
    if os.path.getsize(path) == 0:
        return None
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as data:
        check_tiling(data, path)  # on the file itself: the copy names no cell arrays
        end = data.find(b"<AppendedData")
        end = len(data) if end < 0 else end
        parts = _parts(data, end, path)
        if parts == [(0, len(data))]:
            return None  # nothing to remove: VTK reads the file itself
        try:
            fd, copy = tempfile.mkstemp(prefix="darboux-", suffix=".vtp")
        except OSError as error:
            raise CloudFileError(path, f"cannot write its copy without cells: {error}") from None
        try:
            for part in parts:
                if isinstance(part, bytes):
                    _write_all(fd, part)
                else:
                    _copy_range(f.fileno(), fd, data, *part)
        except BaseException as error:
            os.close(fd)
            os.unlink(copy)
            if isinstance(error, OSError):  # a full disk
                raise CloudFileError(path, f"cannot write its copy without cells to {copy}: {error}") from None
            raise
        os.close(fd)
        return copy


def check_closed(data, path) -> None:
    """Refuse a file that does not end with its root element's closing tag: one cut after
    its points (in the cells, or in the appended data after the points) was read as it
    was, VTK reading the points and the copy taking no cells; an XML document ends with
    the close of its root, and every VTK writer ends a .vtp with ``</VTKFile>`` (a file
    without the root's start is VTK's to name)."""
    if data.find(b"<VTKFile", 0, 1 << 16) >= 0 and _CLOSED.search(data, max(0, len(data) - _TAIL)) is None:
        raise CloudFileError(path, "truncated: it does not end with the closing </VTKFile> tag a .vtp file ends "
                                   "with (the file was cut short)")


def _parts(data, end: int, path) -> list:
    """The copy, as ``(start, stop)`` ranges of ``data`` and rewritten ``<Piece>`` tags (bytes)."""
    parts, pos, after_tag = [], 0, True
    while True:
        match = _ELEMENT.search(data, pos, end)
        if match is None:
            break
        name, tag = match.group(1), match.group(0)
        after_tag = _ends_with_tag(data, pos, match.start(), after_tag)
        parts.append((pos, match.start()))
        if name == b"Piece":
            parts.append(_CELL_COUNT.sub(rb'\1"0"', tag))
            pos, after_tag = match.end(), True
            continue
        if not after_tag:  # the text on either side would join into markup of its own
            raise CloudFileError(path, f"its <{name.decode()}> element does not follow a tag")
        pos = match.end() if match.group(2).rstrip().endswith(b"/") else _closing(data, match, end, path)
    parts.append((pos, len(data)))
    parts = [part for part in parts if not isinstance(part, tuple) or part[0] < part[1]]
    _check(data, parts, end, path)
    return parts


def _ends_with_tag(data, start: int, stop: int, before: bool) -> bool:
    """Whether ``data[start:stop]`` ends with '>' and white space (``before`` if all white)."""
    i = stop
    while i > start and data[i - 1 : i].isspace():
        i -= 1
    return before if i == start else data[i - 1 : i] == b">"


def _closing(data, match, end: int, path) -> int:
    name = match.group(1)
    close = re.compile(rb"</" + name + rb"\s*>").search(data, match.end(), end)
    if close is None:
        raise CloudFileError(path, f"its <{name.decode()}> element is not closed")
    return close.end()


def _check(data, parts: list, end: int, path) -> None:
    """Refuse the file if the XML VTK would parse still holds an unused element, a cell count
    or a document type (as in malformed XML the search above does not recognize)."""
    for part in parts:
        if isinstance(part, bytes):
            found = _LEFT_COUNT.search(part)
        elif part[0] < end:
            found = _LEFT.search(data, part[0], min(part[1], end))
        else:
            found = None
        if found:
            raise CloudFileError(path, f"its XML cannot be read without its cells (at {found.group(0)[:40]!r})")


def _copy_range(source: int, target: int, data, start: int, stop: int) -> None:
    """Bytes ``start:stop`` of the source appended to the target: in the kernel where it can
    (``copy_file_range``), else through memory in chunks."""
    while start < stop:
        try:
            done = os.copy_file_range(source, target, min(stop - start, 1 << 30), start)
        except (AttributeError, OSError):
            break
        if done <= 0:
            break
        start += done
    for chunk in range(start, stop, _CHUNK):
        _write_all(target, data[chunk : min(chunk + _CHUNK, stop)])


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]
