"""Third audit of the file readers and writers: rows dropped or columns read against their
names without a word (text numbers with units, names of another count, repeated names),
PLY int64/uint64/float16 properties, LAZ headers counting fewer points than their chunks,
and writes whose fields came back as the normals, or failed with a bare encoder error."""

from __future__ import annotations

import io
import struct

import numpy as np
import pytest

from core.io import CloudFileError, read_cloud, write_cloud

ROWS = "1 2 3\n4 5 6\n7 8 9\n"


def _write(path, text: str | bytes):
    path.write_bytes(text.encode() if isinstance(text, str) else text)
    return path


# ------------------------------------------------------------------ text: numbers with units


@pytest.mark.parametrize("name, text, line, token", [
    ("a.xyz", "1.5m 2.5m 3.5m\n" + ROWS, 1, "1.5m"),              # the first row was a header: dropped
    ("a.csv", "1.5 m,2.5 m,3.5 m\n" + ROWS.replace(" ", ","), 1, "1.5 m"),
    ("a.csv", "x,y,z\n1.5m,2.5m,3.5m\n" + ROWS.replace(" ", ","), 2, "1.5m"),
    ("a.xyz", "12mm 25mm 3.5mm 0.5\n1 2 3 4\n4 5 6 7\n", 1, "12mm"),  # its '0.5' became a field name
    ("a.xyz", "1.5° 2.5° 3.5\n" + ROWS, 1, "1.5°"),
    ("a.xyz", "1.5m 2.5m 3.5m\n1.5m 2.5m 3.5m\n", 1, "1.5m"),     # "no numeric data lines"
    ("a.xyz", ROWS + "1.5ft 2ft 3ft\n", 4, "1.5ft"),              # a later line: now says why
])
def test_text_numbers_with_units_are_refused_by_line_and_token(tmp_path, name, text, line, token):
    path = _write(tmp_path / name, text)
    with pytest.raises(CloudFileError, match=f"line {line}: cannot parse '{token}' as a number .*unit"):
        read_cloud(path)


@pytest.mark.parametrize("header", ["m m m", "x y z", "1st 2nd 3rd", "[m] [m] [m]"])
def test_text_unit_and_name_lines_stay_headers(tmp_path, header):
    assert len(read_cloud(_write(tmp_path / "a.xyz", f"{header}\n" + ROWS))) == 3


@pytest.mark.parametrize("token", ["1_000", "１"])
def test_text_numbers_python_takes_but_the_parser_does_not_are_named(tmp_path, token):
    """Python's float takes "1_000" and full-width digits, np.loadtxt does not: the line was
    not found and the message was numpy's ("at row 0, column 1")."""
    path = _write(tmp_path / "a.xyz", f"{token} 2 3\n" + ROWS)
    with pytest.raises(CloudFileError, match=f"line 1: cannot parse '{token}' as a number"):
        read_cloud(path)


@pytest.mark.parametrize("text, line, token", [
    ('x,y,z\n"1,000.5","2,000.5","3,000.5"\n"4,000.5","5,000.5","6,000.5"\n', 2, "1,000.5"),
    ('"1,5","2,5","3,5"\n"4,5","5,5","6,5"\n', 1, "1,5"),
    ('x,y,z\n1,2,3\n"4,5",5,6\n7,8,9\n', 3, "4,5"),
])
def test_text_quoted_numbers_with_commas_are_named_by_line(tmp_path, text, line, token):
    """Refused with numpy's "could not convert string '1,000.5' to float64 at row 0, column 1"
    (or "found 3 columns but line 2 has 4": the quotes were not read as quotes)."""
    path = _write(tmp_path / "a.csv", text)
    with pytest.raises(CloudFileError, match=f"line {line}: cannot parse '{token}' as a number .*decimal comma"):
        read_cloud(path)


def test_text_quoted_names_with_commas_are_one_name_each(tmp_path):
    cloud = read_cloud(_write(tmp_path / "a.csv", '"x","y","z","Point, id"\n1,2,3,4\n4,5,6,7\n7,8,9,1\n'))
    assert list(cloud.fields) == ["Point, id"] and cloud.points[1].tolist() == [4, 5, 6]


