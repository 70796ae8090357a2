"""core.io: reading every format from small generated files, round trips, errors, atomic writes."""

from __future__ import annotations

import hashlib
import os
import pickle
import stat
import struct
import sys
import types
import warnings
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

from core.io import (
    READ_FORMATS, WRITE_FORMATS, Cloud, CloudFileError, describe, read_cloud, write_cloud, write_result,
)
from core.io import write as io_write
from core.io.pcd import lzf_decompress

REPO = Path(__file__).resolve().parents[2]
RNG = np.random.default_rng(7)
PTS = RNG.standard_normal((20, 3))
NRM = PTS / np.linalg.norm(PTS, axis=1, keepdims=True)


def assert_error(path, match, **kwargs):
    """read_cloud(path) raises CloudFileError naming the file and containing ``match``."""
    with pytest.raises(CloudFileError) as info:
        read_cloud(path, **kwargs)
    message = str(info.value)
    assert Path(path).name in message
    assert match.lower() in message.lower(), message
    return message


def write_plyfile(path, columns, *, text=False, byte_order="<", faces=None, before=None):
    """A PLY written by plyfile itself (independent of core.io's writer)."""
    table = np.empty(len(columns["x"]), dtype=[(k, np.asarray(v).dtype.str) for k, v in columns.items()])
    for k, v in columns.items():
        table[k] = v
    elements = [] if before is None else [before]
    elements.append(PlyElement.describe(table, "vertex"))
    if faces is not None:
        face = np.empty(len(faces), dtype=[("vertex_indices", "i4", (3,))])
        face["vertex_indices"] = faces
        elements.append(PlyElement.describe(face, "face"))
    PlyData(elements, text=text, byte_order=byte_order).write(str(path))
    return path


def xyz_columns(points, normals=None, dtype="f8"):
    cols = {c: points[:, i].astype(dtype) for i, c in enumerate("xyz")}
    if normals is not None:
        cols.update({c: normals[:, i].astype(dtype) for i, c in enumerate(("nx", "ny", "nz"))})
    return cols


# ------------------------------------------------------------------------------ PLY


@pytest.mark.parametrize("text", [False, True])
def test_ply_with_normals_and_scalar(tmp_path, text):
    cols = xyz_columns(PTS, NRM)
    cols["intensity"] = np.arange(20, dtype=np.uint16)
    path = write_plyfile(tmp_path / "a.ply", cols, text=text)
    cloud = read_cloud(path)
    assert isinstance(cloud, Cloud) and cloud.format == "ply" and cloud.path == path
    assert cloud.points.dtype == np.float64 and cloud.points.flags.c_contiguous
    np.testing.assert_allclose(cloud.points, PTS, rtol=0, atol=0 if not text else 1e-15)
    np.testing.assert_allclose(cloud.normals, NRM, atol=1e-15)
    assert list(cloud.fields) == ["intensity"]
    assert cloud.fields["intensity"].dtype == np.uint16
    np.testing.assert_array_equal(cloud.fields["intensity"], np.arange(20))


@pytest.mark.parametrize("text", [False, True])
def test_ply_without_normals_with_faces(tmp_path, text):
    faces = [[0, 1, 2], [2, 3, 4]]
    path = write_plyfile(tmp_path / "mesh.ply", xyz_columns(PTS, dtype="f4"), text=text, faces=faces)
    cloud = read_cloud(path)
    assert cloud.normals is None and cloud.fields == {}
    np.testing.assert_array_equal(cloud.points, PTS.astype("f4").astype("f8"))


def test_ply_big_endian_and_vertex_not_first(tmp_path):
    before = PlyElement.describe(np.zeros(2, dtype=[("a", "i4")]), "camera")
    path = write_plyfile(tmp_path / "be.ply", xyz_columns(PTS, NRM), byte_order=">", before=before)
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, PTS)
    np.testing.assert_array_equal(cloud.normals, NRM)


def test_ply_list_property_in_vertex_falls_back_to_plyfile(tmp_path):
    table = np.empty(3, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("ids", "O")])
    table["x"], table["y"], table["z"] = 1, 2, 3
    table["ids"] = [np.array([1, 2], "i4")] * 3
    path = tmp_path / "lists.ply"
    PlyData([PlyElement.describe(table, "vertex")]).write(str(path))
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3]] * 3)
    assert cloud.fields == {}


