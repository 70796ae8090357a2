"""Reader defects found by the I/O sweep (findings 2, 4, 5-10): headerless colours read as
normals, ASCII PLY floats rounded, element counts that do not match the data, case-variant
property names, UTF-8 text, a bad first data line taken as a header, non-ASCII PLY comments."""

from __future__ import annotations

import struct
import subprocess
import sys
import warnings

import numpy as np
import pytest

import core
from core.io import read_cloud, write_cloud
from io_testutils import refused as _error

RNG = np.random.default_rng(7)
PTS = RNG.normal(size=(40, 3))
NRM = PTS / np.linalg.norm(PTS, axis=1, keepdims=True)
RGB = RNG.integers(0, 256, size=(40, 3)).astype(float)
XYZ_PROPS = "property float x\nproperty float y\nproperty float z\n"



def _read_quietly(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read_cloud(path)


def _save(path, *blocks):
    np.savetxt(path, np.hstack(blocks), fmt="%.10g")
    return path


# finding 2: headerless columns 3-5 become normals only if they are unit vectors

@pytest.mark.parametrize("colours", [RGB, RGB / 255.0], ids=["0-255", "0-1"])
def test_headerless_xyzrgb_colours_are_fields_with_a_warning(tmp_path, colours):
    path = _save(tmp_path / "scan.xyz", PTS, colours)
    with pytest.warns(UserWarning, match=r"columns 3-5 \(counting from 0\) are not unit normals.*col3, col4, col5"):
        cloud = read_cloud(path)
    assert cloud.normals is None
    np.testing.assert_allclose(cloud.fields["col4"], colours[:, 1], rtol=1e-9)


def test_headerless_xyz_intensity_rgb_is_not_normals(tmp_path):
    path = _save(tmp_path / "scan.txt", PTS, RNG.random((40, 1)) * 2000, RGB)
    with pytest.warns(UserWarning, match="scan.txt.*no normals"):
        cloud = read_cloud(path)
    assert cloud.normals is None and list(cloud.fields) == ["col3", "col4", "col5", "col6"]
    pts = _save(tmp_path / "scan.pts", PTS, RNG.random((40, 1)) * 2000, RGB)
    assert list(_read_quietly(pts).fields) == ["intensity", "red", "green", "blue"]  # Leica's layout, no warning


def test_headerless_normals_first_or_after_colours(tmp_path):
    cloud = _read_quietly(_save(tmp_path / "n.xyz", PTS, NRM))
    np.testing.assert_allclose(cloud.normals, NRM, atol=1e-9)
    cloud = _read_quietly(_save(tmp_path / "nrgb.xyz", PTS, NRM, RGB))  # x y z nx ny nz r g b
    np.testing.assert_allclose(cloud.normals, NRM, atol=1e-9)
    assert list(cloud.fields) == ["col6", "col7", "col8"]
    for colours in (RGB, RGB / 255.0):  # CloudCompare: x y z r g b nx ny nz
        cloud = _read_quietly(_save(tmp_path / "rgbn.txt", PTS, colours, NRM))
        np.testing.assert_allclose(cloud.normals, NRM, atol=1e-9)
        assert list(cloud.fields) == ["col3", "col4", "col5"]


def test_headerless_normals_with_zero_and_nan_rows_and_rounding(tmp_path):
    nrm = np.round(NRM, 3)
    nrm[:5] = 0.0
    nrm[5:8] = np.nan
    cloud = _read_quietly(_save(tmp_path / "holes.xyz", PTS, nrm))
    np.testing.assert_array_equal(cloud.normals[:5], 0.0)
    assert np.isnan(cloud.normals[5:8]).all()


def test_headerless_colours_warning_reaches_the_cli(tmp_path):
    path = _save(tmp_path / "scan.xyz", PTS, RGB)
    run = subprocess.run([sys.executable, "-m", "core", "info", str(path)], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
    assert "are not unit normals" in run.stderr


# finding 4: ASCII PLY float coordinates keep the text's precision

def test_ascii_ply_float_coordinates_keep_float64(tmp_path):
    pts = PTS + [500000.123, 4200000.0, 300.0]
    rows = "".join(f"{x:.4f} {y:.4f} {z:.4f} 0.5\n" for x, y, z in pts)
    path = tmp_path / "utm.ply"
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\n{XYZ_PROPS}property float q\nend_header\n"
                    + rows)
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, np.loadtxt(path, skiprows=8)[:, :3])
    assert cloud.fields["q"].dtype == np.float32  # other float properties stay as declared
    binary = tmp_path / "utm_binary.ply"
    binary.write_bytes(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\n{XYZ_PROPS}end_header\n"
                       .encode() + pts.astype("<f4").tobytes())
    np.testing.assert_array_equal(read_cloud(binary).points, pts.astype(np.float32))  # binary: as stored


