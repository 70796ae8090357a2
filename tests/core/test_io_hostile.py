"""Hostile files: values out of their declared type, sizes the file cannot hold, broken
LAS headers and LAZ data, text in encodings or number styles the reader does not take,
and degenerate clouds arriving through files."""

from __future__ import annotations

import struct

import warnings

import numpy as np
import pytest

import core
from core.io import CloudFileError
from io_testutils import cpu_seconds, refused as _error

HEAD = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"



@pytest.mark.parametrize("prop, rows, parts", [
    ("uchar red", "0 0 0 300\n1 1 1 2\n", ("vertex 0", "'red' (uchar)", "300", "[0, 255]")),
    ("short s", "0 0 0 4\n1 1 1 40000\n", ("vertex 1", "'s' (short)", "40000", "[-32768, 32767]")),
    ("int i", "0 0 0 4.5\n1 1 1 4\n", ("vertex 0", "4.5", "not an integer")),
    ("char c", "0 0 0 -129\n1 1 1 4\n", ("-129", "[-128, 127]")),
])
def test_ascii_ply_integers_out_of_range_refused(tmp_path, prop, rows, parts):
    path = tmp_path / "bad.ply"
    path.write_text(f"{HEAD}property {prop}\nend_header\n{rows}")
    _error(path, *parts)


def test_ascii_ply_in_range_integers_kept(tmp_path):
    path = tmp_path / "ok.ply"
    path.write_text(f"{HEAD}property uchar red\nproperty short s\nend_header\n0 0 0 255 -32768\n1 1 1 0 32767\n")
    cloud = core.io.read_cloud(path)
    assert cloud.fields["red"].dtype == np.uint8 and cloud.fields["red"].tolist() == [255, 0]
    assert cloud.fields["s"].tolist() == [-32768, 32767]


def test_ascii_ply_with_list_property_out_of_range_refused(tmp_path):
    path = tmp_path / "list.ply"
    path.write_text(f"{HEAD}property uchar red\nproperty list uchar int idx\nend_header\n0 0 0 300 1 5\n1 1 1 2 1 5\n")
    _error(path, "malformed PLY data", "300")


@pytest.mark.parametrize("fmt, element, tail", [
    ("binary_little_endian", "vertex 1000000000000", b""),
    ("ascii", "vertex 1000000000000", b"0 0 0\n"),
    ("binary_little_endian", "vertex 1\nproperty float x\nproperty float y\nproperty float z\nelement face 500000000\n"
     "property list uchar int vertex_indices", b"\0" * 12),
])
def test_ply_declared_size_checked_before_allocating(tmp_path, fmt, element, tail):
    path = tmp_path / "huge.ply"
    props = "" if "face" in element else "\nproperty float x\nproperty float y\nproperty float z"
    path.write_bytes(f"ply\nformat {fmt} 1.0\nelement {element}{props}\nend_header\n".encode() + tail)
    ordinary = tmp_path / "ordinary.ply"
    core.io.write_cloud(ordinary, np.random.default_rng(0).random((30, 3)))
    read = cpu_seconds(lambda: core.io.read_cloud(ordinary))
    assert cpu_seconds(lambda: _error(path, "truncated: the header declares"), 1) < 20 * read


def _las(path, scale=(0.01, 0.01, 0.01)):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = list(scale), [0.0, 0.0, 0.0]
    las = laspy.LasData(header)
    t = np.arange(30.0)
    las.x, las.y, las.z = np.cos(t), np.sin(t), t / 10
    las.write(path)
    return path


@pytest.mark.parametrize("value", [0.0, float("nan"), float("inf")])
def test_las_zero_or_nonfinite_scale_refused(tmp_path, value):
    data = bytearray(_las(tmp_path / "a.las").read_bytes())
    data[139:147] = struct.pack("<d", value)  # the y scale factor of a LAS 1.2 header
    path = tmp_path / "bad.las"
    path.write_bytes(bytes(data))
    _error(path, "invalid header", "scales")


