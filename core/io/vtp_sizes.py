"""The sizes an XML PolyData (``.vtp``) file declares, checked before VTK allocates them."""

from __future__ import annotations

import json
import mmap
import os
import re

from .cloud import CloudFileError, check_memory
from .vtp_blocks import Tags, check_binary_headers
from .vtp_points import check_closed
from .xml_scan import scan_xml


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
