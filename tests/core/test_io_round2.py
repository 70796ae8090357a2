"""Second audit of the file readers and writers: rows dropped or columns swapped without a
word (text headers, LAS/STL/OFF counts), refusals that now say what the file is, and round
trips of every writer with invalid (NaN) rows."""

from __future__ import annotations

import gzip
import struct

import numpy as np
import pytest

from core.io import CloudFileError, read_cloud, write_cloud

ROWS = "0 1 2\n1 0 0\n0 1 0\n1 1 1\n"


def _write(path, text: str):
    path.write_bytes(text.encode())
    return path


# ------------------------------------------------------------------ text: the lines before the data


@pytest.mark.parametrize("row", ["NA,NA,NA", "1,null,2", "-,-,-", "N/A,N/A,N/A"])
def test_text_missing_value_row_before_the_data_is_refused(tmp_path, row):
    """A row of missing values after the names was a header line: dropped without a word."""
    path = _write(tmp_path / "a.csv", f"x,y,z\n{row}\n" + ROWS.replace(" ", ","))
    with pytest.raises(CloudFileError, match=r"line 2: cannot parse .* missing value"):
        read_cloud(path)


@pytest.mark.parametrize("after", ["m,m,m", "# exported by a tool", ",,", '"","",""'])
def test_text_names_are_kept_after_a_units_comment_or_empty_line(tmp_path, after):
    """"y,x,z" then another line: the names were taken from the last line only, and x and y
    were read swapped."""
    path = _write(tmp_path / "a.csv", f"y,x,z\n{after}\n" + ROWS.replace(" ", ","))
    cloud = read_cloud(path)
    assert cloud.points[0].tolist() == [1.0, 0.0, 2.0]
    assert len(cloud) == 4


def test_text_normals_named_before_a_comment_are_read(tmp_path):
    path = _write(tmp_path / "a.xyz", "x y z nx ny nz\n# tool 1.0 by me\n" +
                  "".join(f"{r} 2 0 0\n" for r in ROWS.splitlines()))
    cloud = read_cloud(path)
    assert cloud.normals is not None and cloud.normals[0].tolist() == [2.0, 0.0, 0.0]


@pytest.mark.parametrize("first, bad", [("1 2 3 a", "a"), ("0 0 0 ; end", "end"), ("4.5 1 2 m 3", "m")])
def test_text_first_row_with_trailing_text_is_refused(tmp_path, first, bad):
    """A first line of a whole row of numbers and more text was taken for a header and dropped."""
    path = _write(tmp_path / "a.xyz", f"{first}\n" + ROWS)
    with pytest.raises(CloudFileError, match=f"line 1: cannot parse '{bad}'"):
        read_cloud(path)


@pytest.mark.parametrize("header", ["x y z", "Scan 1 of 3", "VIEWPOINT 0 0 0 1 0 0 0", "4"])
def test_text_header_lines_still_read(tmp_path, header):
    path = _write(tmp_path / "a.pts", f"{header}\n" + ROWS)
    assert len(read_cloud(path)) == 4


def test_text_text_row_among_data_rows_names_the_row(tmp_path):
    path = _write(tmp_path / "a.xyz", ROWS + "hello world now\n" + ROWS)
    with pytest.raises(CloudFileError, match=r"line 5: cannot parse 'hello'"):
        read_cloud(path)


# ------------------------------------------------------------------ text writer: round trips


@pytest.mark.parametrize("ext", ["xyz", "txt"])
@pytest.mark.parametrize("kind", ["not unit", "all NaN"])
def test_text_normals_round_trip_when_not_unit(tmp_path, ext, kind):
    """Headerless columns 3-5 are normals only when unit: other normals were read back as
    fields col3..col5 (with a warning) and the cloud had none."""
    rng = np.random.default_rng(0)
    points = rng.random((30, 3))
    normals = rng.normal(size=(30, 3)) * 3 if kind == "not unit" else np.full((30, 3), np.nan)
    path = write_cloud(tmp_path / f"a.{ext}", points, normals=normals)
    cloud = read_cloud(path)
    assert np.array_equal(cloud.normals, normals, equal_nan=True) and not cloud.fields


