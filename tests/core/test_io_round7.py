"""Hostile files, round seven (2026-12-08): a binary STL whose last triangle took inserted bytes,
leaving only its zero attribute bytes after it (read shifted: corners of 1e38 or 1e-39, read as
padding), ..."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from core.io import read_cloud
from io_testutils import refused

_RECORD = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


def _mesh(seed: int, normals: str) -> bytes:
    """A binary STL of a triangulated sphere cap or height field at a random scale and place, its
    stored normals unit ones from the corners (most writers) or zeros."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.linspace(0.1, 3.0, 7), np.linspace(0, 6.0, 9), indexing="ij")
    if seed % 2:
        grid = np.stack([np.sin(u) * np.cos(v), np.sin(u) * np.sin(v), np.cos(u)], -1)
    else:
        grid = np.stack([u, v, 0.2 * np.sin(u) * v], -1)
    grid = grid * 10.0 ** rng.uniform(-3, 4) + rng.normal(size=3) * 10.0 ** rng.uniform(-2, 5)
    quads = [(grid[i, j], grid[i + 1, j], grid[i, j + 1], grid[i + 1, j + 1]) for i in range(6) for j in range(8)]
    corners = np.array([t for a, b, c, d in quads for t in ((a, b, c), (b, d, c))], np.float32)
    rng.shuffle(corners)
    records = np.zeros(len(corners), _RECORD)
    records["vertices"] = corners
    if normals == "unit":
        cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]).astype(np.float64)
        records["normal"] = cross / np.linalg.norm(cross, axis=1, keepdims=True)
    return b"round7".ljust(80) + len(records).to_bytes(4, "little") + records.tobytes()


@pytest.mark.parametrize("normals", ["unit", "zero"])
@pytest.mark.parametrize("seed", range(4))
def test_bytes_inserted_into_the_last_stl_triangle_are_refused(tmp_path, seed, normals):
    """1 or 2 bytes inserted at one of its corners leave its attribute's zeros after it (its stored normal
    intact: at the normal, the existing check of stored normals refuses unit ones)."""
    data = _mesh(seed, normals)
    last = len(data) - 50
    rng = np.random.default_rng(seed)
    for k in (1, 2):
        for at in (12, 24, 36):
            path = tmp_path / f"s{seed}_{k}_{at}.stl"
            path.write_bytes(data[: last + at] + rng.integers(1, 256, k, dtype=np.uint8).tobytes() + data[last + at :])
            refused(path, f"but the file has {len(data) + k} bytes, {k} more, padding-like, but the last triangle has",
                    "bytes were inserted into it")


@pytest.mark.parametrize("normals", ["unit", "zero"])
@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("padding", [b"\0", b"\r\n", bytes(49)])
def test_stl_padding_after_sound_triangles_still_reads(tmp_path, seed, normals, padding):
    data = _mesh(seed, normals)
    path = tmp_path / "padded.stl"
    path.write_bytes(data + padding)
    assert len(read_cloud(path).points) == 7 * 9


@pytest.mark.filterwarnings("ignore:invalid value encountered in dot:RuntimeWarning")  # pye57's pose of inf
@pytest.mark.parametrize("value", [np.nan, np.inf, 1e308])
def test_a_failed_e57_seed_leaves_no_exception_for_the_destructor(tmp_path, monkeypatch, value):
    """pye57's E57.__del__ closed a file whose close had failed (libE57 cannot write the bounds
    of NaN, inf or 1e308): an IndexError "ignored in E57.__del__", noise in every fuzz run."""
    pytest.importorskip("pye57")
    import gc
    import sys

    import io_fuzz_cases as F

    ignored = []
    monkeypatch.setattr(sys, "unraisablehook", lambda info: ignored.append(info.exc_value))
    points = F.patch(16, 1)[0]
    points[3] = value
    with pytest.raises(IndexError):
        F.e57(points, tmp_path)
    gc.collect()
    assert not ignored, ignored


def _rows(points, fmt="%.6f", extra=""):
    return "".join(" ".join(fmt % float(v) for v in p) + extra + "\n" for p in points)