# findings 5 and 7: element counts that do not match the data

def _binary_ply(path, declared, points, faces=(), order="<"):
    kind = "little" if order == "<" else "big"
    head = f"ply\nformat binary_{kind}_endian 1.0\nelement vertex {declared}\n{XYZ_PROPS}"
    if len(faces):
        head += f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
    body = points.astype(order + "f4").tobytes()
    body += b"".join(struct.pack(f"{order}B{len(f)}i", len(f), *f) for f in faces)
    path.write_bytes((head + "end_header\n").encode() + body)
    return path


TRIANGLES = [(i, (i + 1) % 10, (i + 2) % 10) for i in range(20)]
MIXED = [(0, 1, 2), (0, 1, 2, 3), (4, 5, 6), (1, 2, 3, 4, 5)] * 5


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize("faces", [TRIANGLES, MIXED], ids=["triangles", "mixed"])
def test_binary_ply_with_faces_reads_when_counts_match(tmp_path, faces, order):
    cloud = read_cloud(_binary_ply(tmp_path / "mesh.ply", 10, PTS[:10], faces, order))
    np.testing.assert_array_equal(cloud.points, PTS[:10].astype(np.float32))


@pytest.mark.parametrize("declared", [14, 8])
def test_binary_ply_vertex_count_wrong_before_faces_refused(tmp_path, declared):
    path = _binary_ply(tmp_path / "mesh.ply", declared, PTS[:10], TRIANGLES)
    _error(path, f"declares {declared} vertices but the file holds 10", "20 faces", "does not match")


def test_binary_ply_vertex_count_wrong_before_mixed_faces_refused(tmp_path):
    path = _binary_ply(tmp_path / "mesh.ply", 14, PTS[:10], MIXED)
    _error(path, "declares 14 vertices and 20 faces but the data does not match these counts")


def test_binary_ply_under_declared_vertices_refused(tmp_path):
    path = _binary_ply(tmp_path / "under.ply", 8, PTS[:10])
    _error(path, "declares 8 vertices but the file holds 10")
    path = _binary_ply(tmp_path / "ok.ply", 10, PTS[:10])
    path.write_bytes(path.read_bytes() + b"\n")  # a trailing newline (less than a record) is no data
    assert len(read_cloud(path)) == 10


def test_ascii_ply_under_declared_vertices_refused(tmp_path):
    rows = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in PTS[:10].tolist())
    path = tmp_path / "under.ply"
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 8\n{XYZ_PROPS}end_header\n{rows}")
    _error(path, "declares 8 vertices but 10 vertex rows follow")
    faces = "".join(f"3 {a} {b} {c}\n" for a, b, c in TRIANGLES)
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 9\n{XYZ_PROPS}element face 20\n"
                    f"property list uchar int vertex_indices\nend_header\n{rows}{faces}")
    _error(path, "declares 9 vertices and 20 faces but 30 data lines")


def test_ascii_ply_trailing_blank_lines_and_faces_are_fine(tmp_path):
    rows = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in PTS[:10].tolist())
    faces = "".join(f"3 {a} {b} {c}\n" for a, b, c in TRIANGLES)
    path = tmp_path / "ok.ply"
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 10\n{XYZ_PROPS}end_header\n{rows}\n  \n\n")
    assert len(read_cloud(path)) == 10
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 10\n{XYZ_PROPS}element face 20\n"
                    f"property list uchar int vertex_indices\nend_header\n{rows}{faces}\n")
    assert len(read_cloud(path)) == 10


def test_binary_pcd_under_declared_points_refused(tmp_path):
    path = tmp_path / "under.pcd"
    head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 10\nHEIGHT 1\nPOINTS 8\nDATA binary\n"
    path.write_bytes(head.encode() + PTS[:10].astype("<f4").tobytes())
    _error(path, "declares 8 points", "10 points", "does not match")
    path.write_bytes(head.replace("POINTS 8", "POINTS 10").encode() + PTS[:10].astype("<f4").tobytes())
    assert len(read_cloud(path)) == 10


# finding 6: case-variant property names

def test_ply_exact_case_names_win(tmp_path):
    path = tmp_path / "both.ply"
    table = np.zeros(5, dtype=[(n, "<f4") for n in ("X", "x", "y", "z", "nx", "ny", "nz", "NZ")])
    table["x"], table["X"], table["nz"], table["NZ"] = 1.0, 1000.0, 1.0, 0.0
    core.io.ply.PlyData([core.io.ply.PlyElement.describe(table, "vertex")], text=False).write(str(path))
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points[:, 0], 1.0)
    np.testing.assert_array_equal(cloud.normals[:, 2], 1.0)
    assert list(cloud.fields) == ["X", "NZ"]


