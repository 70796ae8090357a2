"""Bad input to a tiled run: a clear error naming the file (and the tile), no output, and
no work directory left behind unless it holds finished tiles to resume."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from core import shapes
from core.tiled import estimate_tiled, task

laspy = pytest.importorskip("laspy")


@pytest.fixture
def scan(tmp_path):
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-4), np.zeros(3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = shapes.torus(4000, seed=2).points.T
    path = tmp_path / "scan.laz"
    las.write(str(path))
    return path


def _everything(folder):
    return sorted(p.name for p in folder.iterdir())  # hidden work directories included


def _patched(src, dst, offset, data):
    raw = bytearray(src.read_bytes())
    raw[offset:offset + len(data)] = data
    dst.write_bytes(bytes(raw))
    return dst


@pytest.mark.parametrize("name, damage, message", [
    ("cut.laz", lambda raw: raw[: len(raw) // 2], r"cut\.laz.*(truncated|unreadable)"),
    ("short.laz", lambda raw: raw[:107] + struct.pack("<I", 5000) + raw[111:], r"short\.laz.*(truncated|unreadable)"),
    ("zero.laz", lambda raw: raw[:131] + np.float64(0.0).tobytes() + raw[139:], r"zero\.laz.*scale"),
])
def test_a_damaged_laz_is_named_and_leaves_nothing(scan, tmp_path, name, damage, message):
    bad = tmp_path / name
    bad.write_bytes(damage(scan.read_bytes()))  # (short: the header claims 5000 of 4000 points)
    before = _everything(tmp_path)
    with pytest.raises(ValueError, match=message):
        estimate_tiled(bad, tmp_path / "out.laz", k=15, tile_points=1000, workers=0)
    assert _everything(tmp_path) == before  # no output, no work directory


def test_an_output_folder_that_does_not_exist_is_named_before_any_work(scan, tmp_path):
    with pytest.raises(ValueError, match=r"folder .*nowhere does not exist"):
        estimate_tiled(scan, tmp_path / "nowhere" / "out.laz", k=15, workers=0)
    assert not (tmp_path / "nowhere").exists()


def test_a_tile_failing_on_dask_is_named_with_the_file_and_nothing_is_written(scan, tmp_path, monkeypatch):
    distributed = pytest.importorskip("distributed")
    real = task.run_tile

    def fails_at_tile_2(root, tile, spec):
        if tile == 2:
            raise RuntimeError("disk on fire")
        return real(root, tile, spec)

    monkeypatch.setattr("core.tiled.engine.run_tile", fails_at_tile_2)
    out = tmp_path / "out.laz"
    with distributed.Client(processes=False, n_workers=1, threads_per_worker=1, dashboard_address=":0") as client:
        with pytest.raises(ValueError, match=r"scan\.laz: tile 2 failed: RuntimeError: disk on fire"):
            estimate_tiled(scan, out, k=15, tile_points=1000, client=client)
    assert not out.exists()
    assert (tmp_path / ".out.laz.tiles").is_dir()  # the finished tiles are kept: a rerun resumes


@pytest.mark.parametrize("orientation", [{"x": 1}, [1, "a", 2], [1.0, 2.0], [0.0, np.nan, 1.0], object()])
def test_a_viewpoint_that_is_not_three_numbers_is_refused_as_in_memory(tmp_path, orientation):
    """The tiles check a viewpoint as core.estimate does (a dict raised a bare TypeError)."""
    import core

    pts = shapes.sphere(400, seed=0).points
    message = r"orientation as a viewpoint must be 3 finite numbers"
    with pytest.raises(ValueError, match=message):
        core.estimate(pts, orientation=orientation)
    with pytest.raises(ValueError, match=message):
        estimate_tiled(pts, tmp_path / "out.npz", orientation=orientation)
    assert not (tmp_path / "out.npz").exists()
