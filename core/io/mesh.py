"""Mesh files read as point clouds: Wavefront OBJ (vertices, vertex normals) and STL."""

from __future__ import annotations

import os
import re
import warnings

import numpy as np

from .cloud import CloudFileError, RawCloud, is_padding
from .sniff import UTF8_BOM

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
#: ``vertex`` as the first word of a line (a solid named "vertex colours" is no vertex)
_STL_VERTEX = re.compile(rb"(?<![^\r\n])[ \t]*vertex[ \t]+(\S+)[ \t]+(\S+)[ \t]+(\S+)", re.IGNORECASE)
_STL_VERTEX_WORD = re.compile(rb"(?<![^\r\n])[ \t]*vertex(?![^ \t\r\n])", re.IGNORECASE)
#: bytes a binary STL may have after its last triangle (some writers pad or add a newline)
_STL_SLACK = 50
#: triangles before a binary STL's last one that the last one's check needs as evidence
_LAST_EVIDENCE = 3
#: a binary STL triangle's stored normal is zero or of length 1 within this
_UNIT_NORMAL_TOL = 1e-3


# ---------------------------------------------------------------------------------- OBJ


def read_obj(path) -> RawCloud:
    """``v`` lines are the points (``v x y z r g b``: colours as fields red, green, blue).
    Normals come from faces' ``v//vn`` (or ``v/vt/vn``) indices; without those, ``vn``
    lines are used in order when there is one per vertex."""
    with open(path, encoding="latin-1") as f:
        lines = f.read().removeprefix(UTF8_BOM.decode("latin-1")).splitlines()  # a UTF-8 BOM hid the first 'v'
    v_lines, vn_lines, f_lines = [], [], []  # f_lines: (line index, #v so far, #vn so far)
    for i, line in enumerate(lines):
        parts = line.split(None, 1)
        key = parts[0] if parts else ""
        if key == "v":
            v_lines.append(i)
        elif key == "vn":
            vn_lines.append(i)
        elif key == "f":
            f_lines.append((i, len(v_lines), len(vn_lines)))
    points = _parse_vectors(path, lines, v_lines, "v")
    colours = _vertex_colours(path, lines, v_lines)
    if not vn_lines:
        return RawCloud(points, None, colours)
    vn = _parse_vectors(path, lines, vn_lines, "vn")
    normals, referenced = _face_normals(path, lines, f_lines, points, vn)
    if not referenced and len(vn) == len(points):
        normals = vn
    elif not referenced:
        warnings.warn(f"{path}: {len(vn)} 'vn' normals cannot be matched to {len(points)} vertices (no face "
                      "references them and the counts differ); normals ignored", UserWarning, stacklevel=4)
    return RawCloud(points, normals, colours)


def _vertex_colours(path, lines, v_lines) -> dict:
    """The fields red, green, blue of 'v x y z r g b' lines (MeshLab and CloudCompare write
    vertex colours so), when every 'v' line has them; {} otherwise."""
    rows = [lines[i].split()[4:] for i in v_lines]
    if not rows or any(len(row) != 3 for row in rows):
        return {}
    try:
        rgb = np.array(rows, dtype=np.float64)
    except ValueError:
        i = next(i for i, row in zip(v_lines, rows) if not all(map(_is_float, row)))
        raise CloudFileError(path, f"line {i + 1}: cannot parse the colour of {lines[i].strip()!r}") from None
    return {"red": rgb[:, 0], "green": rgb[:, 1], "blue": rgb[:, 2]}


def _parse_vectors(path, lines, indices, key) -> np.ndarray:
    rows = [lines[i].split()[1:4] for i in indices]
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), 3)
    except ValueError:
        for i, row in zip(indices, rows):
            if len(row) < 3:
                raise CloudFileError(path, f"line {i + 1}: a '{key}' line needs 3 numbers, found {len(row)}") from None
            if not all(map(_is_float, row)):
                raise CloudFileError(path, f"line {i + 1}: cannot parse {lines[i].strip()!r}") from None
        raise CloudFileError(path, f"cannot parse the '{key}' lines") from None


def _face_normals(path, lines, f_lines, points, vn):
    """(normals or None, whether any face gives a vertex//normal pair)."""
    vi, ni = [], []
    for i, n_v, n_vn in f_lines:
        for token in lines[i].split()[1:]:
            parts = token.split("/")
            if len(parts) < 3 or not parts[2]:
                continue
            try:
                a, b = int(parts[0]), int(parts[2])
            except ValueError:
                raise CloudFileError(path, f"line {i + 1}: cannot parse face vertex {token!r}") from None
            a = a - 1 if a > 0 else n_v + a  # OBJ indices are 1-based, negative ones relative
            b = b - 1 if b > 0 else n_vn + b
            if not (0 <= a < len(points) and 0 <= b < len(vn)):
                raise CloudFileError(path, f"line {i + 1}: face vertex {token!r} refers to a missing v or vn")
            vi.append(a)
            ni.append(b)
    if not vi:
        return None, False
    pairs = np.unique(np.column_stack([vi, ni]), axis=0)
    normals = np.zeros_like(points)
    np.add.at(normals, pairs[:, 0], vn[pairs[:, 1]])
    per_vertex = np.bincount(pairs[:, 0], minlength=len(points))
    shared = per_vertex > 1  # a vertex with several different vn: their normalised mean
    if shared.any():
        length = np.linalg.norm(normals[shared], axis=1, keepdims=True)
        normals[shared] /= np.where(length > 0, length, 1.0)
    missing = int(np.count_nonzero(per_vertex == 0))
    if missing:
        warnings.warn(f"{path}: {missing} of {len(points)} vertices get no normal from the faces; normals ignored",
                      UserWarning, stacklevel=5)
        return None, True
    return normals, True