def test_corrupt_or_truncated_laz_is_one_clear_error(tmp_path):
    pytest.importorskip("lazrs")
    data = _las(tmp_path / "a.laz").read_bytes()
    (tmp_path / "trunc.laz").write_bytes(data[:-40])
    _error(tmp_path / "trunc.laz", "LAZ")
    broken = bytearray(data)
    broken[-60:-20] = bytes(b ^ 0x5A for b in broken[-60:-20])
    (tmp_path / "corrupt.laz").write_bytes(bytes(broken))
    _error(tmp_path / "corrupt.laz", "LAZ")


CSV = "x,y,z\n0,0,0\n1,0,0\n0,1,0\n1,1,1.5\n"


def test_utf16_csv_with_bom_read(tmp_path):
    for codec in ("utf-16", "utf-16-be"):
        path = tmp_path / f"{codec}.csv"
        data = CSV.encode(codec)
        path.write_bytes(data if codec == "utf-16" else b"\xfe\xff" + data)
        np.testing.assert_array_equal(core.io.read_cloud(path).points[3], [1, 1, 1.5])


def test_utf16_csv_without_bom_named(tmp_path):
    path = tmp_path / "u16.csv"
    path.write_bytes(CSV.encode("utf-16-le"))
    _error(path, "UTF-16")


