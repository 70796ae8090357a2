"""Hostile files, fifth round: a seeded fuzz of every format (``io_fuzz_cases``: cut short,
header counts too big, too small, negative or huge, binary header words overwritten, bytes
flipped), read in a child process with limited memory; and what that round found: a file of
another format read as delimited text (an ASCII PLY's normals taken as its points, an OFF's
counts line as a point), a text line of millions of columns (a gigabyte, minutes), a PTX
count beyond int64 (a TypeError), numpy's warnings leaking out of the readers, messages that
quoted a whole names line, and paths that are empty or links that cannot be followed."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import io_fuzz_cases as F
from core.io import CloudFileError, read_cloud
from io_testutils import refused


def test_seeded_mutations_of_every_format_are_read_or_refused_by_name(tmp_path, helpers):
    """Each mutation is read, or refused with a CloudFileError (a ValueError) naming the file;
    any other exception, a crash or an allocation beyond the child's memory ends the child."""
    rng = np.random.default_rng(2026)
    paths = []
    for name, (ext, data) in F.seeds(tmp_path, n=16, seed=1).items():
        paths.append(tmp_path / f"{name}.{ext}")
        paths[-1].write_bytes(data)
        for i, (_, mutated) in enumerate(F.mutations(data, rng, count=8)):
            paths.append(tmp_path / f"{name}_{i}.{ext}")
            paths[-1].write_bytes(mutated)
    answers = helpers.read_in_child(paths)
    for path in paths:
        answer = answers[str(path)]
        assert isinstance(answer, list) or path.name in answer, (path, answer)
    assert all(isinstance(answers[str(tmp_path / f"{name}.{ext}")], list)
               for name, (ext, _) in F.seeds(tmp_path, n=16, seed=1).items())  # every seed reads


def _ply_normals_first(points):
    head = "ply\nformat ascii 1.0\nelement vertex {}\n".format(len(points)) + "".join(
        f"property float {name}\n" for name in ("nx", "ny", "nz", "x", "y", "z")) + "end_header\n"
    return (head + "".join(f"0 0 1 {x!r} {y!r} {z!r}\n" for x, y, z in points.tolist())).encode()


@pytest.mark.parametrize("ext", ["xyz", "csv", "txt", "pts"])
@pytest.mark.parametrize("kind", ["ply", "off"])
def test_another_formats_file_named_as_text_is_refused_not_misread(tmp_path, ext, kind):
    """The delimited text reader took an ASCII PLY's header for a title and read its rows
    (normals listed first became the points), and an OFF's counts line "10 0 0" as a point."""
    points = F.patch(10, seed=4)[0]
    path = tmp_path / f"cloud.{ext}"
    path.write_bytes(_ply_normals_first(points) if kind == "ply" else F.off(points, "OFF", faces=0))
    refused(path, f"its content is a .{kind} file, not .{ext}: rename it to .{kind}")


@pytest.mark.parametrize("value", [b"18446744073709551617", b"-99999999999999999999", b"1" + b"0" * 400])
def test_ptx_count_beyond_int64_is_refused_exactly(tmp_path, value):
    """An integer beyond int64 made an object array, and np.isfinite raised a TypeError."""
    path = tmp_path / "big.ptx"
    path.write_bytes(value + F.ptx(F.patch(10)[0])[1:])
    refused(path, f"scan 0 declares {value.decode()[:40]}")


@pytest.mark.parametrize("sep", [" ", ",", ";", "\t"])
def test_text_line_of_too_many_columns_is_refused_before_splitting(tmp_path, sep):
    """3 million columns on a 9 MB line took 1 GB and minutes, as that many per-point fields."""
    path = tmp_path / "wide.csv"
    path.write_text(sep.join(["0.5"] * 20_003) + "\n" + "1 2 3\n".replace(" ", sep))
    refused(path, "line 1 has more than 10,000 columns")
    path.write_text("x y z\n1 2 3\n" + " ".join(["0.5"] * 20_003) + "\n")
    refused(path, "line 3 has more than 10,000 columns")


def test_a_message_quoting_a_long_names_line_is_cut_in_its_middle(tmp_path):
    path = tmp_path / "names.csv"
    path.write_text("a,x,y,z," + ",".join(f"n{i}" for i in range(9000)) + "\n1,2,3\n4,5,6\n")
    with pytest.raises(CloudFileError) as info:
        read_cloud(path)
    message = str(info.value)
    assert len(message) < 1100 and "characters cut" in message, message
    assert message.startswith(f"{path}: line 1 names 9004 columns") and message.endswith("or none (x y z first)")


def _nan_bits_stl(tmp_path):
    data = bytearray(F.stl(F.patch(12)[0]))
    data[84 + 12 : 84 + 16] = b"\x01\x00\x80\x7f"  # a signalling NaN as the first corner's x
    path = tmp_path / "nan.stl"
    path.write_bytes(bytes(data))
    return path


def _empty_list_ply(tmp_path):
    path = tmp_path / "lists.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     b"property list uchar float w\nend_header\n0 0 0 2 1 1\n1 0 0 0\n0 1 0 1 5\n")
    return path