# ---------------------------------------------------------------------------------- STL


def read_stl(path) -> RawCloud:
    """The triangle corners, exact duplicates removed (first occurrence order); no normals.
    A file whose size fits its triangle count is binary, even when its header begins with
    "solid" (SolidWorks writes that); so is one that begins with "solid" but holds no
    ASCII vertices, if its size allows the count."""
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(1024)
    n = int.from_bytes(head[80:84], "little") if len(head) >= 84 else -1
    fits = n >= 0 and 0 <= size - (84 + 50 * n) < _STL_SLACK
    corners = None
    if head.removeprefix(UTF8_BOM).lstrip()[:5].lower() == b"solid" and not fits:  # a UTF-8 BOM: ASCII
        corners = _read_stl_ascii(path)
        if not len(corners) and n >= 0 and size >= 84 + 50 * n:
            corners = None  # no ASCII vertices: a binary STL whose header begins with "solid"
    if corners is None:
        corners = _read_stl_binary(path, n, size)
    corners = corners.astype(np.float64) + 0.0  # + 0.0 turns -0.0 into 0.0 so they deduplicate
    _, first = np.unique(corners, axis=0, return_index=True)
    return RawCloud(corners[np.sort(first)], None, {})


def _read_stl_binary(path, n: int, size: int) -> np.ndarray:
    if n < 0:
        raise CloudFileError(path, f"too short for a binary STL (needs at least 84 bytes, has {size})")
    if size < 84 + 50 * n:
        raise CloudFileError(
            path, f"truncated: the binary STL header declares {n} triangles ({84 + 50 * n} bytes) but the file "
            f"has {size} bytes"
        )
    if size - (84 + 50 * n) >= _STL_SLACK and _stl_tail_holds_data(path, 84 + 50 * n):
        raise CloudFileError(
            path, f"the binary STL header declares {n} triangles ({84 + 50 * n} bytes) but the file has {size} bytes, "
            f"room for {(size - 84) // 50}; the triangle count (bytes 80-83) does not match the data"
        )
    records = np.fromfile(path, dtype=_STL_RECORD, count=n, offset=84)
    if size > 84 + 50 * n:
        _check_stl_alignment(path, records, size)
    return records["vertices"].reshape(-1, 3)


def _check_stl_alignment(path, records, size: int) -> None:
    """A binary STL longer than its count's 84 + 50 n bytes: bytes inserted into its data
    shift every triangle after them (read as garbage, 1e38), bytes after its last triangle
    are a writer's padding (NULs, a newline: read) or not (refused, as trimesh does). Where
    the first triangle's stored normal is a unit vector, the writer stores unit normals
    (zero only for a degenerate triangle): a later triangle of another normal marks a shift
    behind padding-like bytes, and the file is refused naming it. Bytes inserted into the
    last triangle leave a padding-like end (its attribute's zeros): see _last_triangle_problem."""
    n, extra = len(records), size - 84 - 50 * len(records)
    said = f"the binary STL header declares {n} triangles ({84 + 50 * n} bytes) but the file has {size} bytes"
    with open(path, "rb") as f:
        f.seek(84 + 50 * n)
        tail_data = not is_padding(f.read(1 << 16))
    fine = _stored_normals_fit(records)
    if n and fine[0] and not fine.all():
        i = int(np.argmin(fine))
        raise CloudFileError(path, f"{said}, {extra} more, and triangle {i}'s normal "
                                   f"({' '.join(f'{v:.6g}' for v in records['normal'][i])}) is not a unit vector (nor "
                                   "zero on a degenerate triangle) as those before it are: bytes were inserted into "
                                   "the data before it, shifting the triangles after; the file is damaged")
    if tail_data:
        raise CloudFileError(path, f"{said}, {extra} more, which are not padding (NULs, a newline): bytes were inserted "
                                   "into its data or its triangle count (bytes 80-83) is wrong; the file is damaged")
    problem = _last_triangle_problem(records)
    if problem:
        raise CloudFileError(path, f"{said}, {extra} more, padding-like, but the last triangle {problem}: bytes were "
                                   "inserted into it, leaving its zero attribute bytes after it; the file is damaged")