def test_text_unit_normals_stay_headerless(tmp_path):
    rng = np.random.default_rng(0)
    normals = rng.normal(size=(30, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    normals[4] = np.nan  # an invalid point
    path = write_cloud(tmp_path / "a.xyz", rng.random((30, 3)), normals=normals)
    assert not path.read_text().startswith("#")
    assert np.array_equal(read_cloud(path).normals, normals, equal_nan=True)


@pytest.mark.parametrize("ext", ["ply", "csv", "xyz", "txt", "vtp"])
def test_every_writer_round_trips_invalid_rows(tmp_path, ext):
    pytest.importorskip("vtk") if ext == "vtp" else None
    rng = np.random.default_rng(1)
    n = 25
    points = rng.random((n, 3)) * 200 - 100
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    k1 = rng.random(n)
    normals[[3, 9]] = np.nan
    k1[[3, 9]] = np.nan
    k1[5] = np.inf
    fields = {"k1": k1, "valid": np.isfinite(k1), "e1": rng.random((n, 3)), "k": rng.integers(5, 60, n)}
    path = write_cloud(tmp_path / f"ü €.{ext}", points, normals=normals, fields=fields)
    cloud = read_cloud(path)
    assert np.array_equal(cloud.points, points)
    assert np.array_equal(cloud.normals, normals, equal_nan=True)
    assert np.array_equal(cloud.fields["k1"], k1, equal_nan=True)
    assert np.array_equal(cloud.fields["valid"].astype(bool), fields["valid"])
    assert np.array_equal(cloud.fields["k"], fields["k"])
    assert np.array_equal(np.column_stack([cloud.fields[f"e1_{c}"] for c in "xyz"]), fields["e1"])


# ------------------------------------------------------------------ LAS point counts


def _las(path, version="1.2", point_format=0, n=100):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=point_format, version=version)
    header.scales, header.offsets = np.array([0.001] * 3), np.zeros(3)
    las = laspy.LasData(header)
    xyz = np.random.default_rng(2).random((n, 3)) * 10
    las.x, las.y, las.z = xyz.T
    las.write(path)
    return path


def _patch(path, offset: int, fmt: str, value) -> None:
    data = bytearray(path.read_bytes())
    struct.pack_into(fmt, data, offset, value)
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("version, point_format, offset, fmt", [("1.2", 0, 107, "<I"), ("1.4", 6, 247, "<Q"),
                                                                ("1.4", 1, 247, "<Q")])
@pytest.mark.parametrize("declared", [0, 50])
def test_las_count_below_the_records_is_refused(tmp_path, version, point_format, offset, fmt, declared):
    """laspy reads only the points the header declares: the other 50 or 100 were dropped."""
    path = _las(tmp_path / "a.las", version, point_format)
    _patch(path, offset, fmt, declared)
    with pytest.raises(CloudFileError, match=f"declares {declared} points but the point data holds 100 records"):
        read_cloud(path)


def _legacy_only(path, count: int):
    """A copy of the LAS 1.4 file ``path`` whose 64-bit point count (byte 247) is 0 and whose
    legacy count (byte 107) is ``count``, as some older tools write point formats 0-5."""
    out = path.with_name("legacy_" + path.name)
    out.write_bytes(path.read_bytes())
    _patch(out, 247, "<Q", 0)
    _patch(out, 107, "<I", count)
    return out


@pytest.mark.parametrize("ext", ["las", "laz"])
@pytest.mark.parametrize("point_format", [1, 3])
def test_las14_with_only_the_legacy_count_reads_its_points(tmp_path, point_format, ext):
    """laspy reads the 64-bit count only: such a file read as empty. It is read with the
    legacy count (as LAStools and PDAL do) by every reader, and the file is left unchanged."""
    import core.tiled
    from core.io import describe
    from core.io.las_sample import sample_las
    from core.io.las_stream import iter_las

    if ext == "laz":
        pytest.importorskip("lazrs")
    good = _las(tmp_path / f"a.{ext}", "1.4", point_format, n=400)
    path = _legacy_only(good, 400)
    before, want = path.read_bytes(), read_cloud(good)
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, want.points)
    assert sorted(cloud.fields) == sorted(want.fields)
    assert describe(path)["n_points"] == 400
    np.testing.assert_array_equal(np.concatenate([p for _, p, _ in iter_las(path, chunk=150)]), want.points)
    assert len(sample_las(path, budget=1000).points) == 400
    res = core.tiled.estimate_tiled(path, tmp_path / "out.laz", k=15, tile_points=150, workers=0)
    assert res.n_points == 400 and res.n_tiles > 1
    out = read_cloud(tmp_path / "out.laz")
    np.testing.assert_allclose(out.points, want.points)
    assert np.isfinite(out.fields["mean"]).any()
    assert path.read_bytes() == before


