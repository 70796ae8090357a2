"""Seed files of every readable format and seeded mutations of them, for the hostile-file fuzz
(``test_io_fuzz.py``, and by hand a larger run with more seeds). Every seed is built here, by
hand or by the format's own library, from a small curved patch of points; each mutation is a
(name, bytes) pair a reader must read or refuse with a ``CloudFileError`` naming the file."""

from __future__ import annotations

import re
import struct
import warnings
import zlib

import numpy as np


def patch(n=24, seed=0):
    """``n`` points on a paraboloid cap, well spread (no two alike), with unit normals."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-1, 1, size=(n, 2))
    z = 0.3 * (xy ** 2).sum(axis=1)
    normals = np.column_stack([-0.6 * xy, np.ones(n)])
    return np.column_stack([xy, z]), normals / np.linalg.norm(normals, axis=1, keepdims=True)


# ------------------------------------------------------------------------------- PLY

_PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4",
              "float": "f4", "double": "f8", "int8": "i1", "uint16": "u2", "float64": "f8", "float32": "f4"}


def ply(points, fmt="ascii", coord="float", extra=("uchar", "short"), faces=0, comments=True, obj_info=True):
    """A PLY of ``points`` (x, y, z of type ``coord``), extra properties of the given types,
    and ``faces`` triangles; ``fmt`` ascii, binary_little_endian or binary_big_endian."""
    n = len(points)
    head = ["ply", f"format {fmt} 1.0"]
    head += ["comment made by the fuzz", "comment   "] if comments else []
    head += ["obj_info a fuzz seed"] if obj_info else []
    head.append(f"element vertex {n}")
    head += [f"property {coord} {axis}" for axis in "xyz"]
    head += [f"property {kind} p{i}" for i, kind in enumerate(extra)]
    if faces:
        head += [f"element face {faces}", "property list uchar int vertex_indices"]
    head.append("end_header")
    order = ">" if fmt == "binary_big_endian" else "<"
    fields = [(axis, order + _PLY_TYPES[coord]) for axis in "xyz"]
    fields += [(f"p{i}", order + _PLY_TYPES[kind]) for i, kind in enumerate(extra)]
    table = np.zeros(n, dtype=fields)
    for i, axis in enumerate("xyz"):
        table[axis] = points[:, i]
    for i, _ in enumerate(extra):
        table[f"p{i}"] = np.arange(n) % 100
    tris = [(j % n, (j + 1) % n, (j + 2) % n) for j in range(faces)]
    if fmt == "ascii":
        rows = [" ".join(repr(v.item()) for v in row) for row in table]
        rows += [f"3 {a} {b} {c}" for a, b, c in tris]
        return ("\n".join(head + rows) + "\n").encode()
    body = table.tobytes() + b"".join(struct.pack(order + "B3i", 3, *t) for t in tris)
    return ("\n".join(head) + "\n").encode() + body


# ------------------------------------------------------------------------------- text

def text(points, sep=" ", header=None, comment=None, decimal=".", newline="\n", bom="", ragged=False, count=False):
    """Delimited text rows x y z nx ny nz; a names ``header``, a ``comment`` line, a count line."""
    rows = [sep.join(repr(float(v)).replace(".", decimal) for v in p) for p in points]
    if ragged:
        rows[len(rows) // 2] = sep.join(rows[len(rows) // 2].split(sep)[:2])
    lines = ([comment] if comment else []) + ([str(len(points))] if count else [])
    lines += [header] if header else []
    return (bom + newline.join(lines + rows) + newline).encode("utf-8")


# ------------------------------------------------------------------------------- PCD

def pcd(points, data="ascii"):
    """A PCD of x y z (float32) and an intensity (uint16), ``data`` ascii/binary/binary_compressed."""
    n = len(points)
    head = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 2\nTYPE F F F U\nCOUNT 1 1 1 1\n"
            f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()
    table = np.zeros(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("i", "<u2")])
    for i, axis in enumerate("xyz"):
        table[axis] = points[:, i]
    table["i"] = np.arange(n)
    if data == "ascii":
        return head + "".join(" ".join(map(repr, row)) + "\n" for row in table.tolist()).encode()
    if data == "binary":
        return head + table.tobytes()
    soa = b"".join(np.ascontiguousarray(table[name]).tobytes() for name in table.dtype.names)
    return head + struct.pack("<II", len(_lzf(soa)), len(soa)) + _lzf(soa)


def _lzf(data):
    """``data`` as LZF literal runs only (valid LZF that any decoder expands back)."""
    return b"".join(bytes([len(data[i:i + 32]) - 1]) + data[i:i + 32] for i in range(0, len(data), 32))


# ------------------------------------------------------------------------------- meshes, PTX

def off(points, keyword="NOFF", normals=None, faces=1):
    n = len(points)
    rows = [" ".join(map(repr, p.tolist() + ([] if normals is None else normals[i].tolist())))
            for i, p in enumerate(points)]
    return (f"{keyword}\n# a comment\n{n} {faces} 0\n" + "\n".join(rows) + "\n"
            + "".join(f"3 0 1 {2 + j}\n" for j in range(faces))).encode()


def obj(points):
    return ("# fuzz\no cloud\n" + "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())
            + "f 1 2 3\n").encode()


def stl(points, binary=True):
    tris = [points[i:i + 3] for i in range(0, len(points) - 2, 3)]
    if binary:
        return b"fuzz".ljust(80, b" ") + struct.pack("<I", len(tris)) + b"".join(
            struct.pack("<12fH", 0, 0, 1, *t.ravel(), 0) for t in tris)
    facets = "".join("facet normal 0 0 1\n outer loop\n" + "".join(f"  vertex {x!r} {y!r} {z!r}\n" for x, y, z in t)
                     + " endloop\nendfacet\n" for t in (t.tolist() for t in tris))
    return f"solid fuzz\n{facets}endsolid fuzz\n".encode()


def ptx(points, cols=1):
    n = len(points)
    cols = cols if n % cols == 0 else 1
    head = f"{cols}\n{n // cols}\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
    return (head + "".join(f"{x!r} {y!r} {z!r} 0.5\n" for x, y, z in points.tolist())).encode()


# ------------------------------------------------------------------------------- VTK, LAS, E57

def vtk_legacy(points, binary=False):
    n = len(points)
    head = f"# vtk DataFile Version 3.0\nfuzz\n{'BINARY' if binary else 'ASCII'}\nDATASET POLYDATA\nPOINTS {n} float\n"
    if binary:
        body = points.astype(">f4").tobytes() + f"\nVERTICES {n} {2 * n}\n".encode()
        body += np.column_stack([np.ones(n, int), np.arange(n)]).astype(">i4").tobytes() + b"\n"
    else:
        body = ("".join(" ".join(map(repr, p)) + "\n" for p in points.astype(np.float32).tolist())
                + f"VERTICES {n} {2 * n}\n" + "".join(f"1 {i}\n" for i in range(n))).encode()
    return head.encode() + body


def vtp(points, tmp):
    from core.io import write_cloud
    path = tmp / "seed.vtp"
    write_cloud(path, points)
    return path.read_bytes()


def las(points, tmp, point_format=3, version="1.2", scale=0.001, offset=0.0, laz=False):
    import laspy
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales, header.offsets = [scale] * 3, [offset] * 3
    data = laspy.LasData(header)
    data.x, data.y, data.z = (points[:, i] + offset for i in range(3))
    path = tmp / ("seed.laz" if laz else "seed.las")
    data.write(str(path))
    return path.read_bytes()


def e57(points, tmp):
    """An E57 file of one scan of ``points``. libE57 cannot write the bounds of non-finite or
    huge coordinates: its close raises IndexError, and pye57's ``E57.__del__`` closed the file
    again, an "Exception ignored in E57.__del__" warning in pytest; the one close is the ``with``'s."""
    import pye57
    path = tmp / "seed.e57"
    f = pye57.E57(str(path), mode="w")
    try:
        with f:
            f.write_scan_raw({"cartesianX": points[:, 0], "cartesianY": points[:, 1], "cartesianZ": points[:, 2]})
    finally:
        f.__dict__.pop("image_file", None)  # pye57's destructor closes only a file it still holds
    return path.read_bytes()


