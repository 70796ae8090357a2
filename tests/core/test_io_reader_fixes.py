"""Readers on files they misread: PCL's ASCII colours, a PCD field listed twice, 8-byte PCD
integers, ASCII PLY floats beyond float32 and rows shifted between elements, binary STL
headers that begin with "solid", ASCII STL names holding "vertex", UTF-32 text, and the
messages and warnings around them."""

from __future__ import annotations

import gc
import struct
import warnings

import numpy as np
import pytest

from core.io import read_cloud
from io_testutils import refused

PCD_HEAD = ("VERSION 0.7\nFIELDS x y z {name}\nSIZE 4 4 4 {size}\nTYPE F F F {kind}\nCOUNT 1 1 1 1\nWIDTH 3\n"
            "HEIGHT 1\nPOINTS 3\nDATA {data}\n")
PLY_XYZ = "ply\nformat ascii 1.0\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n"


def _pcd(path, name, size, kind, body, data="ascii"):
    path.write_bytes(PCD_HEAD.format(name=name, size=size, kind=kind, data=data).encode() + body)
    return path


def _quiet_read(path):
    """read_cloud with numpy's RuntimeWarnings (and ResourceWarnings) made errors."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("error", ResourceWarning)
        return read_cloud(path)


# 1. PCL's writeASCII stores a TYPE F rgb as its uint32

def test_pcl_ascii_rgb_integer_tokens_are_the_colour(tmp_path):
    rgb = (0xFF << 24) | (10 << 16) | (20 << 8) | 30
    body = "".join(f"{p} {rgb}\n" for p in ("0 0 0", "1 0 0", "0 1 0")).encode()
    fields = _quiet_read(_pcd(tmp_path / "pcl.pcd", "rgb", 4, "F", body)).fields
    assert (fields["red"].tolist(), fields["green"].tolist(), fields["blue"].tolist()) == ([10] * 3, [20] * 3, [30] * 3)


def test_pcd_ascii_rgb_float_tokens_keep_their_bits(tmp_path):
    """A colour written as the float holding its bits reads as before, beside integer tokens too."""
    packed = float(np.array([(10 << 16) | (20 << 8) | 30], dtype="<u4").view("<f4")[0])
    body = f"0 0 0 {packed!r}\n1 0 0 {packed!r}\n0 1 0 {(40 << 16) | (50 << 8) | 60}\n".encode()
    fields = _quiet_read(_pcd(tmp_path / "float.pcd", "rgb", 4, "F", body)).fields
    assert fields["red"].tolist() == [10, 10, 40] and fields["blue"].tolist() == [30, 30, 60]


def test_pcd_ascii_rgb_integer_beyond_32_bits_refused(tmp_path):
    path = _pcd(tmp_path / "big.pcd", "rgb", 4, "F", b"0 0 0 1\n1 0 0 4294967296\n0 1 0 1\n")
    refused(path, "point 1", "'rgb'", "4294967296", "[0, 4294967295]")


# 2. a field listed twice

@pytest.mark.parametrize("data, body", [("ascii", b"1 2 3 4\n4 5 6 4\n7 8 9 4\n"), ("binary", bytes(48))])
def test_pcd_field_listed_twice_refused(tmp_path, data, body):
    path = tmp_path / "dup.pcd"
    path.write_bytes(PCD_HEAD.format(name="x", size=4, kind="F", data=data).encode() + body)
    refused(path, "field 'x' occurs more than once")


# 6. 8-byte PCD integers parsed exactly

def test_pcd_ascii_8_byte_integers_exact(tmp_path):
    body = b"0 0 0 9007199254740993\n1 0 0 18446744073709551615\n0 1 0 5\n"
    ids = _quiet_read(_pcd(tmp_path / "u8.pcd", "id", 8, "U", body)).fields["id"]
    assert ids.dtype == np.uint64 and ids.tolist() == [2**53 + 1, 2**64 - 1, 5]
    body = b"0 0 0 -9223372036854775808\n1 0 0 9223372036854775807\n0 1 0 5.0\n"
    assert _quiet_read(_pcd(tmp_path / "i8.pcd", "id", 8, "I", body)).fields["id"].tolist() == [-2**63, 2**63 - 1, 5]


@pytest.mark.parametrize("kind, value", [("U", "18446744073709551616"), ("U", "-1"), ("I", "9223372036854775808"),
                                         ("I", "1.5"), ("I", "nan")])
def test_pcd_ascii_8_byte_integers_out_of_range_refused(tmp_path, kind, value):
    path = _pcd(tmp_path / "bad.pcd", "id", 8, kind, f"0 0 0 1\n1 0 0 {value}\n0 1 0 1\n".encode())
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        refused(path, "point 1", f"field 'id' (TYPE {kind} SIZE 8)", f"the value {value}", "not an integer in")


# 3. ASCII PLY floats beyond float32

def test_ascii_ply_float_beyond_its_type_refused(tmp_path):
    path = tmp_path / "big.ply"
    path.write_text(PLY_XYZ.format(n=3) + "property float nx\nproperty float ny\nproperty float nz\n"
                    "property float intensity\nend_header\n0 0 0 0 0 1 1\n1 0 0 0 0 1 1\n0 1 0 0 1e300 0 1\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        refused(path, "vertex 2", "property 'ny' (float)", "1e+300", "beyond the range")


def test_ascii_ply_float_beyond_its_type_refused_through_plyfile(tmp_path):
    """A vertex with a list property is read by plyfile: its overflow is refused too."""
    path = tmp_path / "list.ply"
    path.write_text(PLY_XYZ.format(n=3) + "property float s\nproperty list uchar int idx\nend_header\n"
                    "0 0 0 1 1 5\n1 0 0 1e300 1 5\n0 1 0 1 1 5\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        refused(path, "element 'vertex'", "beyond the range")


# 4. ASCII PLY rows shifted between elements

FACES = "element face {n}\nproperty list uchar int vertex_indices\nend_header\n"


def test_ascii_ply_rows_shifted_between_elements_refused(tmp_path):
    path = tmp_path / "shifted.ply"
    path.write_text(PLY_XYZ.format(n=3) + FACES.format(n=2) + "0 0 0\n1 0 0\n0 1 0\n0.25 0.75 0.5\n3 0 1 2\n")
    refused(path, "face row 0", "'0.25 0.75 0.5'", "'vertex_indices'", "'0.25'", "3 vertices and 2 faces")


@pytest.mark.parametrize("row, parts", [
    ("3 0 1\n", ("face row 1", "has 3 values", "need 4")),
    ("3 0 1 2 3\n", ("face row 1", "has 5 values", "need 4")),
    ("-3 0 1 2\n", ("face row 1", "'-3'", "not a list length")),
])
def test_ascii_ply_face_rows_that_do_not_fit_refused(tmp_path, row, parts):
    path = tmp_path / "faces.ply"
    path.write_text(PLY_XYZ.format(n=3) + FACES.format(n=2) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n" + row)
    refused(path, *parts)


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_ascii_ply_rows_that_fit_read(tmp_path, newline):
    extra = "element edge 2\nproperty int vertex1\nproperty int vertex2\n"
    body = "0 0 0\n1 0 0\n\n0 1 0\n3\t0 1 2\n\n  4 0 1 2 0  \n0 1\n1 2\n"
    path = tmp_path / "ok.ply"
    path.write_bytes((PLY_XYZ.format(n=3) + FACES.format(n=2).replace("end_header\n", extra + "end_header\n")
                      + body).replace("\n", newline).encode())
    assert len(_quiet_read(path)) == 3


# 5. STL: binary headers beginning with "solid", ASCII names holding "vertex"

def _binary_stl(path, header, tail=b""):
    rec = np.zeros(4, dtype=[("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
    rec["vertices"] = np.random.default_rng(0).uniform(size=(4, 3, 3))
    path.write_bytes(header.ljust(80) + struct.pack("<I", 4) + rec.tobytes() + tail)
    return path


@pytest.mark.parametrize("header, tail", [(b"solid part", b""), (b"solid part", b"\0\0"), (b"solid facet", b"\n"),
                                          (b"solid part", b"\0" * 60)])
def test_binary_stl_with_solid_header_read_as_binary(tmp_path, header, tail):
    assert len(read_cloud(_binary_stl(tmp_path / "bin.stl", header, tail))) == 12


def test_ascii_stl_named_vertex_reads(tmp_path):
    path = tmp_path / "named.stl"
    path.write_text("solid vertex colours\nfacet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  VERTEX 1 0 0\n"
                    "  vertex 0 1 0\n endloop\nendfacet\nendsolid vertex colours\n")
    np.testing.assert_array_equal(read_cloud(path).points, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


def test_ascii_stl_vertex_line_of_two_values_named(tmp_path):
    path = tmp_path / "short.stl"
    path.write_text("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nvertex 0 1 0\n"
                    "endloop\nendfacet\nendsolid t\n")
    refused(path, "line 5", "'vertex 1 0'")


# 7. minor: a wrapper left open, UTF-32 text, integers printed exactly

def test_ply_plyfile_fallback_leaves_no_file_wrapper_open(tmp_path):
    path = tmp_path / "list.ply"
    path.write_text(PLY_XYZ.format(n=3) + "property list uchar int idx\nend_header\n0 0 0 1 5\n1 0 0 1 5\n0 1 0 1 5\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read_cloud(path)
        gc.collect()
    assert [str(w.message) for w in caught if issubclass(w.category, ResourceWarning)] == []


@pytest.mark.parametrize("encoding", ["utf-32", "utf-32-le", "utf-32-be"])
def test_utf32_text_with_bom_reads(tmp_path, encoding):
    path = tmp_path / "u.xyz"
    bom = "" if encoding == "utf-32" else "\ufeff"  # the utf-32 codec writes its own
    path.write_bytes((bom + "1 2 3\n4 5 6\n7 8 9\n").encode(encoding))
    np.testing.assert_array_equal(read_cloud(path).points, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


def test_integer_range_errors_print_the_value_exactly(tmp_path):
    ply = tmp_path / "uint.ply"
    ply.write_text(PLY_XYZ.format(n=2) + "property uint id\nend_header\n0 0 0 4294967296\n1 1 1 0\n")
    refused(ply, "vertex 0", "the value 4294967296,", "[0, 4294967295]")
    pcd = _pcd(tmp_path / "u4.pcd", "id", 4, "U", b"0 0 0 1\n1 0 0 4294967296\n0 1 0 1\n")
    refused(pcd, "point 1", "the value 4294967296,", "[0, 4294967295]")
