"""Geomview OFF meshes read as point clouds: the vertices, their normals (NOFF) and colours (COFF).

The header keyword is ``[ST][C][N][4][n]OFF``: ST texture coordinates, C a colour, N a normal
and 4 a homogeneous coordinate on each vertex line, n a dimension before the counts. The counts
``vertices faces edges`` follow on the keyword's line or the next; ``#`` starts a comment. A
vertex line is ``x y z [w] [nx ny nz] [r g b [a]] [s t]``. Faces are not read. ModelNet's
files that run the keyword into the counts (``OFF490 518 0``) are read too. Binary OFF is
refused with a message saying so.
"""

from __future__ import annotations

import itertools
import os
import re
import warnings

import numpy as np

from .cloud import CloudFileError, RawCloud, check_memory
from .sniff import UTF8_BOM

_KEYWORD = re.compile(rb"(ST)?(C)?(N)?(4)?(n)?OFF")
#: bytes of the shortest vertex line, "0 0 0\n": a bound on the vertices a file can hold
_MIN_LINE = 6


def read_off(path) -> RawCloud:
    """The vertices (divided by w for 4OFF), normals when the keyword has N, and ``red``,
    ``green``, ``blue`` (uint8; 0-1 floats scaled to 0-255) when it has C."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        lines = _content(f)
        flags, count, faces = _header(path, lines)
        if count * _MIN_LINE > size:
            raise CloudFileError(path, f"declares {count} vertices but its {size} bytes hold at most "
                                       f"{size // _MIN_LINE}")
        check_memory(path, count * 8 * 16, f"declares {count} vertices: reading them needs")
        table = _vertices(path, lines, count)
        _check_after_vertices(path, next(lines, None), count, faces)
    return _raw(path, flags, table)


def _check_after_vertices(path, line, count: int, faces: int) -> None:
    """Refuse a line after the vertices that is not a face (``n i1 ... in``): the counts
    are wrong, and the vertices after the count were dropped without a word."""
    tokens = [] if line is None else line.split()
    n = int(tokens[0]) if tokens and tokens[0].isdigit() else 0
    face = faces > 0 and 0 < n < len(tokens) and all(t.isdigit() for t in tokens[1 : n + 1])
    if line is not None and not face:
        raise CloudFileError(path, f"declares {count} vertices and {faces} faces, but the line after the vertices, "
                                   f"{line[:60].decode('latin-1')!r}, is not a face (n i1 ... in); the vertex count "
                                   "does not match the data")


def _content(f):
    """The lines of ``f`` that hold something besides a comment, comments cut off."""
    for line in f:
        line = line.split(b"#", 1)[0].strip()
        if line:
            yield line


def _header(path, lines) -> tuple[dict, int, int]:
    """The keyword's flags, the vertex and face counts, from the first content lines."""
    first = next(lines, b"").removeprefix(UTF8_BOM)
    if first[:3] == b"off":  # a lower-case plain keyword, as some writers spell it
        first = b"OFF" + first[3:]
    match = _KEYWORD.match(first)
    if match is None:
        raise CloudFileError(path, f"is not an OFF file: it starts with {first[:40].decode('latin-1')!r}, not a "
                                   "keyword such as OFF, COFF, NOFF or 4OFF")
    flags = dict(zip(("ST", "C", "N", "4", "n"), (g is not None for g in match.groups())))
    rest = first[match.end():].split()
    if rest[:1] == [b"BINARY"]:
        raise CloudFileError(path, "is a binary OFF file; only ASCII OFF is read (MeshLab or meshio can save it "
                                   "as ASCII)")
    if flags["n"]:
        rest = rest or next(lines, b"").split()
        dimension = _integers(path, rest[:1], "the dimension after nOFF")
        if dimension != [3]:
            got = f"vertices of dimension {dimension[0]}" if dimension else "no dimension after its nOFF keyword"
            raise CloudFileError(path, f"holds {got}; a point cloud in space needs dimension 3")
        rest = rest[1:]
    counts = _integers(path, rest or next(lines, b"").split(), "the counts (vertices faces edges)")
    if not 2 <= len(counts) <= 3 or min(counts) < 0:
        raise CloudFileError(path, f"the counts after the keyword must be 3 integers, vertices faces edges, none "
                                   f"negative; found {' '.join(map(str, counts))!r}")
    return flags, counts[0], counts[1]


def _integers(path, tokens, what) -> list[int]:
    try:
        return [int(t) for t in tokens] if tokens else []
    except ValueError:
        shown = b" ".join(tokens).decode("latin-1")[:60]
        raise CloudFileError(path, f"{what} must be integers, found {shown!r}") from None


def _vertices(path, lines, count: int) -> np.ndarray:
    if count == 0:
        raise CloudFileError(path, "contains no points (it declares 0 vertices)")
    try:
        table = np.loadtxt(itertools.islice(lines, count), ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise CloudFileError(path, f"malformed vertex lines: {exc}") from None
    if len(table) != count:
        raise CloudFileError(path, f"declares {count} vertices but only {len(table)} vertex lines follow")
    return table


def _raw(path, flags, table) -> RawCloud:
    """Points, normals and colours from the vertex table, by the keyword's flags."""
    before_colour = 3 + flags["4"] + 3 * flags["N"]
    need = before_colour + 3 * flags["C"] + 2 * flags["ST"]
    if table.shape[1] < need:
        raise CloudFileError(path, f"vertex lines hold {table.shape[1]} numbers; its keyword asks for at least {need}")
    points = table[:, :3]
    if flags["4"]:
        with np.errstate(divide="ignore", invalid="ignore"):  # w = 0 is a point at infinity: refused as non-finite
            points = points / table[:, 3:4]
    normals = table[:, before_colour - 3:before_colour] if flags["N"] else None
    fields = {}
    if flags["C"]:
        spare = table.shape[1] - before_colour - 2 * flags["ST"]
        fields = _colours(path, table[:, before_colour:before_colour + min(spare, 4)][:, :3])
    return RawCloud(points, normals, fields)


def _colours(path, rgb) -> dict:
    """uint8 channels from 0-255 integers or 0-1 floats; other values are dropped with a warning."""
    if ((rgb >= 0) & (rgb <= 1)).all() and (rgb != np.round(rgb)).any():
        rgb = np.round(rgb * 255)
    if not ((rgb >= 0) & (rgb <= 255) & (rgb == np.round(rgb))).all():
        warnings.warn(f"{path}: vertex colours are neither 0-255 integers nor 0-1 numbers; colours ignored",
                      UserWarning, stacklevel=5)
        return {}
    return {name: rgb[:, i].astype(np.uint8) for i, name in enumerate(("red", "green", "blue"))}