def seeds(tmp, n=24, seed=0, points=None):
    """{name: (extension, bytes)}: one valid file of each format and variant, of ``n`` points
    on a patch, or of ``points`` (then with those points' normals all +z)."""
    pts, nrm = patch(n, seed)
    if points is not None:
        pts, nrm = np.asarray(points, float), np.tile([0.0, 0.0, 1.0], (len(points), 1))
    both = np.hstack([pts, nrm])
    builders = {
        "ply_ascii": ("ply", lambda: ply(pts)), "ply_ascii_faces": ("ply", lambda: ply(pts, faces=5)),
        "ply_le_odd": ("ply", lambda: ply(pts, "binary_little_endian", "double", ("char", "uint", "float64", "int8"))),
        "ply_be_faces": ("ply", lambda: ply(pts, "binary_big_endian", faces=4)),
        "ply_le_plain": ("ply", lambda: ply(pts, "binary_little_endian", extra=(), comments=False, obj_info=False)),
        "xyz": ("xyz", lambda: text(both)), "xyz_comment": ("xyz", lambda: text(pts, comment="# units m")),
        "csv_header": ("csv", lambda: text(both, ",", header="x,y,z,nx,ny,nz")),
        "csv_semicolon": ("csv", lambda: text(pts, ";", header="x;y;z")),
        "txt_crlf_bom": ("txt", lambda: text(pts, "\t", newline="\r\n", bom="\ufeff")),
        "pts_count": ("pts", lambda: text(pts, count=True)),
        "pcd_ascii": ("pcd", lambda: pcd(pts)), "pcd_binary": ("pcd", lambda: pcd(pts, "binary")),
        "pcd_compressed": ("pcd", lambda: pcd(pts, "binary_compressed")),
        "off": ("off", lambda: off(pts, "OFF")), "noff": ("off", lambda: off(pts, "NOFF", nrm)),
        "obj": ("obj", lambda: obj(pts)), "stl_binary": ("stl", lambda: stl(pts)),
        "stl_ascii": ("stl", lambda: stl(pts, False)), "ptx": ("ptx", lambda: ptx(pts, 6)),
        "vtk_ascii": ("vtk", lambda: vtk_legacy(pts)), "vtk_binary": ("vtk", lambda: vtk_legacy(pts, True)),
        "vtp": ("vtp", lambda: vtp(pts, tmp)),
        "las12_pf3": ("las", lambda: las(pts, tmp)),
        "las14_pf6_odd": ("las", lambda: las(pts, tmp, 6, "1.4", scale=1e-7, offset=1e6)),
        "laz_pf1": ("laz", lambda: las(pts, tmp, 1, laz=True)),
        "e57": ("e57", lambda: e57(pts, tmp)),
    }
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # float32 overflow of 1e308: the file holds inf
        for name, (ext, build) in builders.items():
            try:
                out[name] = (ext, build())
            except (ImportError, ValueError, OverflowError, IndexError):  # points the format cannot hold
                pass
    return out