def test_text_header_row_of_numbers_in_two_separator_styles_is_named(tmp_path):
    """"1,2,3;4,5" before the data: a StopIteration escaped the reader (no ValueError)."""
    with pytest.raises(CloudFileError, match="line 2: cannot parse '3;4' as a number"):
        read_cloud(_write(tmp_path / "a.csv", "x,y,z,i\n1,2,3;4,5\n7,8,9,1\n"))


# ------------------------------------------------------------------ text: PTS of several scans

_BLOCKS = "3\n1 2 3 10\n4 5 6 20\n7 8 9 30\n2\n1 1 1 5\n2 2 2 6\n"


@pytest.mark.parametrize("ext", ["pts", "xyz"])
def test_text_count_blocks_are_read_with_their_scan(tmp_path, ext):
    """Leica Cyclone writes a PTS of several scans as blocks, each with its count line: it
    was refused at the second count line ("line 5: found 1 columns but line 2 has 4")."""
    cloud = read_cloud(_write(tmp_path / f"a.{ext}", _BLOCKS))
    assert len(cloud) == 5 and cloud.points[3].tolist() == [1, 1, 1]
    assert cloud.fields["scan"].tolist() == [0, 0, 0, 1, 1]


@pytest.mark.parametrize("text, match", [
    (_BLOCKS + "3\n1 1 1 1\n", "truncated: line 8 declares 3 points but 1 rows follow"),
    (_BLOCKS.replace("\n2\n", "\n1\n") + "3\n1 1 1 1\n1 1 1 1\n1 1 1 1\n",
     "line 7: expected the point count of the next block"),
    (_BLOCKS.replace("2 2 2 6", "2 x 2 6"), "line 7: cannot parse 'x' as a number"),
])
def test_text_count_blocks_that_do_not_add_up_are_named(tmp_path, text, match):
    with pytest.raises(CloudFileError, match=match):
        read_cloud(_write(tmp_path / "a.pts", text))


# ------------------------------------------------------------------ text: names against the data


@pytest.mark.parametrize("text, match", [
    ("y x z\n1 2 3 9\n4 5 6 9\n7 8 9 9\n", r"line 1 names 3 columns \(y, x, z\) but the data lines have 4"),
    ("y x z nx ny nz\n" + "1 2 3 0 0 1 9\n" * 3, "names 6 columns"),
    ("id,y,x,z\n1,2,3\n4,5,6\n7,8,9\n", "names 4 columns"),
    ("x,x,y,z\n1,2,3,4\n4,5,6,7\n7,8,9,1\n", "names the column.* x more than once"),
    ("x,y,z,X\n1,2,3,4\n4,5,6,7\n7,8,9,1\n", "names the column.* x more than once"),
    ("x y z nx nx nz\n" + "1 2 3 0 0 1\n" * 3, "nx more than once"),
])
def test_text_names_that_do_not_fit_the_data_are_refused(tmp_path, text, match):
    """Such a names line was dropped and the columns read by position: x and y swapped."""
    path = _write(tmp_path / "a.csv", text)
    with pytest.raises(CloudFileError, match=match):
        read_cloud(path)


def test_text_names_with_x_y_z_first_still_read_by_position(tmp_path):
    cloud = read_cloud(_write(tmp_path / "a.txt", "x y z\n1 2 3 9\n4 5 6 9\n7 8 9 9\n"))
    assert cloud.points[0].tolist() == [1, 2, 3] and list(cloud.fields) == ["col3"]


def test_text_repeated_field_names_keep_both_columns(tmp_path):
    cloud = read_cloud(_write(tmp_path / "a.csv", "x,y,z,i,i,i_2\n1,2,3,4,5,6\n4,5,6,7,8,9\n7,8,9,1,2,3\n"))
    assert {name: values[0] for name, values in cloud.fields.items()} == {"i": 4, "i_3": 5, "i_2": 6}


def test_text_unnamed_index_column_gets_a_name(tmp_path):
    """pandas' to_csv writes ",x,y,z": the field was called '' (and could not be written back)."""
    cloud = read_cloud(_write(tmp_path / "a.csv", ",x,y,z\n0,1,2,3\n1,4,5,6\n2,7,8,9\n"))
    assert list(cloud.fields) == ["col0"] and cloud.points[2].tolist() == [7, 8, 9]
    write_cloud(tmp_path / "b.ply", cloud.points, fields=cloud.fields)