def test_ply_errors(tmp_path):
    path = write_plyfile(tmp_path / "t.ply", xyz_columns(PTS))
    data = path.read_bytes()
    (tmp_path / "trunc.ply").write_bytes(data[:-10])
    assert_error(tmp_path / "trunc.ply", "truncated")
    assert_error(tmp_path / "trunc.ply", "20 vertices")
    ascii_path = write_plyfile(tmp_path / "ta.ply", xyz_columns(PTS), text=True)
    lines = ascii_path.read_text().splitlines()
    (tmp_path / "trunc_ascii.ply").write_text("\n".join(lines[:-3]) + "\n")
    assert_error(tmp_path / "trunc_ascii.ply", "truncated")
    lines[-5] = "1.0 abc 2.0"
    (tmp_path / "bad.ply").write_text("\n".join(lines) + "\n")
    assert_error(tmp_path / "bad.ply", "malformed")
    (tmp_path / "header.ply").write_bytes(b"ply\nformat nonsense 1.0\nend_header\n")
    assert_error(tmp_path / "header.ply", "not a valid PLY header")
    (tmp_path / "novertex.ply").write_bytes(b"ply\nformat ascii 1.0\nelement face 0\nend_header\n")
    assert_error(tmp_path / "novertex.ply", "no 'vertex' element")
    noxyz = write_plyfile(tmp_path / "noxyz.ply", {"x": np.zeros(2), "q": np.zeros(2)})
    assert_error(noxyz, "no x, y, z")
    empty = write_plyfile(tmp_path / "zero.ply", {c: np.zeros(0) for c in "xyz"})
    assert_error(empty, "no points")


# ------------------------------------------------------------------------------ text


def test_xyz_with_header_line(tmp_path):
    path = tmp_path / "a.xyz"
    body = "\n".join(" ".join(repr(v) for v in row) for row in np.hstack([PTS, NRM]).tolist())
    path.write_text("X Y Z Nx Ny Nz\n" + body + "\n")
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, PTS)
    np.testing.assert_array_equal(cloud.normals, NRM)
    assert cloud.format == "xyz" and cloud.fields == {}


def test_xyz_cloudcompare_header_comments_and_tabs(tmp_path):
    path = tmp_path / "cc.txt"
    path.write_text("# exported\n//X\tY\tZ\tscalar\n1\t2\t3\t0.5\n\n4\t5\t6\t0.25  # inline\n")
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    assert cloud.normals is None
    np.testing.assert_array_equal(cloud.fields["scalar"], [0.5, 0.25])


@pytest.mark.parametrize("ncols, normals, fields", [(3, False, []), (4, False, ["col3"]), (6, True, []),
                                                   (8, True, ["col6", "col7"])])
def test_headerless_columns(tmp_path, ncols, normals, fields):
    """Columns 3-5 are normals when they hold unit vectors (core.io.text._unit_rows)."""
    path = tmp_path / "plain.txt"
    table = RNG.random((5, ncols))
    if normals:
        table[:, 3:6] /= np.linalg.norm(table[:, 3:6], axis=1, keepdims=True)
    np.savetxt(path, table)
    cloud = read_cloud(path)
    assert (cloud.normals is not None) == normals
    assert list(cloud.fields) == fields


def test_pts_with_count_line(tmp_path):
    path = tmp_path / "scan.pts"
    path.write_text("3\n1 2 3 10 255 0 0\n4 5 6 20 0 255 0\n7 8 9 30 0 0 255\n")
    cloud = read_cloud(path)
    assert cloud.format == "pts" and cloud.normals is None
    np.testing.assert_array_equal(cloud.points[:, 0], [1, 4, 7])
    assert list(cloud.fields) == ["intensity", "red", "green", "blue"]
    np.testing.assert_array_equal(cloud.fields["green"], [0, 255, 0])
    path.write_text("5\n1 2 3\n4 5 6\n")
    assert_error(path, "line 1 declares 5 points but 2")