def test_ply_uppercase_only_and_ambiguous_names(tmp_path):
    path = tmp_path / "upper.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float X\nproperty float Y\nproperty float Z\n"
                    "end_header\n1 2 3\n4 5 6\n")
    np.testing.assert_array_equal(read_cloud(path).points, [[1, 2, 3], [4, 5, 6]])
    path.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float X\nproperty float y\nproperty float z\n"
                    "property float Nx\nproperty float NX\nproperty float ny\nproperty float nz\n"
                    "end_header\n1 2 3 0 0 0 1\n4 5 6 0 0 0 1\n")
    _error(path, "'Nx', 'NX'", "nx")


@pytest.mark.parametrize("fields, bad", [({"X": 1.0}, "X"), ({"NZ": 0.0}, "NZ"), ({"a": 1.0, "A": 2.0}, "A, a"),
                                         ({"Nx": 1.0}, "Nx")])
def test_writer_refuses_names_clashing_ignoring_case(tmp_path, fields, bad):
    with pytest.raises(ValueError, match=f"field names {bad} clash"):
        write_cloud(tmp_path / "out.ply", PTS, normals=NRM, fields={k: np.full(40, v) for k, v in fields.items()})


# finding 8: UTF-8 text first, latin-1 as the fallback

def test_text_utf8_names_round_trip_and_latin1_fallback(tmp_path):
    for ext in ("csv", "xyz"):
        path = tmp_path / f"out.{ext}"
        write_cloud(path, PTS, fields={"Intensität": np.arange(40.0)})
        assert list(read_cloud(path).fields) == ["Intensität"]
    path = tmp_path / "latin.csv"
    path.write_bytes("x,y,z,Höhe\n1,2,3,4\n5,6,7,8\n".encode("latin-1"))
    assert list(read_cloud(path).fields) == ["Höhe"]
    path.write_bytes("x,y,z,Höhe\n1,2,3,4\n".encode("utf-8-sig"))
    assert list(read_cloud(path).fields) == ["Höhe"]


# finding 9: a first line that is an unparseable data row is refused, not a header

@pytest.mark.parametrize("line, bad", [("1.5 2.5 3.5e", "'3.5e'"), ("0x1.8p+0 0x1.4p+1 0x1.cp+1", "'0x1.8p+0'"),
                                       ("1.5D+00 2.5D+00 3.5D+00", "'1.5D+00'"), ("1.5,2.5x,3", "'2.5x'")])
def test_bad_first_data_line_refused(tmp_path, line, bad):
    path = tmp_path / "first.xyz"
    path.write_text(line + "\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in PTS[:5].tolist()))
    _error(path, "line 1: cannot parse", bad)


@pytest.mark.parametrize("header", ["x y z", "//X,Y,Z", "east north height", "scan 2024-05-01 12:00",
                                    "# 1.5 2.5 3.5e"])
def test_real_headers_still_read(tmp_path, header):
    path = tmp_path / "head.xyz"
    path.write_text(header + "\n1 2 3\n4 5 6\n")
    np.testing.assert_array_equal(read_cloud(path).points, [[1, 2, 3], [4, 5, 6]])


# finding 10: non-ASCII bytes in PLY comments

@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_ply_non_ascii_comment_and_obj_info_accepted(tmp_path, fmt):
    body = (" ".join(map(repr, p)) + "\n" for p in PTS[:10].tolist()) if fmt == "ascii" else ()
    head = (f"ply\nformat {fmt} 1.0\ncomment TextureFile Façade_été.jpg\nobj_info auteur: Zoë\n"
            f"element vertex 10\n{XYZ_PROPS}end_header\n")
    data = "".join(body).encode() if fmt == "ascii" else PTS[:10].astype("<f4").tobytes()
    path = tmp_path / "facade.ply"
    path.write_bytes(head.encode("utf-8") + data)
    np.testing.assert_allclose(read_cloud(path).points, PTS[:10], rtol=1e-6)
    path.write_bytes(head.encode("latin-1") + data)
    assert len(read_cloud(path)) == 10


def test_ply_non_ascii_outside_comments_names_the_line(tmp_path):
    path = tmp_path / "name.ply"
    path.write_bytes("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                     "property float z\nproperty float höhe\nend_header\n1 2 3 4\n".encode("utf-8"))
    _error(path, "line 7", "höhe", "non-ASCII", "comment")