# ------------------------------------------------------------------ OBJ colours, PCD header entries


def test_obj_vertex_colours_are_read(tmp_path):
    """'v x y z r g b' (MeshLab, CloudCompare): the colours were dropped without a word."""
    path = _write(tmp_path / "a.obj", "v 1 2 3 0.1 0.2 0.3\nv 4 5 6 1 0 0\nv 7 8 9 0 1 0\nf 1 2 3\n")
    cloud = read_cloud(path)
    assert cloud.points[2].tolist() == [7, 8, 9]
    assert cloud.fields["red"].tolist() == [0.1, 1, 0] and cloud.fields["blue"].tolist() == [0.3, 0, 0]


def test_obj_vertex_weights_are_not_colours(tmp_path):
    cloud = read_cloud(_write(tmp_path / "a.obj", "v 1 2 3 1\nv 4 5 6 1\nv 7 8 9 0.5\n"))
    assert cloud.fields == {}


@pytest.mark.parametrize("old, new, match", [
    ("COUNT 1 1 1", "COUNT 1 1 0", "field 'z' COUNT '0'; a count is an integer >= 1"),
    ("TYPE F F F", "TYPE F F Q", "field 'z' TYPE 'Q'; allowed: F, I, U"),
    ("POINTS 3", "POINTS -3", "POINTS '-3'; it must be an integer >= 0"),
    ("POINTS 3", "POINTS 3.5", "POINTS '3.5'"),
    ("WIDTH 3\nHEIGHT 1\nPOINTS 3\n", "", "no POINTS or WIDTH line"),
    ("SIZE 4 4 4", "SIZE 4 4 1", "field 'z' TYPE 'F' SIZE '1'; a float \\(F\\) has SIZE 4 or 8"),
])
def test_pcd_header_entries_are_named(tmp_path, old, new, match):
    """All were "the PCD header has an invalid FIELDS/SIZE/TYPE/COUNT/POINTS entry"."""
    text = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\n"
            "DATA ascii\n" + ROWS)
    assert old in text
    with pytest.raises(CloudFileError, match=match):
        read_cloud(_write(tmp_path / "a.pcd", text.replace(old, new)))


# ------------------------------------------------------------------ byte-order marks and UTF-16

_BOM = b"\xef\xbb\xbf"
_STL = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 1 2 3\nvertex 4 5 6\nvertex 7 8 9\nendloop\nendfacet\nendsolid t\n"
_PTX = b"1\n3\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 2 3 0.5\n4 5 6 0.5\n7 8 9 0.5\n"


@pytest.mark.parametrize("name, data", [("a.stl", _BOM + _STL), ("a.ptx", _BOM + _PTX)])
def test_utf8_byte_order_mark_is_skipped(tmp_path, name, data):
    """The ASCII STL was taken for a binary one ("declares 1818521189 triangles"), the PTX
    refused its first line ('ï»¿1')."""
    assert read_cloud(_write(tmp_path / name, data)).points.tolist() == [[1, 2, 3], [4, 5, 6], [7, 8, 9]]


@pytest.mark.parametrize("name, text", [("a.obj", "v 1 2 3\nv 4 5 6\nv 7 8 9\n"),
                                        ("a.off", "OFF\n3 0 0\n1 2 3\n4 5 6\n7 8 9\n")])
@pytest.mark.parametrize("encoding, kind", [("utf-16", "UTF-16"), ("utf-32", "UTF-32")])
def test_utf16_mesh_text_is_named(tmp_path, name, text, encoding, kind):
    """"contains no points", or "starts with 'ÿþO\x00F\x00F\x00'"."""
    with pytest.raises(CloudFileError, match=f"is {kind} text .*save it as UTF-8"):
        read_cloud(_write(tmp_path / name, text.encode(encoding)))