@pytest.mark.parametrize("name, text", [
    ("semi.csv", "x;y;z\n0,5;0;0\n1;0,25;0\n0;1;0\n"),
    ("space.xyz", "0,5 0 0\n1 0,25 0\n0 1 0\n"),
])
def test_decimal_comma_named(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    _error(path, "decimal commas")


def _write_identical(path, ext):
    pts = np.full((60, 3), 2.5)
    if ext == "ply":
        core.io.write_cloud(path, pts)
    elif ext == "vtp":
        pv = pytest.importorskip("pyvista")
        pv.PolyData(pts).save(path)
    else:
        laspy = pytest.importorskip("laspy")
        las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
        las.header.scales, las.header.offsets = [0.01] * 3, [0.0] * 3
        las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
        las.write(path)


@pytest.mark.parametrize("ext", ["ply", "vtp", "las"])
def test_identical_points_through_files_invalid(tmp_path, ext):
    path = tmp_path / f"same.{ext}"
    _write_identical(path, ext)
    cloud = core.io.read_cloud(path)
    res = core.estimate(cloud.points, cloud.normals, k=10)
    assert not res.valid.any() and "identical" in res.params["degenerate"]



def test_las_with_impossible_vlr_count_refused_at_once(tmp_path):
    data = bytearray(_las(tmp_path / "a.las").read_bytes())
    data[100:104] = struct.pack("<I", 0xFFFFFFF0)  # number of variable-length records
    path = tmp_path / "vlrs.las"
    path.write_bytes(bytes(data))
    read = cpu_seconds(lambda: core.io.read_cloud(tmp_path / "a.las"))  # 30 points
    assert cpu_seconds(lambda: _error(path, "variable-length records"), 1) < 20 * read  # laspy loops for minutes


def test_las_header_version_garbage_is_a_clear_error(tmp_path):
    data = bytearray(_las(tmp_path / "a.las").read_bytes())
    data[24:26] = bytes([1, 5])
    (tmp_path / "v.las").write_bytes(bytes(data[:400]))
    _error(tmp_path / "v.las")


@pytest.mark.parametrize("where, part", [("table", "chunk table"), ("chunk", "chunks of")])
def test_laz_sizes_that_would_abort_lazrs_refused(tmp_path, where, part):
    """lazrs aborts the whole process on these (a failed allocation, not an exception)."""
    pytest.importorskip("lazrs")
    data = bytearray(_las(tmp_path / "a.laz").read_bytes())
    header_size, offset = struct.unpack_from("<HI", data, 94)
    if where == "table":
        table = struct.unpack_from("<q", data, offset)[0]
        struct.pack_into("<I", data, table + 4, 0xFFFFFFF0)  # number of chunks
    else:
        struct.pack_into("<I", data, header_size + 54 + 12, 0xFFFFFFF0)  # LASzip VLR: chunk size
    path = tmp_path / "bad.laz"
    path.write_bytes(bytes(data))
    _error(path, part)


def test_laz_variable_chunks_point_count_beyond_memory_refused(tmp_path):
    """Variable-size chunks keep their point counts compressed, so a LAZ file's count cannot be
    checked against its size: a count of 4 billion was given one 146 GB allocation (overcommitted)
    before lazrs ran out of data ("failed to fill whole buffer"); below the machine's memory the
    allocation is real."""
    pytest.importorskip("lazrs")
    data = bytearray(_las(tmp_path / "a.laz").read_bytes())
    header_size = struct.unpack_from("<H", data, 94)[0]
    struct.pack_into("<I", data, header_size + 54 + 12, 0xFFFFFFFF)  # LASzip VLR: variable chunks
    struct.pack_into("<I", data, 107, 0xFFFFFFF0)  # number of points
    path = tmp_path / "count.laz"
    path.write_bytes(bytes(data))
    _error(path, "declares 4294967280 points", "GB of memory available")


def test_laz_point_count_judged_against_the_memory_available(tmp_path, monkeypatch):
    """The same check on an undamaged file: refused only when its points would not fit."""
    pytest.importorskip("lazrs")
    path = _las(tmp_path / "ok.laz")
    assert len(core.io.read_cloud(path).points) == 30
    monkeypatch.setattr("core.io.cloud.available_memory", lambda: 30 * 60)
    _error(path, "declares 30 points")


def test_vtk_with_non_utf8_bytes_is_a_clear_error(tmp_path):
    path = tmp_path / "bad.vtk"
    path.write_bytes(b"\x80# vtk DataFile Version 5.1\nvtk output\nASCII\nDATASET POLYDATA\nPOINTS 1 double\n0 0 0\n")
    _error(path, "VTK cannot read it")


def _pcd(path, size, typ, rows, data="ascii"):
    path.write_bytes(f"VERSION 0.7\nFIELDS x y z\nSIZE {size}\nTYPE {typ}\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
                     f"POINTS 3\nDATA {data}\n".encode() + rows)
    return path


@pytest.mark.parametrize("size", ["4,", ",", "16", "3"])
@pytest.mark.parametrize("data", ["ascii", "binary"])
def test_pcd_size_not_1_2_4_8_refused(tmp_path, size, data):
    """numpy reads the type "<f4," as a structured dtype: column_stack then failed with a DTypePromotionError."""
    path = _pcd(tmp_path / "size.pcd", f"{size} 4 4", "F F F", b"0 0 0\n1 0 0\n0 1 0\n" if data == "ascii" else b"\0" * 48,
                data)
    _error(path, "field 'x' SIZE", repr(size), "allowed: 1, 2, 4, 8")


def test_ascii_pcd_integers_out_of_range_refused(tmp_path):
    """A 1-byte I field holding 1000 was cast to -24 without a word."""
    _error(_pcd(tmp_path / "int.pcd", "1 1 1", "I I I", b"0 0 0\n1 0 0\n0 1 1000\n"),
           "point 2", "field 'z' (TYPE I SIZE 1)", "1000", "[-128, 127]")
    _error(_pcd(tmp_path / "frac.pcd", "4 4 2", "F F U", b"0 0 0\n1 0 1.5\n0 1 0\n"), "point 1", "1.5", "[0, 65535]")
    cloud = core.io.read_cloud(_pcd(tmp_path / "ok.pcd", "4 4 1", "F F U", b"0 0 0\n1 0 255\n0 1 0\n"))
    assert cloud.points[1, 2] == 255


def test_ascii_pcd_floats_beyond_their_type_refused(tmp_path):
    """A 4-byte F field holding 1e39 became inf, with numpy's overflow warning leaking out;
    inf and nan written as such are values, and an 8-byte F holds 1e300."""
    _error(_pcd(tmp_path / "big.pcd", "4 4 4", "F F F", b"0 0 0\n1 0 0\n0 1e39 0\n"),
           "point 2", "field 'y' (TYPE F SIZE 4)", "1e+39", "beyond the range")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)  # the drop is announced
        cloud = core.io.read_cloud(_pcd(tmp_path / "inf.pcd", "4 4 8", "F F F", b"0 0 0\n1 0 inf\n0 1 1e300\n"),
                                   drop_nonfinite=True)
    assert len(cloud.points) == 2 and cloud.points[1, 2] == 1e300  # inf read as inf, dropped as asked


