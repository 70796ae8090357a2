"""Hostile files, sixth round: the new mutation classes of ``io_fuzz_more`` over every format
(bytes inserted or deleted mid-record, header lines and fields swapped or duplicated, huge
counts over tiny bodies, UTF-16/32 and BOM text, CR LF and CR line ends, gzip'd files under
their own extension, NaN, inf and 1e308 coordinates), and what the round found: bytes
inserted into a LAS file's or a binary STL's point data read as shifted garbage, a .vtp cut
after its points read as whole, a text cloud whose first line is "VERSION 2" refused as a
PCD, ``-o ""`` reported as ".: no file extension", and a text file cut inside its last number."""

from __future__ import annotations

import os
import shutil
import struct
import subprocess
import sys
import warnings

import numpy as np
import pytest

import io_fuzz_cases as F
import io_fuzz_more as M
from core.io import CloudFileError, read_cloud, write_cloud
from io_testutils import refused


def _same(a, b) -> bool:
    return isinstance(a, list) and isinstance(b, list) and np.allclose(np.array(a, float), np.array(b, float),
                                                                        equal_nan=True)


def test_new_mutation_classes_of_every_format_are_read_or_refused_by_name(tmp_path, helpers):
    """Each mutation is read, or refused by a CloudFileError naming the file (in a child with
    limited memory); a gzip'd file is named as such; bytes spliced into the fixed-size records
    of a binary PLY, PCD, STL or LAS, or a .vtp's appended data, are refused unless the points
    read are the seed's."""
    rng = np.random.default_rng(2027)
    cases = []  # (path, class, seed name)
    for name, (ext, data) in F.seeds(tmp_path, n=16, seed=2).items():
        cases.append((tmp_path / f"{name}.{ext}", "seed", name))
        cases[-1][0].write_bytes(data)
        for i, (kind, _, mutated) in enumerate(M.mutations(name, data, rng, count=6)):
            cases.append((tmp_path / f"{name}_{kind}{i}.{ext}", kind, name))
            cases[-1][0].write_bytes(mutated)
    for (label, name), (ext, data) in M.extreme_seeds(tmp_path).items():
        cases.append((tmp_path / f"{name}_{label}.{ext}", "extreme", name))
        cases[-1][0].write_bytes(data)
    answers = helpers.read_in_child([path for path, _, _ in cases])
    seeds = {name: answers[str(path)] for path, kind, name in cases if kind == "seed"}
    for path, kind, name in cases:
        answer = answers[str(path)]
        assert isinstance(answer, list) or path.name in answer, (path, answer)
        if kind == "gzip":
            assert "gzip-compressed" in answer, (path, answer)
        if kind == "splice" and name in M.SHIFT_CHECKED:
            assert isinstance(answer, str) or _same(answer, seeds[name]), (path, "read shifted records")
        if kind == "extreme":  # read_in_child drops non-finite rows: 1e308 beyond float32 is inf too
            assert isinstance(answer, str) or len(answer) in (15, 16), (path, answer)
    assert all(isinstance(answer, list) for answer in seeds.values()), seeds


def _las_with(tmp_path, extra: bytes, at=None):
    pytest.importorskip("laspy")
    data = F.las(F.patch(20)[0], tmp_path)
    at = len(data) if at is None else struct.unpack_from("<I", data, 96)[0] + at
    path = tmp_path / "spliced.las"
    path.write_bytes(data[:at] + extra + data[at:])
    return path


@pytest.mark.parametrize("k", [1, 3, 7, 33])
def test_las_bytes_inserted_into_the_point_data_are_refused(tmp_path, k):
    """The records after the inserted bytes read shifted (1e6 for points within 1); the data's
    length was the header's records and part of one more, which was accepted."""
    path = _las_with(tmp_path, b"\xab" * k, at=100)
    refused(path, f"the point data is {k} byte{'s' * (k > 1)} longer than the header's 20 records of 34 bytes", "and point 3 (",
            "lies outside the header's bounds", "bytes were inserted into")