def test_csv_named_columns_in_any_order(tmp_path):
    path = tmp_path / "pts.csv"
    order = ["nz", "label", "x", "ny", "z", "nx", "y"]
    data = {"x": PTS[:, 0], "y": PTS[:, 1], "z": PTS[:, 2], "nx": NRM[:, 0], "ny": NRM[:, 1], "nz": NRM[:, 2],
            "label": np.arange(20.0)}
    lines = [",".join(f'"{n.upper()}"' if n == "x" else n for n in order)]
    lines += [", ".join(repr(float(data[n][i])) for n in order) for i in range(20)]
    path.write_text("\r\n".join(lines) + "\r\n", encoding="utf-8-sig")  # Excel-style BOM and CRLF
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, PTS)
    np.testing.assert_array_equal(cloud.normals, NRM)
    np.testing.assert_array_equal(cloud.fields["label"], np.arange(20.0))


@pytest.mark.parametrize("content", ["x;y;z\n1;2;3\n4;5;6\n", "x,y,z,\n1,2,3,\n4,5,6,\n",
                                     "# scan\n2\n1 2 3\n4 5 6\n"])
def test_semicolons_trailing_commas_commented_count(tmp_path, content):
    path = tmp_path / "c.csv"
    path.write_text(content)
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    assert cloud.fields == {}


@pytest.mark.parametrize("content, where", [("0,,0\n1,2,3\n4,5,6\n", "line 1: column 2"),
                                            ("1,2,3\n0,,0\n4,5,6\n", "line 2: column 2"),
                                            ("x,y,z\n,2,3\n4,5,6\n", "line 2: column 1"),
                                            ("x;y;z\n1;2;3\n4;;6\n", "line 3: column 2")])
def test_an_empty_field_is_refused_not_taken_for_a_header(tmp_path, content, where):
    """A data row with a hole ("0,,0") was silently skipped as a header when it came first."""
    path = tmp_path / "holes.csv"
    path.write_text(content)
    assert_error(path, f"{where} of 3 is empty")


def test_text_errors(tmp_path):
    path = tmp_path / "bad.xyz"
    path.write_text("1 2 3\n4 5 6\n7 oops 9\n")
    assert_error(path, "line 3: cannot parse 'oops'")
    path.write_text("x y z\n1 2 3\n4 5\n")
    assert_error(path, "line 3: found 2 columns but line 2 has 3")
    path.write_text("1 2\n3 4\n")
    assert_error(path, "line 1: found 2 column(s); need at least 3")
    path.write_text("x y z\n# nothing else\n")
    assert_error(path, "contains no points")
    path.write_text("\n\n")
    assert_error(path, "no points")


# ------------------------------------------------------------------------------ non-finite


def test_nonfinite_raises_or_drops(tmp_path):
    pts = PTS.copy()
    pts[[3, 7], 1] = [np.nan, np.inf]
    path = write_cloud(tmp_path / "nan.ply", pts, normals=NRM, fields={"id": np.arange(20)})
    message = assert_error(path, "2 of 20 points have non-finite")
    assert "drop_nonfinite=True" in message
    with pytest.warns(UserWarning, match="dropped 2 of 20 points"):
        cloud = read_cloud(path, drop_nonfinite=True)
    keep = np.setdiff1d(np.arange(20), [3, 7])
    np.testing.assert_array_equal(cloud.points, PTS[keep])
    np.testing.assert_array_equal(cloud.normals, NRM[keep])
    np.testing.assert_array_equal(cloud.fields["id"], keep)
    path.write_text("nan 1 2\n")
    path = path.rename(tmp_path / "nan.xyz")
    assert_error(path, "all 1 points have non-finite", drop_nonfinite=True)


def test_zero_length_normals_are_kept(tmp_path):
    normals = NRM.copy()
    normals[0] = 0
    cloud = read_cloud(write_cloud(tmp_path / "z.ply", PTS, normals=normals))
    np.testing.assert_array_equal(cloud.normals, normals)


# ------------------------------------------------------------------------------ PCD