# ------------------------------------------------------------------------------- mutations

_NUMBER = re.compile(rb"(?<![\w.])\d+(?![\w.])")
#: what a header count becomes: beyond int64 always, then one of the others
_BIG = (b"18446744073709551617", b"0", b"-1", b"-2147483649", b"1000000000000", b"2147483648", b"1e3", b"0x10")


def _header_end(data: bytes) -> int:
    """Where the text header ends: the first 1 KiB (or the whole file when smaller)."""
    for mark in (b"end_header\n", b"DATA ascii\n", b"DATA binary\n", b"DATA binary_compressed\n"):
        at = data.find(mark)
        if at >= 0:
            return at + len(mark)
    return min(len(data), 1024)


def mutations(data: bytes, rng, count=12):
    """(name, bytes) mutations of ``data``: cut at random offsets, header integers replaced by
    values too big, too small, negative or huge, binary header words overwritten, bytes flipped."""
    out = [(f"cut{at}", data[:at]) for at in sorted(set(rng.integers(1, len(data), size=count // 2).tolist()))]
    head = data[:_header_end(data)]
    numbers = list(_NUMBER.finditer(head))
    chosen = [0] + (1 + rng.permutation(max(0, len(numbers) - 1))[: count // 2 - 1]).tolist() if numbers else []
    for match in (numbers[i] for i in chosen):  # the first number (often a count), and others at random
        for value in [_BIG[0], rng.choice(_BIG[1:]).item(), str(int(match.group()) + 1).encode()]:
            out.append((f"num{match.start()}={value.decode()}", data[:match.start()] + value + data[match.end():]))
    for _ in range(count // 3):
        at = int(rng.integers(0, max(1, min(len(data) - 8, 400))))
        word = rng.choice([0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 0, 1 << 24]).item()
        out.append((f"word{at}={word:x}", data[:at] + struct.pack("<I", word) + data[at + 4:]))
    for _ in range(count // 2):
        flipped = bytearray(data)
        for at in rng.integers(0, len(data), size=int(rng.integers(1, 9))):
            flipped[at] = int(rng.integers(0, 256))
        out.append((f"flip{int(rng.integers(1 << 30))}", bytes(flipped)))
    return out


def compressed_pcd_inflated(points):
    """A binary_compressed PCD whose data is a zlib stream instead of LZF (another tool's idea)."""
    soa = points.astype("<f4").T.tobytes()
    packed = zlib.compress(soa)
    head = (f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {len(points)}\nHEIGHT 1\n"
            f"POINTS {len(points)}\nDATA binary_compressed\n").encode()
    return head + struct.pack("<II", len(packed), len(soa)) + packed


