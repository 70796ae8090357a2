"""Hostile files, round seven (2026-12-08): a binary STL whose last triangle took inserted bytes,
leaving only its zero attribute bytes after it (read shifted: corners of 1e38 or 1e-39, read as
padding), ..."""

from __future__ import annotations

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