def pcd_header(fields, sizes, types, counts, n, data):
    return (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {' '.join(fields)}\n"
            f"SIZE {' '.join(map(str, sizes))}\nTYPE {' '.join(types)}\nCOUNT {' '.join(map(str, counts))}\n"
            f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {data}\n").encode()


def lzf_literal(data: bytes) -> bytes:
    """LZF 'compression' using only literal runs (valid input for any LZF decoder)."""
    return b"".join(bytes([len(c) - 1]) + c for c in (data[i : i + 32] for i in range(0, len(data), 32)))


PCD_FIELDS = (["x", "y", "z", "normal_x", "normal_y", "normal_z", "rgb", "_"], [4] * 8, ["F"] * 7 + ["U"],
              [1] * 8)


def pcd_table():
    dtype = np.dtype([(f"f{i}", "<f4") for i in range(7)] + [("pad", "<u4")])
    table = np.zeros(20, dtype)
    for i in range(3):
        table[f"f{i}"], table[f"f{i + 3}"] = PTS[:, i], NRM[:, i]
    table["f6"] = np.full(20, 0x00FF8001, "<u4").view("<f4")  # packed r=255 g=128 b=1
    return table


@pytest.mark.parametrize("mode", ["ascii", "binary", "binary_compressed"])
def test_pcd(tmp_path, mode):
    table = pcd_table()
    path = tmp_path / f"{mode}.pcd"
    head = pcd_header(*PCD_FIELDS, 20, mode)
    if mode == "ascii":
        rows = [" ".join(repr(float(v)) for v in list(r)[:6]) + f" {r[6]!r} 0" for r in table.tolist()]
        path.write_bytes(head + ("\n".join(rows) + "\n").encode())
    elif mode == "binary":
        path.write_bytes(head + table.tobytes())
    else:
        soa = b"".join(np.ascontiguousarray(table[name]).tobytes() for name in table.dtype.names)
        packed = lzf_literal(soa)
        path.write_bytes(head + struct.pack("<II", len(packed), len(soa)) + packed)
    cloud = read_cloud(path)
    assert cloud.format == "pcd"
    np.testing.assert_array_equal(cloud.points, PTS.astype("f4"))
    np.testing.assert_array_equal(cloud.normals, NRM.astype("f4"))
    if mode != "ascii":  # ascii rgb text is rounded
        assert [cloud.fields[c][0] for c in ("red", "green", "blue")] == [255, 128, 1]
    assert set(cloud.fields) == {"red", "green", "blue"}


def test_pcd_errors(tmp_path):
    path = tmp_path / "t.pcd"
    path.write_bytes(pcd_header(*PCD_FIELDS, 20, "binary") + pcd_table().tobytes()[:-5])
    assert_error(path, "truncated")
    path.write_bytes(pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 3, "ascii") + b"1 2 3\n4 5 6\n")
    assert_error(path, "truncated: the header declares 3 points but 2")
    path.write_bytes(pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 2, "ascii") + b"1 2 3\n4 x 6\n")
    assert_error(path, "line 13: cannot parse 'x'")
    path.write_bytes(pcd_header(["x", "y", "z"], [4] * 3, ["F"] * 3, [1] * 3, 1, "binary_compressed")
                     + struct.pack("<II", 3, 12) + b"\x05ab")
    assert_error(path, "corrupt compressed")
    path.write_bytes(b"VERSION 0.7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n")
    assert_error(path, "no x, y, z fields")


def test_lzf_back_references():
    # "abc" literal, then a back reference of length 5 at distance 3 (overlapping copy)
    assert lzf_decompress(bytes([2]) + b"abc" + bytes([(3 << 5) | 0, 2]), 8) == b"abcabcab"
    # long reference: length code 7 + extra byte 1 -> 7 + 1 + 2 = 10 bytes at distance 1
    assert lzf_decompress(bytes([0]) + b"z" + bytes([7 << 5, 1, 0]), 11) == b"z" * 11
    with pytest.raises(ValueError, match="before the start"):
        lzf_decompress(bytes([0]) + b"z" + bytes([1 << 5, 5]), 4)


# ------------------------------------------------------------------------------ OBJ / STL