def _las14(path):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.add_extra_dims([laspy.ExtraBytesParams(name="nx", type=np.float32)])
    las = laspy.LasData(header)
    las.x, las.y, las.z, las.nx = np.arange(30.0), np.ones(30), np.zeros(30), np.ones(30)
    las.write(path)
    return bytearray(path.read_bytes())


def _las_and_stream_error(path, *parts):
    from core.io.las_stream import open_las

    _error(path, *parts)
    with pytest.raises(CloudFileError, match=parts[0]):
        open_las(path)


def test_las_zero_size_extra_bytes_refused(tmp_path):
    """Data type 0 with a size of 0 made laspy divide by zero (a ZeroDivisionError traceback)."""
    data = _las14(tmp_path / "a.las")
    eb = data.find(b"LASF_Spec") - 2 + 54  # the extra-bytes VLR's first 192-byte descriptor
    data[eb + 2 : eb + 4] = b"\0\0"
    (tmp_path / "eb.las").write_bytes(bytes(data))
    _las_and_stream_error(tmp_path / "eb.las", "dimension 'nx' has a size of 0 bytes")


@pytest.mark.parametrize("where, part", [
    ("offset", "point data starts at byte 4294967295"),
    ("evlrs", "extended variable-length records"),
    ("laz_count", "hold at most"),
])
def test_las_offsets_and_counts_past_the_file_refused(tmp_path, where, part):
    """laspy allocated what these ask for: 4 GB for the offset, a record length read from the
    file's first bytes, and a bytearray of 4 billion LAZ points (a MemoryError, or a
    machine's whole memory for a few hundred million)."""
    name = "a.laz" if where == "laz_count" else "a.las"
    if where == "laz_count":
        pytest.importorskip("lazrs")
    data = _las14(tmp_path / name)
    if where == "offset":
        struct.pack_into("<I", data, 96, 0xFFFFFFFF)
    elif where == "evlrs":
        struct.pack_into("<QI", data, 235, 0, 5)  # 5 extended VLRs from byte 0
    else:
        struct.pack_into("<Q", data, 247, 4_000_000_000)  # the LAS 1.4 point count
    path = tmp_path / f"bad_{name}"
    path.write_bytes(bytes(data))
    _las_and_stream_error(path, part)


_VTK42 = "# vtk DataFile Version 4.2\nx\n{mode}\nDATASET {kind}\nPOINTS 3 float\n"