@pytest.mark.parametrize("ext", ["las", "laz"])
def test_las14_with_only_the_legacy_count_in_the_cli(tmp_path, capsys, ext):
    """`darboux-cli info`, and an estimate whole into LAS/LAZ (k auto: the input read by laspy)."""
    import json

    from core import cli

    if ext == "laz":
        pytest.importorskip("lazrs")
    path = _legacy_only(_las(tmp_path / f"a.{ext}", "1.4", 1, n=300), 300)
    assert cli.main(["info", "--json", str(path)]) == 0
    assert json.loads(capsys.readouterr().out)[0]["n_points"] == 300
    assert cli.main(["estimate", str(path), "-o", str(tmp_path / "out.laz"), "--k", "auto", "-q"]) == 0
    out = read_cloud(tmp_path / "out.laz")
    np.testing.assert_allclose(out.points, read_cloud(path).points)
    assert "intensity" in out.fields and "mean" in out.fields


@pytest.mark.parametrize("legacy, match", [(50, "declares 50 points but the point data holds 100 records"),
                                           (150, r"truncated: the header declares 150 points")])
def test_las14_legacy_count_unlike_the_records_is_refused(tmp_path, legacy, match):
    """The legacy count read in place of a 0 is checked against the records as any count."""
    path = _legacy_only(_las(tmp_path / "a.las", "1.4", 1), legacy)
    with pytest.raises(CloudFileError, match=match):
        read_cloud(path)


def test_overlaid_file_reads_the_overlay_in_any_pieces(tmp_path):
    from core.io.las_open import OverlaidFile

    path = tmp_path / "a.bin"
    path.write_bytes(bytes(range(100)))
    want = bytes(range(10)) + b"abcd" + bytes(range(14, 100))
    with OverlaidFile(path, 10, b"abcd") as f:
        assert f.read() == want
        for start in range(0, 20):
            f.seek(start)
            got = b"".join(iter(lambda: f.read(3), b""))
            assert got == want[start:]
    assert path.read_bytes() == bytes(range(100))


def test_las14_with_extended_records_after_the_points_reads(tmp_path):
    laspy = pytest.importorskip("laspy")
    path = _las(tmp_path / "a.las", "1.4", 6)
    las = laspy.read(path)
    from laspy.vlrs.vlrlist import VLRList

    las.evlrs = VLRList([laspy.VLR(user_id="test", record_id=1, description="d", record_data=b"x" * 500)])
    las.write(path)
    assert len(read_cloud(path)) == 100


# ------------------------------------------------------------------ STL, OFF, PLY