def test_obj_face_normals(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("# cube corner\no thing\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\n"
                    "vn 0 0 -1\nvn 0 0 1\nf 1//1 2//1 3//1\nf -3/1/-1 -2/1/-1 -1/1/-1\n")
    cloud = read_cloud(path)
    assert cloud.format == "obj"
    np.testing.assert_array_equal(cloud.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_array_equal(cloud.normals[0], [0, 0, -1])
    np.testing.assert_array_equal(cloud.normals[3], [0, 0, 1])
    np.testing.assert_allclose(cloud.normals[1], [0, 0, 0])  # opposite normals: their mean is zero, kept


def test_obj_normals_in_order_and_without(tmp_path):
    path = tmp_path / "pc.obj"
    path.write_text("".join(f"v {p[0]!r} {p[1]!r} {p[2]!r}\n" for p in PTS.tolist())
                    + "".join(f"vn {n[0]!r} {n[1]!r} {n[2]!r}\n" for n in NRM.tolist()))
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, PTS)
    np.testing.assert_array_equal(cloud.normals, NRM)
    path.write_text("v 1 2 3\nv 4 5 6\nvn 0 0 1\n")
    with pytest.warns(UserWarning, match="normals ignored"):
        assert read_cloud(path).normals is None
    path.write_text("v 1 2 3\nv 4 5\n")
    assert_error(path, "line 2: a 'v' line needs 3 numbers")


def write_stl_ascii(path, triangles):
    body = "".join("facet normal 0 0 1\n outer loop\n" + "".join(f"  vertex {x!r} {y!r} {z!r}\n" for x, y, z in t)
                   + " endloop\nendfacet\n" for t in triangles.tolist())
    path.write_text(f"solid test\n{body}endsolid test\n")


def write_stl_binary(path, triangles, header=b"binary stl"):
    records = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = triangles
    path.write_bytes(header.ljust(80, b" ") + struct.pack("<I", len(triangles)) + records.tobytes())


TRIANGLES = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[1, 0, 0], [1, 1, 0], [0, 1, -0.0]]], dtype="f4")


@pytest.mark.parametrize("kind", ["ascii", "binary", "binary_solid"])
def test_stl(tmp_path, kind):
    path = tmp_path / "tri.STL"
    if kind == "ascii":
        write_stl_ascii(path, TRIANGLES)
    else:
        write_stl_binary(path, TRIANGLES, header=b"solid but binary" if kind == "binary_solid" else b"bin")
    cloud = read_cloud(path)
    assert cloud.format == "stl" and cloud.normals is None
    np.testing.assert_array_equal(cloud.points, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])


def test_stl_errors(tmp_path):
    path = tmp_path / "t.stl"
    write_stl_binary(path, TRIANGLES)
    path.write_bytes(path.read_bytes()[:-7])
    assert_error(path, "truncated: the binary STL header declares 2 triangles")
    path.write_bytes(b"short")
    assert_error(path, "too short")
    path.write_text("solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2 3\nvertex 1 q 3\nvertex 0 0 0\n")
    assert_error(path, "line 5: cannot parse 'vertex 1 q 3'")


# ------------------------------------------------------------------------------ VTK / VTP / LAS


def vtk_polydata():
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    poly, points = vtkPolyData(), vtkPoints()
    points.SetData(numpy_to_vtk(PTS, deep=True))
    poly.SetPoints(points)
    normals = numpy_to_vtk(NRM, deep=True)
    normals.SetName("Normals")
    poly.GetPointData().SetNormals(normals)
    scalars = numpy_to_vtk(np.arange(20, dtype=np.float32), deep=True)
    scalars.SetName("intensity")
    poly.GetPointData().AddArray(scalars)
    return poly


@pytest.mark.parametrize("kind", ["vtk-ascii", "vtk-binary", "vtp"])
def test_vtk_and_vtp(tmp_path, kind):
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    path = tmp_path / ("c.vtp" if kind == "vtp" else "c.vtk")
    writer = vtkXMLPolyDataWriter() if kind == "vtp" else vtkPolyDataWriter()
    if kind == "vtk-binary":
        writer.SetFileTypeToBinary()
    if kind == "vtk-ascii":
        writer.SetFileVersion(42)  # plain legacy 4.2, readable by older tools too
    writer.SetFileName(str(path))
    writer.SetInputData(vtk_polydata())
    writer.Write()
    cloud = read_cloud(path)
    assert cloud.format == path.suffix[1:]
    np.testing.assert_allclose(cloud.points, PTS, atol=1e-6 if kind == "vtk-ascii" else 0)
    np.testing.assert_allclose(cloud.normals, NRM, atol=1e-6 if kind == "vtk-ascii" else 0)
    np.testing.assert_array_equal(cloud.fields["intensity"], np.arange(20))


