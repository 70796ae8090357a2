"""Reader defects found by a mutation fuzz of every format (byte flips, truncations, header
edits): a binary PLY vertex element of no properties divided by zero; a legacy VTK cell
array with entries left after its cells crashed VTK (a segmentation fault), so did a dataset
FIELD section VTK could not read, cells after a header line of over 512 bytes, a negative
cell count in a version 5 file, cells under a version "5'1" and a binary cell array whose
count line lost its newline; a layered LAZ chunk
declaring a 4 GB layer aborted lazrs (a failed allocation), a LASzip record of no items
panicked it; a text header of a long run of digits took hours. Files that could end the
process are read in a subprocess with limited memory (``helpers.read_in_child``)."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from core.io import CloudFileError, read_cloud
from io_testutils import cpu_seconds, refused as _error

BINARY_PLY = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
FACE = b"element face 1\nproperty list uchar int vertex_indices\n"



@pytest.mark.parametrize("header, body, part", [
    (b"", b"", "no x, y, z properties"),  # records of 0 bytes: numpy could not count them
    (b"", b"abc", "3 bytes are left after the last vertex row"),  # finding the vertex count divided by 0
    (FACE, b"\x01\0\0\0\0", "no x, y, z properties"),  # so did fitting the vertices before the faces
])
def test_binary_ply_vertex_of_no_properties_named(tmp_path, header, body, part):
    path = tmp_path / "empty_vertex.ply"
    path.write_bytes(BINARY_PLY + header + b"end_header\n" + body)
    _error(path, part)


POINTS = "".join(f"{i} {i * i % 7} {i % 3}\n" for i in range(12))


def _legacy_vtk(tmp_path, name, binary, cells: str, ids):
    if binary:
        data = b"".join(struct.pack(">3f", i, i * i % 7, i % 3) for i in range(12)) + b"\n"
        data += f"{cells}\n".encode() + np.asarray(ids, ">i4").tobytes() + b"\n"
    else:
        data = f"{POINTS}{cells}\n{' '.join(map(str, ids))}\n".encode()
    path = tmp_path / name
    mode = "BINARY" if binary else "ASCII"
    path.write_bytes(f"# vtk DataFile Version 3.0\nt\n{mode}\nDATASET POLYDATA\nPOINTS 12 float\n".encode() + data)
    return path


def test_legacy_vtk_cell_entries_left_over_refused(tmp_path, helpers):
    """VTK walks (count, ids...) runs to the end of the array, whatever the cell count says:
    an entry left after the last cell was taken as the count of one more, read past the array."""
    paths = [
        _legacy_vtk(tmp_path, "ascii.vtk", False, "VERTICES 2 5", [1, 0, 1, 1, 1000000000]),
        _legacy_vtk(tmp_path, "binary.vtk", True, "VERTICES 3 6", [1, 0, 1, 1, 0, 100000000]),  # an empty cell
    ]
    answers = helpers.read_in_child(paths)
    for path, taken, size in zip(paths, (4, 5), (5, 6)):
        assert path.name in answers[str(path)] and "corrupt VERTICES section" in answers[str(path)]
        assert f"take {taken} of the {size} entries" in answers[str(path)]


def test_legacy_vtk_cells_checked_after_a_long_header_line(tmp_path, helpers):
    """The checks took the header from the first 512 bytes: a longer version or title line
    (VTK reads 255 bytes of it and skips the rest) skipped them, and VTK crashed."""
    path = _legacy_vtk(tmp_path, "title.vtk", True, "VERTICES 3 6", [1, 0, 1, 1, 0, 100000000])
    path.write_bytes(path.read_bytes().replace(b"\nt\n", b"\n" + b"t" * 600 + b"\n", 1))
    answer = helpers.read_in_child([path])[str(path)]
    assert "take 5 of the 6 entries" in answer, answer


def test_vtk_negative_cell_count_and_version_without_a_minor_refused(tmp_path, helpers):
    """A version 5 binary file with a negative count on its VERTICES or POINTS line, and a version
    "5'1" (VTK reads no version: legacy cells, which the check skipped as version 5), both
    crashed VTK."""
    negative = tmp_path / "negative.vtk"
    negative.write_bytes(b"# vtk DataFile Version 5.1\nt\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n"
                         + np.arange(12, dtype=">f4").tobytes() + b"\nVERTICES 3 -1\nOFFSETS vtktypeint64\n"
                         + np.arange(3, dtype=">i8").tobytes() + b"\nCONNECTIVITY vtktypeint64\n"
                         + np.arange(2, dtype=">i8").tobytes() + b"\n")
    version = _legacy_vtk(tmp_path, "version.vtk", True, "VERTICES 3 6", [1, 0, 1, 1, 0, 100000000])
    version.write_bytes(version.read_bytes().replace(b"Version 3.0", b"Version 5'1", 1))
    points = tmp_path / "points.vtk"
    points.write_bytes(negative.read_bytes().replace(b"POINTS 4", b"POINTS -2147483649").replace(b"3 -1", b"3 2"))
    answers = helpers.read_in_child([negative, points, version])
    assert "'VERTICES 3 -1' declares a negative count" in answers[str(negative)], answers
    assert "'POINTS -2147483649' declares a negative count" in answers[str(points)], answers
    assert "take 5 of the 6 entries" in answers[str(version)], answers


def test_legacy_vtk_cells_using_every_entry_still_read(tmp_path):
    path = _legacy_vtk(tmp_path, "ok.vtk", False, "VERTICES 3 7", [1, 0, 0, 3, 1, 2, 3])  # an empty cell
    assert len(read_cloud(path)) == 12


@pytest.mark.parametrize("dataset", ["POLYDATA", "STRUCTURED_POINTS", "UNSTRUCTURED_GRID"])
def test_legacy_vtk_dataset_field_data_vtk_cannot_read_refused(tmp_path, helpers, dataset):
    """A dataset's FIELD section that VTK fails to read (fewer arrays than declared, a header
    only, FIELDS for DIMENSIONS) was used all the same: a segmentation fault."""
    head = f"# vtk DataFile Version 3.0\nField data\nASCII\nDATASET {dataset}\n"
    bodies = {"short": "FIELD f 2\nA 1 3 float\n1 2 3\n", "header": "FIELD f 1\n", "fields": "FIELDS 3 2 2\n",
              "inline": "0 0 FIELD f 1\n"}  # VTK reads words: a keyword after data on its line counts
    paths = []
    for name, body in bodies.items():
        paths.append(tmp_path / f"{name}.vtk")
        paths[-1].write_text(head + body + POINTS.join(["POINTS 12 float\n", ""]) * (dataset == "POLYDATA"))
    answers = helpers.read_in_child(paths)
    for path in paths:
        assert path.name in answers[str(path)] and "section (the dataset's field data)" in answers[str(path)]


def test_legacy_vtk_dataset_field_data_still_read(tmp_path):
    """Field data arrays named like the keyword, and strings, in ASCII and binary, old and new versions."""
    vtk = pytest.importorskip("vtkmodules.vtkIOLegacy")
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
    from vtkmodules.vtkCommonDataModel import vtkPolyData

    points = vtkPoints()
    points.SetData(numpy_to_vtk(np.random.default_rng(3).normal(size=(20, 3))))
    data = vtkPolyData()
    data.SetPoints(points)
    for name, values in (("field_x", np.arange(7.0)), ("FIELD", np.arange(6, dtype=np.int32))):
        array = numpy_to_vtk(values)
        array.SetName(name)
        data.GetFieldData().AddArray(array)
    words = vtkStringArray()
    words.SetName("words")
    words.InsertNextValue("field data")
    data.GetFieldData().AddArray(words)
    for binary in (False, True):
        for version in (42, 51):
            path = tmp_path / f"f{binary:d}{version}.vtk"
            writer = vtk.vtkPolyDataWriter()
            writer.SetInputData(data)
            writer.SetFileName(str(path))
            writer.SetFileVersion(version)
            writer.SetFileTypeToBinary() if binary else writer.SetFileTypeToASCII()
            writer.Write()
            assert len(read_cloud(path)) == 20


def _layered_laz(path, extra=False):
    laspy = pytest.importorskip("laspy")
    pytest.importorskip("lazrs")
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.scales, header.offsets = [0.001] * 3, [0.0] * 3
    if extra:
        header.add_extra_dims([laspy.ExtraBytesParams(name="q", type=np.float32)])
    las = laspy.LasData(header)
    t = np.arange(30.0)
    las.x, las.y, las.z = np.cos(t), np.sin(t), t / 10
    las.write(path)
    return path


def test_laz_layer_size_beyond_its_chunk_refused(tmp_path, helpers):
    """A layered chunk (point format 7) is its first point (36 bytes), its point count and one
    size per layer (9 for the point, 1 for RGB): lazrs allocated a corrupt size of 4 GB at once."""
    data = bytearray(_layered_laz(tmp_path / "a.laz").read_bytes())
    offset = struct.unpack_from("<I", data, 96)[0]
    struct.pack_into("<I", data, offset + 8 + 36 + 4 + 4 * 3, 0xFFFF0000)  # the flags layer
    path = tmp_path / "layer.laz"
    path.write_bytes(bytes(data))
    message = helpers.read_in_child([path])[str(path)]
    assert path.name in message and "chunk 0 declares layers of 4294" in message, message


def test_layered_laz_of_several_chunks_with_extra_bytes_still_read(tmp_path):
    """The layers counted per item: 9 + 1 (RGB) + 4 (extra bytes, one per byte), chunk by chunk."""
    laspy = pytest.importorskip("laspy")
    path = _layered_laz(tmp_path / "b.laz", extra=True)
    las = laspy.read(path)
    big = laspy.LasData(las.header)
    big.points = las.points[np.arange(120_001) % len(las.points)]
    big.write(tmp_path / "c.laz")
    assert len(read_cloud(tmp_path / "c.laz")) == 120_001


def test_laz_record_of_no_items_refused(tmp_path):
    """A LASzip record listing no items (point fields) made lazrs divide by a point size of 0:
    a Rust panic, which Python raises as a BaseException that no reader caught."""
    data = bytearray(_layered_laz(tmp_path / "a.laz").read_bytes())
    header_size = struct.unpack_from("<H", data, 94)[0]
    struct.pack_into("<H", data, header_size + 54 + 32, 0)  # LASzip VLR: number of items
    path = tmp_path / "items.laz"
    path.write_bytes(bytes(data))
    _error(path, "LASzip record describes points of 0 bytes", "36 bytes")


def test_text_header_of_a_long_digit_run_read_at_once(tmp_path):
    """Telling a header from a data line of odd numbers tried every split of a run of digits
    between two parts of a pattern (\\d+\\.?\\d*): seconds for 20,000 digits, hours for a
    megabyte."""
    rows = "".join(f"{i},{i % 3},{i % 5},1\n" for i in range(12))
    path, short = tmp_path / "long.csv", tmp_path / "short.csv"
    path.write_text("x,y,z," + "9" * 20_000 + "q\n" + rows)
    short.write_text("x,y,z," + "9" * 20 + "q\n" + rows)
    assert len(read_cloud(path)) == len(read_cloud(short)) == 12
    assert cpu_seconds(lambda: read_cloud(path), 1) < 20 * cpu_seconds(lambda: read_cloud(short))


@pytest.mark.parametrize("end, part", [
    (b"\0", "cell 0 declares 1347373390"),  # the newline lost: VTK read the ids from after the next line's end
    (b" \t junk", "cell 0 declares 1347373390"),
    (b"\0" * 300, "has no end before its binary data"),  # VTK's read of the line failed, ids left unread
])
def test_legacy_vtk_binary_cells_read_from_where_vtk_reads_them(tmp_path, helpers, end, part):
    """VTK reads a binary cell array's counts as words, then the rest of their line (up to 255
    bytes), then the ids: a damaged end of that line moved the ids (a segmentation fault) where
    the check, which wanted the counts alone on their line, did not look."""
    path = _legacy_vtk(tmp_path, "cells.vtk", True, "VERTICES 3 6", [1, 0, 1, 1, 1, 2])
    path.write_bytes(path.read_bytes().replace(b"VERTICES 3 6\n", b"VERTICES 3 6" + end, 1)
                     + b"POINT_DATA 12\nNORMALS n float\n" + np.zeros(36, ">f4").tobytes())
    answer = helpers.read_in_child([path])[str(path)]
    assert "corrupt VERTICES section" in answer and part in answer, answer


def test_legacy_vtk_binary_cells_after_trailing_blanks_still_read(tmp_path):
    path = _legacy_vtk(tmp_path, "blanks.vtk", True, "VERTICES 3 6", [1, 0, 1, 1, 1, 2])
    path.write_bytes(path.read_bytes().replace(b"VERTICES 3 6\n", b"VERTICES 3 6   \r\n", 1))
    assert len(read_cloud(path)) == 12


class PanicException(BaseException):
    """What pyo3 raises for a Rust panic (its name, and no ``Exception`` base)."""


@pytest.mark.parametrize("reader", ["read_cloud", "open_las", "iter_records", "sample_rows"])
def test_a_laz_decompressor_panic_is_a_clear_error(tmp_path, monkeypatch, reader):
    """A panic of lazrs on a file the checks let through is no ``Exception``: it passed every
    ``except`` (the viewer's worker's too). Every reader that opens the file through laspy
    turns it into a CloudFileError naming the file."""
    laspy = pytest.importorskip("laspy")
    from core.io import las_sample, las_stream

    path = tmp_path / "panic.las"
    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.x, las.y, las.z = np.arange(30.0), np.ones(30), np.zeros(30)
    las.write(str(path))
    info = las_stream.open_las(path)

    def panics(*args, **kwargs):
        raise PanicException("called `Result::unwrap()` on an `Err` value")

    monkeypatch.setattr(laspy, "open", panics)
    read = {"read_cloud": lambda: read_cloud(path), "open_las": lambda: las_stream.open_las(path),
            "iter_records": lambda: list(las_stream.iter_records(path, info=info)),
            "sample_rows": lambda: las_sample._fetch(path, info, np.arange(5), [], lambda *a: None)}[reader]
    with pytest.raises(CloudFileError, match="panic.las: corrupt LAZ data: the decompressor failed"):
        read()


def test_compressed_pcd_beyond_memory_refused_before_decoding(tmp_path, monkeypatch):
    """A binary_compressed PCD declares how many bytes its points expand to (up to 4 GB from a
    48 MB file): more than the memory available is refused before the decoder grows to it."""
    from core.io import cloud

    n = 1000
    soa = np.zeros(3 * n, "<f4").tobytes()
    packed = b"".join(bytes([len(c) - 1]) + c for c in (soa[i:i + 32] for i in range(0, len(soa), 32)))
    path = tmp_path / "big.pcd"
    path.write_bytes(f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
                     f"POINTS {n}\nDATA binary_compressed\n".encode() + struct.pack("<II", len(packed), len(soa)) + packed)
    assert len(read_cloud(path)) == n
    monkeypatch.setattr(cloud, "available_memory", lambda: 10_000)
    _error(path, "decompressing its 12000 bytes of points needs about")


@pytest.mark.parametrize("cut, part", [
    (POINTS.index("4 2 1"), "declares 36 coordinates but 12 follow before the file ends"),  # the file cut short
    (None, "declares 36 coordinates but 33 follow"),  # a point's row lost before the next section
])
def test_legacy_vtk_ascii_points_short_of_their_count_refused(tmp_path, cut, part):
    """VTK read an ASCII POINTS section short of its declared count without a message and
    returned the missing points as whatever memory held (1e+259, 2e-312)."""
    path = _legacy_vtk(tmp_path, "short.vtk", False, "VERTICES 1 2", [1, 0])
    text = path.read_bytes()
    body = text.index(b"POINTS 12 float\n") + len(b"POINTS 12 float\n")
    if cut is None:
        text = text.replace(POINTS.splitlines(keepends=True)[5].encode(), b"", 1)
    else:
        text = text[: body + cut]
    path.write_bytes(text)
    _error(path, "truncated or corrupt POINTS section: 'POINTS 12 float'", part)


def test_legacy_vtk_ascii_points_of_nan_and_inf_still_counted(tmp_path):
    path = _legacy_vtk(tmp_path, "nan.vtk", False, "VERTICES 1 2", [1, 0])
    path.write_bytes(path.read_bytes().replace(b"\n1 1 1\n", b"\nnan -inf inf\n", 1))
    with pytest.warns(UserWarning, match="dropped 1 of 12 points with non-finite coordinates"):
        cloud = read_cloud(path, drop_nonfinite=True)
    assert len(cloud) == 11