def _stored_normals_fit(records) -> np.ndarray:
    """Per triangle: whether its stored normal is a unit vector, or zero on a degenerate
    triangle (False everywhere when the first is not a unit vector)."""
    with np.errstate(all="ignore"):
        normals = records["normal"].astype(np.float64)
        length = np.sqrt((normals ** 2).sum(axis=1))
        corners = records["vertices"].astype(np.float64)
        edges = corners[:, 1:] - corners[:, :1]
        area = np.linalg.norm(np.cross(edges[:, 0], edges[:, 1]), axis=1)
        degenerate = area == 0  # a repeated corner: a shifted record's garbage is never exactly flat
        fit = (np.abs(length - 1) < _UNIT_NORMAL_TOL) | ((length == 0) & degenerate)
    return fit if len(fit) and abs(length[0] - 1) < _UNIT_NORMAL_TOL else np.zeros(len(fit), bool)


def _last_triangle_problem(records) -> str | None:
    """What shows the last triangle read shifted against the (3 or more) triangles before it, or
    None: shifted float bytes read as a corner far from theirs (:func:`_stray_corners`), or as a
    stored normal off its corners' normal where every earlier one matches its own (unit normals
    computed from the corners, as most writers store them)."""
    if len(records) <= _LAST_EVIDENCE:
        return None
    with np.errstate(all="ignore"):
        corners = records["vertices"].astype(np.float64)
        if _stray_corners(corners[:-1].reshape(-1, 3), corners[-1]):
            shown = "; ".join(" ".join(f"{v:.6g}" for v in corner) for corner in corners[-1])
            return f"has corners ({shown}) of another magnitude than every corner before it"
        stored = records["normal"].astype(np.float64)
        geometric = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        lengths = np.linalg.norm(stored, axis=1) * np.linalg.norm(geometric, axis=1)
        cosine = np.einsum("ij,ij->i", stored, geometric) / lengths
    if np.all(cosine[:-1] > 0.99) and not cosine[-1] > 0.99 and np.linalg.norm(geometric[-1]) > 0:
        return (f"has a stored normal ({' '.join(f'{v:.6g}' for v in stored[-1])}) off its corners' normal, where "
                "every triangle before it stores its corners' normal")
    return None


def _stray_corners(before, last) -> bool:
    """Whether a corner of ``last`` is not finite, lies 10 times the box of the corners ``before``
    outside it, or is nonzero 1e20 times below their magnitude (a float's bytes shifted: 1e38, 1e-39)."""
    low, high = before.min(axis=0), before.max(axis=0)
    size = np.linalg.norm(high - low)
    far = (last < low - 10 * size) | (last > high + 10 * size)
    tiny = (last != 0) & (np.abs(last) < 1e-20 * (np.abs(before).max() + size))
    return bool(not np.isfinite(last).all() or (size > 0 and far.any()) or tiny.any())


def _stl_tail_holds_data(path, start: int) -> bool:
    """Whether the bytes after the declared triangles are more than zero padding: triangles
    after a wrong count (0, or a writer's partial count) were dropped without a word."""
    return bool(np.memmap(path, dtype=np.uint8, mode="r", offset=start).any())


def _read_stl_ascii(path) -> np.ndarray:
    with open(path, "rb") as f:
        data = f.read()
    matches = _STL_VERTEX.findall(data)
    try:
        if len(matches) != len(_STL_VERTEX_WORD.findall(data)):
            raise ValueError("a vertex line without three values")
        corners = np.array(matches, dtype=np.bytes_).reshape(-1, 3).astype(np.float64)
    except ValueError:
        for lineno, line in enumerate(data.splitlines(), start=1):
            m = _STL_VERTEX.match(line)
            if line.split()[:1] in ([b"vertex"], [b"VERTEX"]) and not (m and all(_is_float(t) for t in m.groups())):
                raise CloudFileError(path, f"line {lineno}: cannot parse {line.strip().decode('latin-1')!r}") from None
        raise CloudFileError(path, "cannot parse the ASCII STL vertices") from None
    if len(corners) % 3:
        raise CloudFileError(path, f"truncated: {len(corners)} vertices do not make whole triangles")
    if len(corners):  # none: perhaps a binary STL whose header begins with "solid" (read_stl decides)
        _check_stl_end(path, data)
    return corners


def _check_stl_end(path, data: bytes) -> None:
    """Refuse an ASCII STL cut inside a facet: after its vertices (or before them) the whole
    triangles before the cut were read as the file, the rest lost without a word. A file may
    end with ``endsolid`` or, lacking it, with ``endfacet``."""
    end = len(data)
    while end and data[end - 1] in b" \t\r\n\v\f\0":  # the last line (NUL padding too), the text not copied
        end -= 1
    last = data[data.rfind(b"\n", 0, end) + 1 : end].strip()
    if last.split()[:1] and last.split()[0].lower() not in (b"endsolid", b"endfacet"):
        raise CloudFileError(path, f"truncated: the ASCII STL ends inside a facet, at "
                                   f"{last[:60].decode('latin-1')!r}; a whole file ends with 'endsolid'")


def _is_float(token) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True
