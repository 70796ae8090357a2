"""Reader defects found by a mutation fuzz of every format (byte flips, truncations, header
edits): a binary PLY vertex element of no properties divided by zero, and a legacy VTK cell
array with entries left after its cells crashed VTK (a segmentation fault). Files that could
end the process are read in a subprocess with limited memory (``helpers.read_in_child``)."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from core.io import CloudFileError, read_cloud

BINARY_PLY = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
FACE = b"element face 1\nproperty list uchar int vertex_indices\n"


def _error(path, *parts):
    with pytest.raises(CloudFileError) as info:
        read_cloud(path)
    for part in (path.name, *parts):
        assert part in str(info.value), str(info.value)


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


def test_legacy_vtk_cells_using_every_entry_still_read(tmp_path):
    path = _legacy_vtk(tmp_path, "ok.vtk", False, "VERTICES 3 7", [1, 0, 0, 3, 1, 2, 3])  # an empty cell
    assert len(read_cloud(path)) == 12