def test_vtk_errors(tmp_path, capfd):
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    for name, writer in [("t.vtk", vtkPolyDataWriter()), ("t.vtp", vtkXMLPolyDataWriter())]:
        if name == "t.vtk":
            writer.SetFileTypeToBinary()
        writer.SetFileName(str(tmp_path / name))
        writer.SetInputData(vtk_polydata())
        writer.Write()
        data = (tmp_path / name).read_bytes()
        (tmp_path / f"trunc_{name}").write_bytes(data[: len(data) * 2 // 3])
        # a .vtp's first compressed array then runs past the end: refused before VTK reads it
        assert_error(tmp_path / f"trunc_{name}", "truncated or corrupt" if name == "t.vtk" else "past the end of the data")
    (tmp_path / "junk.vtk").write_text("hello world\n")
    assert_error(tmp_path / "junk.vtk", "VTK cannot read it")
    (tmp_path / "junk.vtp").write_text("hello world\n")
    assert_error(tmp_path / "junk.vtp", "VTK cannot read it")
    assert "ERR" not in capfd.readouterr().err  # VTK's messages are captured, not printed


def test_las(tmp_path):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = [1e-4] * 3, [0, 0, 0]
    las = laspy.LasData(header)
    las.x, las.y, las.z = PTS[:, 0], PTS[:, 1], PTS[:, 2]
    las.intensity = np.arange(20)
    las.classification = np.full(20, 2)
    path = tmp_path / "scan.LAS"
    las.write(str(path))
    cloud = read_cloud(path)
    assert cloud.format == "las" and cloud.normals is None
    np.testing.assert_allclose(cloud.points, PTS, atol=1e-4)
    np.testing.assert_array_equal(cloud.fields["intensity"], np.arange(20))
    np.testing.assert_array_equal(cloud.fields["classification"], 2)
    path.write_bytes(path.read_bytes()[:-100])
    assert_error(path, "truncated")
    (tmp_path / "junk.las").write_bytes(b"NOTLAS" * 100)
    assert_error(tmp_path / "junk.las", "not a readable LAS")


def test_laz_without_backend(tmp_path):
    laspy = pytest.importorskip("laspy")
    if laspy.LazBackend.detect_available():
        pytest.skip("a LAZ backend is installed")
    header = laspy.LasHeader(point_format=1, version="1.2")
    las = laspy.LasData(header)
    las.x = las.y = las.z = np.zeros(3)
    path = tmp_path / "scan.laz"
    las.write(str(tmp_path / "plain.las"))
    raw = bytearray((tmp_path / "plain.las").read_bytes())
    raw[104] |= 0x80  # the "points are compressed" bit of the point format id
    path.write_bytes(raw)
    assert_error(path, "pip install lazrs")


# ------------------------------------------------------------------------------ writing


def fake_result(n=20):
    k1, k2 = RNG.random(n), -RNG.random(n)
    return types.SimpleNamespace(points=PTS[:n], normals=NRM[:n], k1=k1, k2=k2, e1=np.eye(3)[np.arange(n) % 3],
                                 e2=np.eye(3)[(np.arange(n) + 1) % 3], gaussian=k1 * k2, mean=(k1 + k2) / 2,
                                 valid=np.arange(n) % 4 != 0)


RESULT_COLUMNS = ["x", "y", "z", "nx", "ny", "nz", "k1", "k2", "e1_x", "e1_y", "e1_z", "e2_x", "e2_y", "e2_z",
                  "gaussian", "mean", "valid"]


@pytest.mark.parametrize("ext", sorted(WRITE_FORMATS))
def test_round_trip(tmp_path, ext):
    fields = {"curv": RNG.standard_normal(20), "label": np.arange(20, dtype=np.int64), "ok": np.arange(20) % 2 == 0,
              "f32": RNG.random(20).astype(np.float32), "dir": NRM[::-1]}
    points, normals = PTS.copy(), NRM.copy()
    points.flags.writeable = False
    out = write_cloud(str(tmp_path / f"rt{ext}"), points, normals=normals, fields=fields)
    assert out == tmp_path / f"rt{ext}" and isinstance(out, Path)
    np.testing.assert_array_equal(points, PTS)  # inputs untouched
    cloud = read_cloud(out)
    np.testing.assert_array_equal(cloud.points, PTS)
    np.testing.assert_array_equal(cloud.normals, NRM)
    assert list(cloud.fields) == ["curv", "label", "ok", "f32", "dir_x", "dir_y", "dir_z"]
    np.testing.assert_array_equal(cloud.fields["curv"], fields["curv"])
    np.testing.assert_array_equal(cloud.fields["label"], np.arange(20))
    np.testing.assert_array_equal(cloud.fields["ok"], fields["ok"])
    np.testing.assert_array_equal(cloud.fields["f32"].astype(np.float32), fields["f32"])  # text: 9 digits
    np.testing.assert_array_equal(cloud.fields["dir_y"], NRM[::-1, 1])
    if ext == ".ply":
        assert cloud.fields["ok"].dtype == np.uint8 and cloud.fields["f32"].dtype == np.float32


@pytest.mark.parametrize("ext", [".xyz", ".txt"])
def test_plain_text_has_no_header_without_fields(tmp_path, ext):
    path = write_cloud(tmp_path / f"p{ext}", PTS, normals=NRM)
    first = path.read_text().splitlines()[0].split()
    assert len(first) == 6 and float(first[0]) == PTS[0, 0]
    np.testing.assert_array_equal(read_cloud(path).normals, NRM)


@pytest.mark.parametrize("ext", [".ply", ".csv"])
def test_write_result(tmp_path, ext):
    result = fake_result()
    path = write_result(tmp_path / f"result{ext}", result)
    if ext == ".ply":
        names = [p.name for p in PlyData.read(str(path))["vertex"].properties]
    else:
        names = path.read_text().splitlines()[0].split(",")
    assert names == RESULT_COLUMNS
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.fields["k1"], result.k1)
    np.testing.assert_array_equal(cloud.fields["e2_y"], result.e2[:, 1])
    np.testing.assert_array_equal(cloud.fields["valid"], result.valid)
    with pytest.raises(TypeError, match="lacks k1"):
        write_result(tmp_path / "x.ply", types.SimpleNamespace(**{k: v for k, v in vars(result).items()
                                                                    if k != "k1"}))


def test_write_validation(tmp_path):
    target = tmp_path / "v.ply"
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        write_cloud(target, np.zeros((4, 2)))
    with pytest.raises(ValueError, match="points must have shape"):
        write_cloud(target, np.zeros((0, 3)))
    with pytest.raises(ValueError, match=r"normals must have shape \(4, 3\)"):
        write_cloud(target, np.zeros((4, 3)), normals=np.zeros((3, 3)))
    with pytest.raises(ValueError, match=r"field 'a' must have shape \(4,\) or \(4, 3\)"):
        write_cloud(target, np.zeros((4, 3)), fields={"a": np.zeros(5)})
    with pytest.raises(ValueError, match="field name 'a b' is invalid"):
        write_cloud(target, np.zeros((4, 3)), fields={"a b": np.zeros(4)})
    with pytest.raises(ValueError, match="nx clash"):
        write_cloud(target, np.zeros((4, 3)), fields={"nx": np.zeros(4)})
    with pytest.raises(ValueError, match="dtype <U1"):
        write_cloud(target, np.zeros((4, 3)), fields={"s": np.array(list("abcd"))})
    with pytest.raises(CloudFileError, match=r"v\.vtk.*unknown file extension '\.vtk' for writing; supported: \.ply"):
        write_cloud(tmp_path / "v.vtk", np.zeros((4, 3)))
    with pytest.raises(CloudFileError, match=r"v\.ply: cannot be written: No such file"):
        write_cloud(tmp_path / "nodir" / "v.ply", np.zeros((4, 3)))
    assert not target.exists() and list(tmp_path.iterdir()) == []
    assert write_cloud(tmp_path / "v.dat", np.ones((4, 3)), format="CSV").read_text().startswith("x,y,z\n")


def failing_writer(f, columns):
    f.write(b"partial data that must never be seen")
    raise RuntimeError("disk full")


def test_atomic_write_keeps_old_file(tmp_path, monkeypatch):
    path = write_cloud(tmp_path / "keep.ply", PTS)
    os.chmod(path, 0o640)
    before = path.read_bytes()
    monkeypatch.setitem(io_write._WRITERS, "ply", failing_writer)
    with pytest.raises(RuntimeError, match="disk full"):
        write_cloud(path, PTS[:3])
    assert path.read_bytes() == before
    with pytest.raises(RuntimeError):
        write_cloud(tmp_path / "new.ply", PTS)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.ply"]  # no temp files, no partial file
    monkeypatch.undo()
    write_cloud(path, PTS[:3])
    assert len(read_cloud(path)) == 3
    if sys.platform != "win32":
        assert stat.S_IMODE(path.stat().st_mode) == 0o640  # permissions of the replaced file kept


# ------------------------------------------------------------------------------ generic


def test_generic_errors(tmp_path):
    assert_error(tmp_path / "missing.ply", "no such file")
    assert_error(tmp_path, "is a directory")
    (tmp_path / "empty.xyz").write_bytes(b"")
    assert_error(tmp_path / "empty.xyz", "empty")
    (tmp_path / "cloud.foo").write_text("1 2 3\n")
    message = assert_error(tmp_path / "cloud.foo", "unknown file extension '.foo'")
    assert all(ext in message for ext in READ_FORMATS)
    assert_error(tmp_path / "cloud.foo", "format='bogus' is not supported", format="bogus")
    assert len(read_cloud(tmp_path / "cloud.foo", format="XYZ")) == 1
    assert read_cloud(tmp_path / "cloud.foo", format=".txt").format == "txt"


def test_error_is_valueerror_and_picklable(tmp_path):
    err = CloudFileError(tmp_path / "a.ply", "truncated")
    assert isinstance(err, ValueError)
    again = pickle.loads(pickle.dumps(err))
    assert str(again) == str(err) and again.problem == "truncated" and again.path.endswith("a.ply")


def test_describe_and_file_untouched(tmp_path):
    pts = PTS.copy()
    pts[0] = np.nan
    path = write_cloud(tmp_path / "d.ply", pts, normals=NRM, fields={"k": np.zeros(20)})
    digest, mtime = hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns
    info = describe(path)
    assert info["format"] == "ply" and info["n_points"] == 20 and info["n_nonfinite"] == 1
    assert info["has_normals"] and info["fields"] == ["k"] and info["n_viewpoints"] == 0
    np.testing.assert_array_equal(info["bbox_min"], PTS[1:].min(axis=0))
    np.testing.assert_array_equal(info["bbox_max"], PTS[1:].max(axis=0))
    assert info["file_size"] == path.stat().st_size and info["bbox_diagonal"] > 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        read_cloud(path, drop_nonfinite=True)
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest and path.stat().st_mtime_ns == mtime


def test_cloud_validates_shapes():
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        Cloud(points=np.zeros((3, 2)))
    with pytest.raises(ValueError, match="normals must have shape"):
        Cloud(points=np.zeros((3, 3)), normals=np.zeros((2, 3)))
    cloud = Cloud(points=[[1, 2, 3]], format="xyz")
    assert cloud.points.dtype == np.float64 and cloud.n_points == 1 and "n_points=1" in repr(cloud)


@pytest.mark.parametrize("candidate", [REPO / "resources" / "bunny.ply", REPO.parent / "shared" / "data" / "bunny.ply"])
def test_bunny(candidate):
    if not candidate.exists():
        pytest.skip(f"{candidate} not present")
    cloud = read_cloud(candidate)
    assert cloud.points.shape == (28088, 3) and cloud.normals.shape == (28088, 3)
    np.testing.assert_allclose(np.linalg.norm(cloud.normals, axis=1), 1, atol=1e-5)
    assert describe(candidate)["bbox_diagonal"] == pytest.approx(1, abs=0.01)
