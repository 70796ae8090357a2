"""Leica PTX: laser scans as text, one or more one after another, as Cyclone exports them.

Each scan is a header of ten lines (its columns, its rows, the scanner's registered position,
the scanner's x, y and z axes, and a 4 x 4 transform whose rows multiply row vectors: the last
row is the translation), then columns x rows lines ``x y z [intensity [red green blue]]`` in
the scanner's own coordinates. The grid is full: a direction with no return is written with
x = y = z = 0 and is left out. The points are placed in world coordinates by their scan's
transform (as PDAL and CloudCompare do), and each point's viewpoint is its scanner's
registered position (the header's third line), right whether or not an exporter had already
applied the transform.
"""

from __future__ import annotations

import itertools
import math
import os

import numpy as np

from .cloud import CloudFileError, RawCloud, Scan, check_memory, joined_scans
from .sniff import UTF8_BOM

#: bytes of the shortest possible point line, "0 0 0\n": a bound on the points a file can hold
_MIN_LINE = 6
#: numbers on a point line -> the fields after x y z
_LAYOUTS = {3: (), 4: ("intensity",), 7: ("intensity", "red", "green", "blue")}
#: bytes a point takes while read: its numbers (7 at most), its world coordinates, its viewpoint
_BYTES_PER_POINT = 8 * 7 + 24 + 24


def read_ptx(path) -> RawCloud:
    """Every scan's points in world coordinates, the ones with no return left out; fields
    ``intensity`` (as stored, 0-1), ``red``, ``green``, ``blue`` (uint8) when every scan has
    them, and ``scan`` (int32, the scan's index); each point's viewpoint is its scanner's position."""
    size = os.path.getsize(path)
    scans = []
    with open(path, "rb") as f:
        if f.read(len(UTF8_BOM)) != UTF8_BOM:  # a UTF-8 byte-order mark (a text editor's) is skipped
            f.seek(0)
        reader = _Lines(f, path)
        while reader.skip_blank():
            scans.append(_read_scan(reader, len(scans), size))
    if not scans:
        raise CloudFileError(path, "holds no PTX scan")
    return _joined(path, scans)


class _Lines:
    """The file's lines with their numbers, for the header's messages."""

    def __init__(self, f, path):
        self.f, self.path, self.line = f, path, 0

    def skip_blank(self) -> bool:
        """Past blank lines; whether a line follows."""
        while True:
            at = self.f.tell()
            text = self.f.readline()
            if not text:
                return False
            if text.strip():
                self.f.seek(at)
                return True
            self.line += 1

    def numbers(self, count: int, what: str, *, integer=False) -> np.ndarray:
        """The next line's ``count`` numbers, refused naming the line and ``what`` it holds."""
        text = self.f.readline()
        self.line += 1
        where = f"scan header line {self.line} ({what})"
        if not text:
            raise CloudFileError(self.path, f"ends inside a scan's header: {where} is missing")
        parts = text.split()
        try:
            values = [int(p) if integer else float(p) for p in parts]
        except ValueError:
            values = None
        if values is None or len(values) != count or not all(integer or math.isfinite(v) for v in values):
            kind = "integer" if integer else "finite number"
            raise CloudFileError(self.path, f"{where} must hold {count} {kind}{'s' * (count > 1)}, found "
                                            f"{text.strip()[:60].decode('latin-1')!r}")
        return np.array(values, dtype=object if integer else np.float64)  # integers exact, beyond int64 too


def _read_scan(reader: _Lines, index: int, size: int) -> Scan:
    """One scan: its header checked, its declared lines read, its missing points dropped."""
    path = reader.path
    columns, rows = (int(reader.numbers(1, what, integer=True)[0]) for what in ("columns", "rows"))
    if columns < 0 or rows < 0:
        raise CloudFileError(path, f"scan {index} declares {columns} columns and {rows} rows; neither can be negative")
    position = reader.numbers(3, "scanner position")
    for axis in "xyz":
        reader.numbers(3, f"scanner {axis} axis")
    transform = np.array([reader.numbers(4, f"transform row {i + 1}") for i in range(4)])
    rotation = transform[:3, :3]
    if abs(np.linalg.det(rotation)) < 1e-12 * max(1.0, np.abs(rotation).max() ** 3):
        raise CloudFileError(path, f"scan {index}'s transform (header lines {reader.line - 3}-{reader.line - 1}) is "
                                   "singular: it would collapse the points; a registration is a rotation")
    count = columns * rows
    room = (size - reader.f.tell()) // _MIN_LINE
    if count > room:
        raise CloudFileError(path, f"scan {index} declares {columns} x {rows} = {count} points but the "
                                   f"{size - reader.f.tell()} bytes after its header hold at most {room}")
    check_memory(path, count * _BYTES_PER_POINT, f"scan {index} declares {count} points: reading them needs")
    table = _point_lines(reader, index, count)
    kept = ~(table[:, :3] == 0).all(axis=1)
    table = table[kept]
    points = table[:, :3] @ rotation + transform[3, :3]
    names = _LAYOUTS[table.shape[1]]
    fields = {name: table[:, 3 + i] for i, name in enumerate(names)}
    return Scan(points, fields, position)


def _point_lines(reader: _Lines, index: int, count: int) -> np.ndarray:
    """The scan's ``count`` point lines as an (count, 3 | 4 | 7) table."""
    path, first = reader.path, reader.line + 1
    if count == 0:
        return np.zeros((0, 3))
    try:
        table = np.loadtxt(itertools.islice(reader.f, count), ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise CloudFileError(path, f"scan {index}'s points (from line {first}): {exc}") from None
    reader.line += count
    if len(table) != count:
        raise CloudFileError(path, f"scan {index} declares {count} points (columns x rows) but only {len(table)} "
                                   f"point lines follow its header (line {first - 1})")
    if table.shape[1] not in _LAYOUTS:
        raise CloudFileError(path, f"scan {index}'s point lines hold {table.shape[1]} numbers; a PTX point is "
                                   "x y z, x y z intensity or x y z intensity red green blue")
    return table


def _joined(path, scans) -> RawCloud:
    """The scans one after another; the fields every scan has, colours as uint8."""
    if not any(len(s.points) for s in scans):
        raise CloudFileError(path, f"contains no points: every point of its {len(scans)} scan"
                                   f"{'s' * (len(scans) > 1)} is missing (0 0 0)")
    common = set.intersection(*(set(s.fields) for s in scans if len(s.points)))
    raw = joined_scans(scans, [name for name in _LAYOUTS[7] if name in common])
    for name in ("red", "green", "blue"):
        if name in raw.fields:
            raw.fields[name] = _colour(path, name, raw.fields[name])
    return raw


def _colour(path, name, values) -> np.ndarray:
    """A colour channel as uint8: PTX colours are integers 0-255."""
    ok = (values >= 0) & (values <= 255) & (values == np.round(values))
    if not ok.all():
        raise CloudFileError(path, f"a {name} value is {values[~ok][0]}; PTX colours are integers 0-255")
    return values.astype(np.uint8)