@pytest.mark.parametrize("name, text", [
    ("a.off", "OFF\n3 0 0\n1 2 3\n4 5 6\n7 8 9\n"),              # "the counts ... found '3 0 0 1 2 3 ...'"
    ("a.pcd", "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\n"
              "DATA ascii\n1 2 3\n4 5 6\n7 8 9\n"),                # "truncated: ... ends before its DATA line"
    ("a.vtk", "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n1 2 3 4 5 6 7 8 9\n"),
    ("a.ptx", _PTX.decode()),
])
def test_lines_ending_in_cr_alone_are_named(tmp_path, name, text):
    if name.endswith(".vtk"):
        pytest.importorskip("vtk")
    with pytest.raises(CloudFileError, match="has lines ending in CR alone"):
        read_cloud(_write(tmp_path / name, text.replace("\n", "\r")))
    assert len(read_cloud(_write(tmp_path / name, text.replace("\n", "\r\n")))) == 3


def test_legacy_vtk_behind_a_byte_order_mark_is_named(tmp_path):
    pytest.importorskip("vtk")
    text = b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n1 2 3 4 5 6 7 8 9\n"
    with pytest.raises(CloudFileError, match="starts with a UTF-8 byte-order mark"):
        read_cloud(_write(tmp_path / "a.vtk", _BOM + text))


# ------------------------------------------------------------------ PLY: 64-bit integers and half floats

_BIG = 1700000000000000123  # a nanosecond time stamp: beyond float64's 2**53