@pytest.mark.parametrize("k", [1, 5, 33])
def test_las_bytes_after_the_last_record_are_ignored_with_a_warning(tmp_path, k):
    """Trailing bytes after whole records (PDAL reads them without a word) leave every point
    inside the header's bounds: read, and said."""
    path = _las_with(tmp_path, b"\n" * k)
    with pytest.warns(UserWarning, match=f"is {k} bytes? longer than .* those bytes .* are ignored"):
        cloud = read_cloud(path)
    np.testing.assert_allclose(cloud.points, F.patch(20)[0], atol=1e-3)


def _stl_with(tmp_path, extra: bytes, at=None, zero_normals=False):
    data = bytearray(F.stl(F.patch(12, seed=3)[0]))
    if zero_normals:
        for i in range(4):
            data[84 + 50 * i : 84 + 50 * i + 12] = bytes(12)
    at = len(data) if at is None else 84 + at
    path = tmp_path / "spliced.stl"
    path.write_bytes(bytes(data[:at]) + extra + bytes(data[at:]))
    return path


@pytest.mark.parametrize("k", [1, 2, 3, 4, 7, 49])
@pytest.mark.parametrize("at", [13, 70, 120])
def test_binary_stl_bytes_inserted_into_the_triangles_are_refused(tmp_path, k, at):
    """With fewer than 50 bytes more than 84 + 50 n, the triangles after the insertion read
    shifted (9.7e37); the stored normals (unit vectors) show where."""
    path = _stl_with(tmp_path, bytes(range(1, k + 1)), at=at)
    refused(path, f"the binary STL header declares 4 triangles (284 bytes) but the file has {284 + k} bytes",
            f"and triangle {at // 50 + 1}'s normal", "bytes were inserted into the data before it")


def test_binary_stl_bytes_after_its_triangles(tmp_path):
    """Junk after the last triangle is refused (it was ignored: the shifted end of an
    insertion looks so); a padding newline or NULs still read without a word."""
    refused(_stl_with(tmp_path, b"junk!"), "5 more, which are not padding")
    refused(_stl_with(tmp_path, b"junk!", zero_normals=True), "5 more, which are not padding")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_cloud(_stl_with(tmp_path, b"\r\n", zero_normals=True))) == 12
        assert len(read_cloud(_stl_with(tmp_path, bytes(7)))) == 12


def test_vtp_cut_anywhere_after_its_points_is_refused(tmp_path):
    """VTK reads the points of a .vtp cut in its cells (the copy it reads takes no cells): every
    cut short of the closing </VTKFile> tag is refused."""
    pytest.importorskip("vtkmodules")
    data = F.vtp(F.patch(20)[0], tmp_path)
    path = tmp_path / "cut.vtp"
    for end in range(data.index(b"</AppendedData>") - 400, len(data) - 2, 23):
        path.write_bytes(data[:end])
        with pytest.raises(CloudFileError, match="cut.vtp: (truncated|.* past the end of the data)"):
            read_cloud(path)
    path.write_bytes(data.rstrip())
    assert len(read_cloud(path)) == 20


@pytest.mark.parametrize("first", ["VERSION 2", "VERSION 0.7 of the survey", "# export\nVERSION 3"])
def test_text_cloud_beginning_with_a_version_line_reads(tmp_path, first):
    """A first line "VERSION 2" was taken for a PCD header ("its content is a .pcd file")."""
    points = F.patch(12)[0]
    path = tmp_path / "survey.xyz"
    path.write_text(first + "\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in points.tolist()))
    np.testing.assert_array_equal(read_cloud(path).points, points)
    path.write_bytes(F.pcd(points))  # a PCD's header (VERSION, then FIELDS) is still named
    refused(path, "its content is a .pcd file, not .xyz")


def test_empty_output_name_is_named(tmp_path, capsys):
    from core.cli import main

    path = tmp_path / "in.xyz"
    path.write_bytes(F.text(F.patch(30)[0]))
    assert main(["estimate", str(path), "-o", "", "-q"]) == 2
    assert "error: -o is empty; give the output file's name" in capsys.readouterr().err


@pytest.mark.parametrize("style, sep", [("%.6f", " "), ("%.3f", ";"), ("%.4e", ",")])
@pytest.mark.parametrize("cut", [1, 4])
def test_text_cut_inside_its_last_number_is_said(tmp_path, style, sep, cut):
    """A last value shorter than the column's fixed format, on a last line without a newline,
    is a cut: read with a warning. Shortest-digit numbers (repr) give no such evidence."""
    rows = np.random.default_rng(cut).uniform(-10, 10, (40, 3))
    text = "".join(sep.join(style % v for v in row) + "\n" for row in rows)
    path = tmp_path / "cut.csv"
    path.write_text(text[: -1 - cut])
    with pytest.warns(UserWarning, match="ends without a newline, in .* the file looks cut short"):
        assert len(read_cloud(path)) == 40
    path.write_text("".join(sep.join(repr(v) for v in row) + "\n" for row in rows.tolist())[: -1 - cut])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_cloud(path)) == 40