def _text_files(points, fmt):
    """name: (extension, text) of every text format but delimited columns, ``fmt`` numbers, ending in points."""
    n, rows = len(points), _rows(points, fmt)
    grid = _rows(points, fmt, " 0.5")
    return {
        "ply": ("ply", f"ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n"
                       f"property float z\nend_header\n{rows}"),
        "pcd": ("pcd", f"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
                       f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA ascii\n{rows}"),
        "obj": ("obj", "# cloud\n" + "".join("v " + line for line in rows.splitlines(True))),
        "off": ("off", f"OFF\n{n} 0 0\n{rows}"),
        "ptx": ("ptx", f"1\n{n}\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n{grid}"),
        "vtk": ("vtk", f"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS {n} float\n{rows}"),
    }


@pytest.mark.parametrize("fmt", ["%.6f", "%.4e", "%.3f"])
@pytest.mark.parametrize("name", ["ply", "pcd", "obj", "off", "ptx", "vtk"])
def test_a_text_file_cut_in_its_last_number_warns_in_every_text_format(tmp_path, name, fmt):
    rng = np.random.default_rng(len(name) + len(fmt))
    points = rng.normal(scale=10.0 ** rng.integers(-2, 4), size=(int(rng.integers(12, 300)), 3))
    ext, text = _text_files(points, fmt)[name]
    if name == "vtk":
        pytest.importorskip("vtkmodules")
    whole = tmp_path / f"whole.{ext}"
    whole.write_text(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_cloud(whole).points) == len(points)
    for cut in (1, 2) if fmt.endswith("f") else (1,):  # decimals (or an exponent's digit) lost, and the newline
        path = tmp_path / f"cut{cut}.{ext}"
        path.write_text(text.rstrip("\n")[:-cut])
        with pytest.warns(UserWarning, match=f"{path.name}: the file ends without a newline, in .* the file looks cut"):
            read_cloud(path)


@pytest.mark.parametrize("name", ["ply", "obj", "off", "vtk"])
def test_shortest_digit_text_files_ending_without_a_newline_read_without_a_word(tmp_path, name):
    """repr numbers vary in their decimals: no evidence of a cut, no warning."""
    if name == "vtk":
        pytest.importorskip("vtkmodules")
    points = np.random.default_rng(1).normal(size=(40, 3))
    ext, text = _text_files(points, "%r")[name]
    path = tmp_path / f"repr.{ext}"
    path.write_text(text.rstrip("\n"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(read_cloud(path).points) == 40


_HEAD = "# vtk DataFile Version 3.0\nt\n{kind}\nDATASET POLYDATA\nPOINTS 2 float\n"
_SCALARS = "POINT_DATA 2\nSCALARS s float 1\nLOOKUP_TABLE default\n"


def _legacy(kind: str, gap: str, where: str) -> bytes:
    """A legacy file whose ``gap`` follows the points' data (then the scalars) or the scalars' (the file's end)."""
    values = (b"0 0 0 1 1 1" if kind == "ASCII" else np.arange(6, dtype=">f4").tobytes())
    scalars = (b"5 6" if kind == "ASCII" else np.array([5, 6], ">f4").tobytes())
    head = _HEAD.format(kind=kind).encode()
    if where == "points":
        return head + values + gap.encode() + b"\n" + _SCALARS.encode() + scalars + b"\n"
    return head + values + b"\n" + _SCALARS.encode() + scalars + gap.encode()


def test_a_run_of_spaces_where_vtk_reads_a_keyword_is_refused_not_a_hang(tmp_path, helpers):
    """VTK 9.7's legacy reader never returned from 256 or more spaces (and carriage returns)
    between an array's data and the next keyword or the file's end (read in one child process,
    which a hang would keep past read_in_child's limit)."""
    pytest.importorskip("vtkmodules")
    paths = []
    for kind in ("ASCII", "BINARY"):
        for where in ("points", "end"):
            for i, gap in enumerate([" " * 256, " " * 5000, " \r" * 200, "\n" + " " * 300, "\r" * 300]):
                paths.append(tmp_path / f"{kind}_{where}_{i}.vtk")
                paths[-1].write_bytes(_legacy(kind, gap, where))
    answers = helpers.read_in_child(paths)
    for path in paths:
        for part in (path.name, "spaces (or carriage returns)", "VTK's reader never returns", "allowed: fewer than 256"):
            assert part in answers[str(path)], answers[str(path)]


@pytest.mark.parametrize("kind", ["ASCII", "BINARY"])
@pytest.mark.parametrize("gap", [" " * 255, "\t" * 5000, " \n" * 300, "\v" * 300, " " * 200 + "\n" + " " * 200])
def test_other_white_space_after_vtk_data_still_reads(tmp_path, kind, gap):
    pytest.importorskip("vtkmodules")
    for where in ("points", "end"):
        path = tmp_path / f"{where}.vtk"
        path.write_bytes(_legacy(kind, gap, where))
        cloud = read_cloud(path)
        assert cloud.points.ravel().tolist() == [0, 0, 0, 1, 1, 1] if kind == "ASCII" else list(range(6))
        assert cloud.fields["s"].tolist() == [5, 6]


_PIECE = ('<Piece NumberOfPoints="1"><Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">'
          "1 2 3</DataArray></Points></Piece>")


@pytest.mark.parametrize("depth, part", [(1001, "nests elements more than 1000 deep"),
                                         (200_000, "nests elements more than 1000 deep")])
def test_deeply_nested_vtp_xml_is_refused_before_vtk(tmp_path, helpers, depth, part):
    """200,000 nested elements overflowed VTK's parser's stack: a segmentation fault."""
    pytest.importorskip("vtkmodules")
    path = tmp_path / "deep.vtp"
    path.write_text(f'<?xml version="1.0"?><VTKFile type="PolyData"><PolyData>{_PIECE}'
                    + "<a>" * depth + "</a>" * depth + "</PolyData></VTKFile>")
    answer = helpers.read_in_child([path])[str(path)]
    assert isinstance(answer, str) and path.name in answer and part in answer, answer


def test_an_element_of_many_attributes_is_refused_before_vtk(tmp_path):
    """VTK reads n attributes of an element in n**2 time: 300,000 took minutes."""
    pytest.importorskip("vtkmodules")
    path = tmp_path / "attributes.vtp"
    path.write_text('<?xml version="1.0"?><VTKFile type="PolyData" ' + " ".join(f'a{i}="1"' for i in range(1001))
                    + f"><PolyData>{_PIECE}</PolyData></VTKFile>")
    refused(path, "its XML gives <VTKFile> (at byte 21) 1002 attributes; allowed: at most 1000")


def test_vtp_nesting_and_attributes_within_the_limits_read(tmp_path):
    pytest.importorskip("vtkmodules")
    path = tmp_path / "ok.vtp"
    path.write_text('<?xml version="1.0"?><VTKFile type="PolyData" ' + " ".join(f'a{i}="1"' for i in range(900))
                    + f"><PolyData>{_PIECE}" + "<a>" * 990 + "</a>" * 990 + "</PolyData></VTKFile>")
    assert read_cloud(path).points.tolist() == [[1, 2, 3]]