@pytest.mark.parametrize("make, n", [(_nan_bits_stl, 11), (_empty_list_ply, 3)])
def test_readers_leak_no_numpy_warning(tmp_path, make, n):
    """A float32 NaN cast ("invalid value encountered in cast") and plyfile's loadtxt of an
    empty list ("input contained no data") reached the caller as numpy's warnings."""
    path = make(tmp_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cloud = read_cloud(path, drop_nonfinite=True)
    assert len(cloud) == n
    assert all("dropped 1 of 12 points" in str(w.message) for w in caught), [str(w.message) for w in caught]


def test_links_that_cannot_be_followed_are_named(tmp_path):
    (tmp_path / "dangling.xyz").symlink_to(tmp_path / "gone.xyz")
    (tmp_path / "loop.xyz").symlink_to(tmp_path / "loop.xyz")
    refused(tmp_path / "dangling.xyz", "is a symbolic link to", "gone.xyz", "target is missing")
    refused(tmp_path / "loop.xyz", "is a symbolic link to", "loop")


@pytest.mark.parametrize("path, says", [("", "path is empty"), ("a\0b.xyz", "holds a NUL byte")])
def test_empty_or_nul_path_is_refused_by_name(path, says):
    """An empty path was the current folder ("is a directory"), a NUL "no such file"."""
    with pytest.raises(ValueError, match=says):
        read_cloud(path)


@pytest.mark.parametrize("at, value, says", [
    (104, 99, "its header's point format 35 is none of the formats LAS defines (0-10)"),  # laspy said "35"
    (24, 9, "its header says LAS version 9.2; versions 1.0 to 1.4 are read"),  # "unpack requires a buffer"
    (25, 9, "its header says LAS version 1.9; versions 1.0 to 1.4 are read"),
])
def test_las_header_point_format_or_version_beyond_the_standard_named(tmp_path, at, value, says):
    pytest.importorskip("laspy")
    from core.io import las_stream

    data = bytearray(F.las(F.patch(20)[0], tmp_path))
    data[at] = value
    path = tmp_path / "odd.las"
    path.write_bytes(bytes(data))
    refused(path, says)
    with pytest.raises(CloudFileError, match=says.replace("(", r"\(").replace(")", r"\)")):
        las_stream.open_las(path)  # the tiled and sampled readers' header


@pytest.mark.parametrize("mode", ["ascii", "binary"])
def test_pcd_ascii_row_of_other_width_names_where_the_width_comes_from(tmp_path, mode):
    """The first data line was compared with itself: "line 12: found 2 columns but line 12 has 4"."""
    path = tmp_path / "twice.pcd"
    path.write_bytes(F.pcd(F.patch(20)[0], mode).replace(b"DATA", b"DATA ascii\nDATA", 1))
    refused(path, "line 12: found 2 columns but the header's FIELDS and COUNT declare 4")


@pytest.mark.parametrize("out, fmt, data", [
    ("o.csv", "xyz", b"1 2 3\nx y\n"), ("o.csv", "ply", b"garbage"), ("o.las", "xyz", b"1 2 3\n4 5\n")])
def test_cli_refusal_of_standard_input_names_stdin(tmp_path, monkeypatch, capsys, out, fmt, data):
    """The message named the temporary copy (/tmp/darboux-stdin-x1y2/stdin.xyz: ...), a file the user never made."""
    import io
    import sys

    from core.cli import main

    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))
    assert main(["estimate", "-", "-o", str(tmp_path / out), "--input-format", fmt, "-q"]) == 2
    said = capsys.readouterr().err
    assert said.startswith("darboux-cli: error: stdin: ") and "darboux-stdin-" not in said, said


def test_ascii_stl_cut_at_any_line_is_read_whole_or_refused(tmp_path):
    """Cut inside a facet (after its vertices, or before them), an ASCII STL read the whole
    triangles before the cut as the file; only a cut after a facet's ``endfacet`` (a missing
    ``endsolid``) is read, with the facets it holds."""
    data = F.stl(F.patch(12, seed=2)[0], binary=False)
    ends = [i + 1 for i, byte in enumerate(data) if byte == ord("\n")]
    path = tmp_path / "cut.stl"
    for end in ends[:-1]:
        path.write_bytes(data[:end])
        last = data[:end].rstrip().rsplit(b"\n", 1)[-1].split()[0]
        if last == b"endfacet":
            assert len(read_cloud(path)) == 3 * data[:end].count(b"endfacet")
        else:
            with pytest.raises(CloudFileError, match="ends inside a facet|whole triangles|contains no points"):
                read_cloud(path)


def _many_arrays(tmp_path, kind, m):
    pts = F.patch(20)[0]
    path = tmp_path / f"many.{'vtp' if kind == 'vtp' else 'vtk'}"
    if kind == "vtp":
        from core.io import write_cloud

        return write_cloud(path, pts, fields={f"f{i}": np.zeros(20) for i in range(m)})
    binary = kind == "binary"
    values = np.zeros(20, ">f4").tobytes() + b"\n" if binary else b"0 " * 20 + b"\n"
    path.write_bytes(F.vtk_legacy(pts, binary) + b"POINT_DATA 20\n" + b"".join(
        f"SCALARS s{i} float 1\nLOOKUP_TABLE default\n".encode() + values for i in range(m)))
    return path


@pytest.mark.parametrize("kind", ["ascii", "binary", "vtp"])
def test_vtk_file_of_more_arrays_than_a_cloud_has_is_refused_before_vtk_reads_it(tmp_path, kind):
    """VTK adds each array after a search of the names before it: 40,000 arrays in a 2.4 MB
    legacy file took 19 s, 20,000 in a .vtp 7 s."""
    pytest.importorskip("vtkmodules")
    path = _many_arrays(tmp_path, kind, 10_050)
    refused(path, "data arrays", "read with at most 10,000")