def _ply(fmt: str, props: str, body: bytes, elements: str = "") -> bytes:
    return (f"ply\nformat {fmt} 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            f"{props}{elements}end_header\n").encode() + body


@pytest.mark.parametrize("order", ["<", ">"])
@pytest.mark.parametrize("faces", [False, True])
def test_binary_ply_int64_uint64_float16_read(tmp_path, order, faces):
    """trimesh writes these types; plyfile refused the header ("field type 'int64' not in [...]")."""
    data = np.zeros(3, dtype=[(c, order + "f4") for c in "xyz"] + [("t", order + "i8"), ("u", order + "u8"),
                                                                   ("h", order + "f2")])
    data["x"], data["t"], data["u"], data["h"] = [1, 4, 7], [_BIG, -5, 0], [2**64 - 1, 3, 0], [1.5, 0.25, -2]
    fmt = "binary_little_endian" if order == "<" else "binary_big_endian"
    face = struct.pack(order + "Bqqq", 3, 0, 1, 2) if faces else b""
    elements = "element face 1\nproperty list uchar int64 vertex_indices\n" if faces else ""
    path = _write(tmp_path / "a.ply", _ply(fmt, "property int64 t\nproperty uint64 u\nproperty float16 h\n",
                                          data.tobytes() + face, elements))
    cloud = read_cloud(path)
    assert cloud.points[:, 0].tolist() == [1, 4, 7]
    assert cloud.fields["t"].tolist() == [_BIG, -5, 0] and cloud.fields["t"].dtype.kind == "i"
    assert cloud.fields["u"].tolist() == [2**64 - 1, 3, 0] and cloud.fields["u"].dtype.kind == "u"
    assert cloud.fields["h"].tolist() == [1.5, 0.25, -2] and cloud.fields["h"].dtype.itemsize == 2


def test_ascii_ply_int64_is_read_exactly(tmp_path):
    path = _write(tmp_path / "a.ply", _ply("ascii", "property int64 t\nproperty uint64 u\n",
                                          f"1 2 3 {_BIG} {2**64 - 1}\n4 5 6 -5 0\n7 8 9 9 1\n".encode()))
    cloud = read_cloud(path)
    assert cloud.fields["t"].tolist() == [_BIG, -5, 9] and cloud.fields["u"].tolist() == [2**64 - 1, 0, 1]


@pytest.mark.parametrize("props, row, match", [
    ("property int64 t\n", f"1 2 3 {2**63}", "holds an integer beyond the range"),
    ("property float16 h\n", "1 2 3 1e6", "'h' \\(float16\\) has the value 1e\\+06, beyond the range"),
])
def test_ascii_ply_values_beyond_the_wide_types_refused(tmp_path, props, row, match):
    path = _write(tmp_path / "a.ply", _ply("ascii", props, f"{row}\n4 5 6 1\n7 8 9 1\n".encode()))
    with pytest.raises(CloudFileError, match=match):
        read_cloud(path)


@pytest.mark.parametrize("old, new", [("end_header\n", "end_header \n"), ("ply\n", "ply \n"), ("ply", "\ufeffply")])
@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_ply_header_blanks_and_byte_order_mark_are_read(tmp_path, old, new, fmt):
    """Refused as "non-ASCII bytes in the header", "expected one of {}" or "unexpected
    characters after 'ply'"; RPly and tinyply read them."""
    body = b"1 2 3\n4 5 6\n7 8 9\n" if fmt == "ascii" else np.arange(1, 10, dtype="<f4").tobytes()
    data = _ply(fmt, "", body)
    head, tail = data[: data.index(b"end_header") + 11], data[data.index(b"end_header") + 11 :]
    path = _write(tmp_path / "a.ply", head.decode().replace(old, new, 1).encode() + tail)
    assert read_cloud(path).points.tolist() == [[1, 2, 3], [4, 5, 6], [7, 8, 9]]


def test_ply_repeated_property_is_named(tmp_path):
    """numpy's "two properties with same name" named neither the element nor the property."""
    path = _write(tmp_path / "a.ply", _ply("ascii", "property float x\n", b"1 2 3 4\n4 5 6 4\n7 8 9 4\n"))
    with pytest.raises(CloudFileError, match="element 'vertex' declares the property 'x' more than once"):
        read_cloud(path)


# ------------------------------------------------------------------ LAZ: a count below the chunks


def _laz(path, n=120_000):
    laspy = pytest.importorskip("laspy")
    pytest.importorskip("lazrs")
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales, header.offsets = np.array([0.01] * 3), np.zeros(3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = (np.random.default_rng(3).random((n, 3)) * 100).T
    las.write(path)  # fixed chunks of 50 000 points: 3 chunks
    return path


def _patch(path, offset: int, fmt: str, value) -> None:
    data = bytearray(path.read_bytes())
    struct.pack_into(fmt, data, offset, value)
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("declared", [60_000, 100_000])
def test_laz_count_below_its_chunks_is_refused(tmp_path, declared):
    """laspy decompressed only the declared points: a whole chunk after them was dropped."""
    path = _laz(tmp_path / "a.laz")
    _patch(path, 107, "<I", declared)
    with pytest.raises(CloudFileError, match=f"declares {declared} points but its 3 compressed chunks of 50000 "
                                             "hold at least 100001"):
        read_cloud(path)


def test_laz_count_within_its_last_chunk_still_reads(tmp_path):
    """Points missing from the count inside the last chunk cannot be told without decompressing it."""
    path = _laz(tmp_path / "a.laz")
    _patch(path, 107, "<I", 100_001)
    assert len(read_cloud(path)) == 100_001


def _variable_laz(path, sizes):
    """A LAZ file of variable-size chunks of ``sizes`` points (the chunk table counts them)."""
    laspy = pytest.importorskip("laspy")
    lazrs = pytest.importorskip("lazrs")
    n = sum(sizes)
    header = laspy.LasHeader(point_format=0, version="1.2")
    header.scales = np.array([0.01] * 3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = (np.random.default_rng(4).random((n, 3)) * 100).T
    buf = io.BytesIO()
    las.write(buf, do_compress=True)
    data = buf.getvalue()
    vlr = lazrs.LazVlr.new_for_compression(0, 0, True)
    start = data.index(b"laszip encoded") - 2
    record = bytes(vlr.record_data())
    assert struct.unpack_from("<H", data, start + 20)[0] == len(record)
    head = bytearray(data[: struct.unpack_from("<I", data, 96)[0]])
    head[start + 54 : start + 54 + len(record)] = record
    out = io.BytesIO()
    out.write(bytes(head))
    compressor = lazrs.LasZipCompressor(out, vlr)
    raw = np.frombuffer(las.points.array.tobytes(), np.uint8).reshape(n, -1)
    first = 0
    for i, size in enumerate(sizes):
        compressor.compress_many(raw[first : first + size].tobytes())
        first += size
        if i < len(sizes) - 1:
            compressor.finish_current_chunk()
    compressor.done()
    path.write_bytes(out.getvalue())
    return path


def test_laz_variable_chunks_count_below_the_points_is_refused(tmp_path):
    path = _variable_laz(tmp_path / "a.laz", [100, 50, 30])
    assert len(read_cloud(path)) == 180
    _patch(path, 107, "<I", 170)
    with pytest.raises(CloudFileError, match="declares 170 points but its 3 compressed chunks hold 180"):
        read_cloud(path)
    _patch(path, 107, "<I", 200)  # was lazrs' "IoError: failed to fill whole buffer"
    with pytest.raises(CloudFileError, match="truncated: the header declares 200 points but its 3 compressed "
                                             "chunks hold 180"):
        read_cloud(path)


# ------------------------------------------------------------------ writes: fields and the normals


def test_write_into_a_missing_folder_names_the_folder(tmp_path):
    with pytest.raises(CloudFileError, match=r"cannot be written: No such file or directory \(the folder '.*nowhere' "
                                             r"does not exist\)"):
        write_cloud(tmp_path / "nowhere" / "a.ply", np.zeros((3, 3)))



@pytest.fixture
def cloud():
    rng = np.random.default_rng(5)
    points = rng.random((10, 3))
    return points, points / np.linalg.norm(points, axis=1)[:, None]


@pytest.mark.parametrize("ext", ["ply", "csv", "xyz", "vtp"])
@pytest.mark.parametrize("name", ["n", "normal"])
def test_field_spelled_as_normals_is_refused_without_normals(tmp_path, cloud, ext, name):
    """It was written as n_x n_y n_z (or normal_x ..., or a VTP array 'normal') and read back
    as the cloud's normals: a file written without normals came back with them."""
    if ext == "vtp":
        pytest.importorskip("vtk")
    points, normals = cloud
    with pytest.raises(ValueError, match="normals"):
        write_cloud(tmp_path / f"a.{ext}", points, fields={name: normals})
    assert not (tmp_path / f"a.{ext}").exists()


@pytest.mark.parametrize("names", [("1", "2", "3", "4"), ("5m", "6m", "7m", "8m")])
def test_csv_with_number_like_field_names_round_trips(tmp_path, cloud, names):
    """The names line "x,y,z,1,2,3,4" is mostly numbers: it was refused as a data line
    ("line 1: cannot parse 'x' as a number")."""
    points, _ = cloud
    fields = {name: np.arange(10) * i for i, name in enumerate(names)}
    back = read_cloud(write_cloud(tmp_path / "a.csv", points, fields=fields))
    assert np.array_equal(back.points, points) and list(back.fields) == list(names)


def test_vtp_field_called_normals_is_refused(tmp_path, cloud):
    """A second array 'Normals' next to the normals: one of the two was lost on reading."""
    points, normals = cloud
    with pytest.raises(ValueError, match="VTP file's normals"):
        write_cloud(tmp_path / "a.vtp", points, normals=normals, fields={"Normals": normals * 2})


@pytest.mark.parametrize("ext", ["ply", "csv"])
def test_fields_spelled_as_normals_next_to_the_normals_round_trip(tmp_path, cloud, ext):
    points, normals = cloud
    cloud = read_cloud(write_cloud(tmp_path / f"a.{ext}", points, normals=normals, fields={"normal": normals * 2}))
    assert np.array_equal(cloud.normals, normals)
    assert np.array_equal(cloud.fields["normal_x"], normals[:, 0] * 2)


def test_vtp_non_ascii_field_name_round_trips(tmp_path, cloud):
    """The XML was encoded as ASCII: a bare UnicodeEncodeError, and no file."""
    pytest.importorskip("vtk")
    points, _ = cloud
    cloud = read_cloud(write_cloud(tmp_path / "a.vtp", points, fields={"Intensité": np.arange(10)}))
    assert cloud.fields["Intensité"].tolist() == list(range(10))


def test_ply_non_ascii_field_name_is_refused_by_name(tmp_path, cloud):
    points, _ = cloud
    with pytest.raises(ValueError, match="field name 'Intensité' is not ASCII, which a PLY header cannot hold"):
        write_cloud(tmp_path / "a.ply", points, fields={"Intensité": np.arange(10)})