_CHILD = "import sys\nfrom core.io import read_cloud, write_cloud\nimport numpy as np\n" \
         "for p in sys.argv[1:]:\n    try:\n        read_cloud(p) if p[-4:] != '.out' else write_cloud(p[:-4], np.ones((9, 3)))\n" \
         "        print('ok')\n    except ValueError as e:\n        print(str(e))\n"


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX permissions")
def test_unreadable_inputs_and_unwritable_folders_are_named(tmp_path):
    """A file without read permission (every format) and a folder without write permission:
    refused naming the file, in a child without root's right to ignore permissions."""
    prefix = []
    if os.geteuid() == 0:
        if not shutil.which("setpriv"):
            pytest.skip("root without setpriv ignores permissions")
        prefix = ["setpriv", "--bounding-set", "-dac_override,-dac_read_search"]
    paths = []
    for name, (ext, data) in F.seeds(tmp_path, n=12).items():
        paths.append(tmp_path / f"{name}.{ext}")
        paths[-1].write_bytes(data)
        paths[-1].chmod(0)
    (tmp_path / "ro").mkdir(mode=0o555)
    outs = [tmp_path / "ro" / f"o.{ext}.out" for ext in ("ply", "csv", "vtp")]
    run = subprocess.run(prefix + [sys.executable, "-c", _CHILD, *map(str, paths + outs)], capture_output=True,
                         text=True, cwd=os.getcwd(), env={**os.environ, "PYTHONPATH": os.getcwd()}, timeout=300)
    said = run.stdout.splitlines()
    assert len(said) == len(paths + outs), run.stderr[-2000:]
    for path, line in zip(paths + outs, said):
        assert line.startswith(str(path).removesuffix(".out") + ": cannot be ") and "Permission denied" in line, line


def test_legacy_vtk_cells_cut_at_a_line_end_name_the_cell_left_without_entries(tmp_path):
    """A cut between two cells said "cell 11 declares None point ids"."""
    pytest.importorskip("vtkmodules")
    data = F.vtk_legacy(F.patch(20)[0])
    at = data.index(b"VERTICES 20 40\n") + len(b"VERTICES 20 40\n")
    path = tmp_path / "cells.vtk"
    path.write_bytes(data[: at + sum(len(f"1 {i}\n") for i in range(11))])
    refused(path, "corrupt VERTICES section: cell 11 of 20 has no entries left: 22 of the 40 declared entries follow")


@pytest.mark.parametrize("k", [1, 4, 9])
@pytest.mark.parametrize("where", ["points", "cells"])
def test_vtp_bytes_spliced_into_its_appended_arrays_are_refused(tmp_path, k, where):
    """An array's header keeps its length when bytes are inserted into (or lost from) its data:
    VTK read the points shifted (1e+291), and the arrays after began elsewhere than their
    offsets say. The raw appended arrays must lie end to end."""
    pytest.importorskip("vtkmodules")
    data = F.vtp(F.patch(20)[0], tmp_path)
    start = data.index(b"_", data.index(b"<AppendedData")) + 1
    at = start + (100 if where == "points" else 500)  # the points take 8 + 480 bytes
    path = tmp_path / "spliced.vtp"
    for spliced in (data[:at] + b"\x3f" * k + data[at:], data[:at] + data[at + k :]):
        path.write_bytes(spliced)
        with pytest.raises(CloudFileError, match="spliced.vtp: (its appended data do not hold their arrays end to "
                                                 "end|array '(connectivity|offsets)' declares .* past the end)"):
            read_cloud(path)