def _stl(declared: int, n: int, head: bytes = b"binary") -> bytes:
    record = np.zeros(n, dtype=[("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
    record["vertices"] = np.random.default_rng(3).random((n, 3, 3))
    return head.ljust(80, b" ") + struct.pack("<I", declared) + record.tobytes()


@pytest.mark.parametrize("head", [b"binary", b"solid part"])
@pytest.mark.parametrize("declared", [0, 4])
def test_binary_stl_count_below_its_triangles_is_refused(tmp_path, head, declared):
    """The triangles after the declared count were dropped without a word."""
    path = tmp_path / "a.stl"
    path.write_bytes(_stl(declared, 10, head))
    with pytest.raises(CloudFileError, match=f"declares {declared} triangles .* room for 10"):
        read_cloud(path)


def test_binary_stl_with_a_padding_newline_reads(tmp_path):
    path = tmp_path / "a.stl"
    path.write_bytes(_stl(10, 10) + b"\n")
    assert len(read_cloud(path)) == 30


@pytest.mark.parametrize("text", ["OFF\n4 0 0\n" + ROWS + "5 5 5\n", "OFF\n3 1 0\n0 1 2\n1 0 0\n0 1 0\n1.5 1 1\n3 0 1 2\n"])
def test_off_vertex_lines_beyond_the_count_are_refused(tmp_path, text):
    path = _write(tmp_path / "a.off", text)
    with pytest.raises(CloudFileError, match="the line after the vertices, .* is not a face"):
        read_cloud(path)


@pytest.mark.parametrize("text", ["OFF\n4 1 0\n" + ROWS + "3 0 1 2 255 0 0\n", "OFF\n4 0 0\n" + ROWS + "\n# end\n",
                                  "OFF\n4 2 0\n" + ROWS + "3 0 1 2\n"])
def test_off_with_faces_or_trailing_comments_reads(tmp_path, text):
    assert len(read_cloud(_write(tmp_path / "a.off", text))) == 4


_PLY = "ply\nformat ascii 1.0\n{}element vertex 4\n{}property float x\nproperty float y\nproperty float z\nend_header\n"


def test_ascii_ply_without_a_final_newline_reads(tmp_path):
    """Single-digit rows whose last line lacks its newline were refused as truncated."""
    path = _write(tmp_path / "a.ply", _PLY.format("", "") + ROWS.rstrip("\n"))
    assert read_cloud(path).points[-1].tolist() == [1.0, 1.0, 1.0]


def test_ply_obj_info_inside_an_element_reads(tmp_path):
    path = _write(tmp_path / "a.ply", _PLY.format("obj_info a\n", "obj_info b c\n") + ROWS)
    assert len(read_cloud(path)) == 4


# ------------------------------------------------------------------ what the file really is


def test_gzip_file_with_a_point_cloud_extension_says_so(tmp_path):
    path = tmp_path / "a.xyz"
    path.write_bytes(gzip.compress(ROWS.encode()))
    with pytest.raises(CloudFileError, match="gzip-compressed file: decompress it first"):
        read_cloud(path)


def test_compressed_extension_says_so(tmp_path):
    path = tmp_path / "a.xyz.gz"
    path.write_bytes(gzip.compress(ROWS.encode()))
    with pytest.raises(CloudFileError, match=r"a compressed file \(\.gz\); decompress it first"):
        read_cloud(path)


@pytest.mark.parametrize("ext", ["xyz", "las", "obj", "pcd", "off"])
def test_file_whose_extension_lies_names_its_content(tmp_path, ext):
    source = write_cloud(tmp_path / "a.ply", np.random.default_rng(4).random((10, 3)))
    path = tmp_path / f"b.{ext}"
    path.write_bytes(source.read_bytes())
    with pytest.raises(CloudFileError, match=rf"its content is a \.ply file, not \.{ext}: rename it to \.ply"):
        read_cloud(path)


def test_pcd_fields_in_upper_case_are_read(tmp_path):
    """FIELDS X Y Z NORMAL_X ... (upper case) was refused: "no x, y, z fields (found: X, Y, Z)"."""
    path = tmp_path / "upper.pcd"
    path.write_text("VERSION .7\nFIELDS X Y Z NORMAL_X NORMAL_Y NORMAL_Z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
                    "COUNT 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                    "1 2 3 0 0 1\n4 5 6 0 1 0\n")
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, [[1, 2, 3], [4, 5, 6]])
    np.testing.assert_array_equal(cloud.normals, [[0, 0, 1], [0, 1, 0]])
