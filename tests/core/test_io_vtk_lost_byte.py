"""A byte lost inside a legacy BINARY VTK array (core/io/vtk_binary.py, check_lost_bytes).

VTK reads the bytes an array declares and then the next keyword, with or without a newline
between them: a byte lost inside an array made VTK take the newline after it as its last
byte, every value after the lost one shifted (normals of 1e304 for unit ones, points of 1e38),
read without a word. Files written without a newline after their data are read on purpose, so
a newline as an array's last byte is refused only where the file's other arrays are followed
by one, as every VTK writer writes them."""

from __future__ import annotations

import numpy as np
import pytest

from core.io import read_cloud

pytest.importorskip("vtkmodules.vtkIOLegacy")

TYPES = {"float": ">f4", "double": ">f8", "int": ">i4", "unsigned_char": ">u1", "short": ">i2"}


def _arrays(rng, n, kind):
    """(header line, data) of each array of a point cloud file: points, normals, a scalar."""
    points = rng.normal(scale=10.0 ** rng.integers(-3, 4), size=(n, 3)) + rng.normal(size=3) * 100
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    values = (rng.random(n) * 200).astype(TYPES[kind])
    return [(b"POINTS %d double\n" % n, points.astype(">f8").tobytes()),
            (b"POINT_DATA %d\nNORMALS Normals float\n" % n, normals.astype(">f4").tobytes()),
            (b"SCALARS s %s 1\nLOOKUP_TABLE default\n" % kind.encode(), values.tobytes())]


def _file(arrays, dataset=b"POLYDATA", tight=False):
    head = b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET " + dataset + b"\n"
    return head + b"".join(line + data + (b"" if tight else b"\n") for line, data in arrays)


def _cases(tmp_path):
    """Files as VTK writes them with 1 to 3 bytes lost at the start, middle or end of each array's data."""
    cases, rng = [], np.random.default_rng(7)
    for seed, kind in enumerate(TYPES):
        dataset = (b"POLYDATA", b"UNSTRUCTURED_GRID")[seed % 2]
        arrays = _arrays(rng, int(rng.integers(5, 60)), kind)
        for which in range(len(arrays)):
            start = len(_file(arrays[:which], dataset)) + len(arrays[which][0])
            size = len(arrays[which][1])
            for lost in (1, 2, 3):
                at = start + int(rng.choice([0, size // 2, size - lost]))
                data = _file(arrays, dataset)
                path = tmp_path / f"{kind}_{which}_{lost}_{at}.vtk"
                path.write_bytes(data[:at] + data[at + lost :])
                cases.append(path)
    return cases


def test_a_byte_lost_in_any_array_is_refused_not_read_shifted(tmp_path, helpers):
    cases = _cases(tmp_path)
    answers = helpers.read_in_child(cases)
    read = [path.name for path in cases if not isinstance(answers[str(path)], str)]
    assert not read, f"{len(read)} of {len(cases)} files with lost bytes were read: {read[:5]}"
    for path in cases:
        assert path.name in answers[str(path)], answers[str(path)]


def test_the_lost_byte_is_named_with_its_section(tmp_path):
    rng = np.random.default_rng(3)
    arrays = _arrays(rng, 20, "float")
    data = _file(arrays)
    at = data.index(b"Normals float\n") + 14 + 100
    path = tmp_path / "lost.vtk"
    path.write_bytes(data[:at] + data[at + 1 :])
    with pytest.raises(ValueError, match="NORMALS section: 'NORMALS Normals float' declares 60 values "
                                         r"\(POINT_DATA 20\), 240 bytes, whose last is the line end .* a byte short"):
        read_cloud(path)


@pytest.mark.parametrize("tight", [False, True], ids=["newlines", "tight"])
def test_arrays_whose_last_byte_is_a_newline_still_read(tmp_path, tight):
    """Data whose last byte is 10 by chance: followed by VTK's newline, or in a file written without any."""
    rng = np.random.default_rng(5)
    arrays = _arrays(rng, 10, "unsigned_char")
    values = np.frombuffer(arrays[2][1], np.uint8).copy()
    values[-1] = 10
    arrays[2] = (arrays[2][0], values.tobytes())
    path = tmp_path / "ten.vtk"
    path.write_bytes(_file(arrays, tight=tight))
    cloud = read_cloud(path)
    assert cloud.fields["s"].tolist() == values.tolist()
    assert np.allclose(np.linalg.norm(cloud.normals, axis=1), 1, atol=1e-6)
