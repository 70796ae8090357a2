"""Reader defects found by a mutation fuzz of every format (byte flips, truncations, header
edits): a binary PLY vertex element of no properties divided by zero."""

from __future__ import annotations

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