@pytest.mark.parametrize("mode, kind, cells, part", [
    ("ASCII", "POLYDATA", b"VERTICES 1 2\n1000000 0\n", "VERTICES section: cell 0 declares 1000000 point ids"),
    ("ASCII", "UNSTRUCTURED_GRID", b"CELLS 1 2\n1000000 0\nCELL_TYPES 1\n1\n", "CELLS section: cell 0"),
    ("BINARY", "POLYDATA", b"LINES 2 3\n" + struct.pack(">3i", 1, 0, 5_000_000) + b"\n", "cell 1 declares 5000000"),
    ("BINARY", "POLYDATA", b"VERTICES 1000000000 1000000000\n" + struct.pack(">2i", 1, 0), "truncated: 'VERTICES"),
])
def test_legacy_vtk_cell_counts_past_their_array_refused(tmp_path, mode, kind, cells, part):
    """VTK walked these counts past the cell array and the process died of a segmentation fault."""
    pytest.importorskip("vtkmodules")
    xyz = b"0 0 0 1 0 0 0 1 0\n" if mode == "ASCII" else struct.pack(">9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + b"\n"
    path = tmp_path / "cells.vtk"
    path.write_bytes(_VTK42.format(mode=mode, kind=kind).encode() + xyz + cells)
    _error(path, part)
    path.write_bytes(_VTK42.format(mode=mode, kind=kind).encode() + xyz)  # the points alone read
    assert len(core.io.read_cloud(path)) == 3


def test_vtk_image_data_of_more_points_than_memory_refused(tmp_path):
    """Image data stores no points: 10**15 of them from a 100-byte header ended in numpy's
    MemoryError (and a few hundred million in the machine's whole memory)."""
    pytest.importorskip("vtkmodules")
    path = tmp_path / "grid.vtk"
    path.write_text("# vtk DataFile Version 4.2\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 100000 100000 100000\n"
                    "SPACING 1 1 1\nORIGIN 0 0 0\n")
    _error(path, "vtkStructuredPoints of 1000000000000000 points", "GB of memory available")


def test_obj_with_utf8_bom_keeps_its_first_vertex(tmp_path):
    """Read as latin-1, the BOM made the first line's key 'ï»¿v' and the first vertex was dropped silently."""
    path = tmp_path / "bom.obj"
    path.write_bytes(b"\xef\xbb\xbfv 5 6 7\nv 1 0 0\nv 0 1 0\n")
    np.testing.assert_array_equal(core.io.read_cloud(path).points[0], [5, 6, 7])


@pytest.mark.parametrize("old, new, part", [
    ('NumberOfPoints="3"', 'NumberOfPoints="3000000000000"', 'NumberOfPoints="3000000000000"'),
    ('NumberOfComponents="3"', 'NumberOfComponents="1000000000000"', "1000000000000 components"),
])
def test_vtp_counts_beyond_memory_refused(tmp_path, old, new, part):
    """VTK allocated these before reading any data: std::bad_alloc aborted the process (and a
    huge NumberOfComponents kept it busy for minutes). A huge cell count is ignored with the cells
    (test_io_vtp_cells)."""
    pv = pytest.importorskip("pyvista")
    path = tmp_path / "a.vtp"
    pv.PolyData(np.eye(3)).save(path, binary=False)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    _error(path, part, "GB of memory available")


def test_huge_coordinates_through_files_give_an_invalid_result_that_writes(tmp_path):
    """estimate refused to fit coordinates of 1e300 (valid=False), but writing the result
    computed the anisotropy with a kd-tree search that overflowed: the CLI said only
    "Encountering floating point overflow. The value of p too large" and wrote nothing."""
    t = np.random.default_rng(0).random((60, 2))
    path = tmp_path / "huge.ply"
    core.io.write_cloud(path, np.column_stack([t, (t ** 2).sum(axis=1)]) * 1e300)
    cloud = core.io.read_cloud(path)
    res = core.estimate(cloud.points, k=15)
    assert not res.valid.any() and "overflow" in res.params["degenerate"]
    core.io.write_result(tmp_path / "out.ply", res)
    assert np.isnan(core.io.read_cloud(tmp_path / "out.ply").fields["anisotropy"]).all()


def test_vtk_with_a_garbled_version_is_checked_as_legacy(tmp_path):
    """A version of 1000000000000 was taken as >= 5 and not checked, but VTK read the file's
    OFFSETS line as legacy cell counts and died of a segmentation fault."""
    pv = pytest.importorskip("pyvista")
    path = tmp_path / "v.vtk"
    pv.PolyData(np.eye(3)).save(path, binary=True)
    data = path.read_bytes()
    assert data.startswith(b"# vtk DataFile Version 5.1")
    path.write_bytes(data.replace(b"Version 5.1", b"Version 1000000000000", 1))
    _error(path, "corrupt VERTICES section")
