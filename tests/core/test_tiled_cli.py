"""``darboux-cli estimate`` with tiles: the options, the automatic switch, LAS/LAZ output."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.cli import main

laspy = pytest.importorskip("laspy")


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    path = tmp_path_factory.mktemp("scan") / "scan.laz"
    pts = core.shapes.torus(8000, seed=2).points
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-4), np.floor(pts.min(axis=0))
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.write(str(path))
    return path


def test_tile_options_run_in_tiles(scan, tmp_path, capsys):
    out = tmp_path / "out.laz"
    assert main(["estimate", str(scan), "-o", str(out), "--k", "15", "--tile-points", "500", "--workers", "0"]) == 0
    text = capsys.readouterr().out
    assert "8000 points in 16 tiles" in text and "agreement over tile overlaps: 100.00 %" in text
    las = laspy.read(out)
    np.testing.assert_array_equal(las.xyz, laspy.read(scan).xyz)
    assert np.median(las.k1) == pytest.approx(1.0, abs=0.05)  # the tube's curvature, outward


def test_a_budget_smaller_than_the_cloud_switches_to_tiles(scan, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("core.tiled.cli.bytes_per_point", lambda k: 10**5)  # 8000 points "need" 800 MB
    monkeypatch.setattr("core.tiled.cli.AUTO_BYTES_PER_POINT", 10**5)
    out = tmp_path / "out.ply"
    assert main(["estimate", str(scan), "-o", str(out), "--k", "15", "--memory", "700MB"]) == 0
    assert "8000 points in 1 tiles" in capsys.readouterr().out  # on a local Dask cluster
    assert main(["estimate", str(scan), "-o", str(tmp_path / "b.ply"), "--k", "15", "--memory", "900MB", "-q"]) == 0
    assert "tiles" not in capsys.readouterr().out  # fits: in memory
    assert main(["estimate", str(scan), "-o", str(tmp_path / "a.ply"), "--memory", "700MB"]) == 0
    text = capsys.readouterr().out  # the default, k="auto", in tiles too, with the whole cloud's medians
    assert "8000 points in 1 tiles" in text and "k auto" in text and "whole cloud: noise" in text
    assert (tmp_path / "a.ply").exists()


def test_auto_k_within_memory_writes_laz(scan, tmp_path):
    out = tmp_path / "auto.laz"
    assert main(["estimate", str(scan), "-o", str(out), "-q"]) == 0
    las = laspy.read(out)
    ks = set(np.unique(las.k))  # k chosen per point among the jet rule's candidates (15 included), not one k
    assert ks <= set(core.scale.JET_KS) and len(ks) > 1 and len(las.points) == 8000


def test_normals_in_the_file_are_kept_unless_ignored(tmp_path, capsys):
    t = core.shapes.torus(6000, seed=4)
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.scales, header.offsets = np.full(3, 1e-5), np.floor(t.points.min(axis=0))
    header.add_extra_dims([laspy.ExtraBytesParams(name=n, type=np.float64) for n in ("nx", "ny", "nz")])
    las = laspy.LasData(header)
    las.x, las.y, las.z = t.points.T
    las.nx, las.ny, las.nz = (-t.normals).T  # inward
    las.write(str(tmp_path / "n.laz"))
    common = ["--k", "15", "--tile-points", "400", "--workers", "0", "-q"]
    assert main(["estimate", str(tmp_path / "n.laz"), "-o", str(tmp_path / "kept.laz"), *common]) == 0
    assert main(["estimate", str(tmp_path / "n.laz"), "-o", str(tmp_path / "own.laz"), "--ignore-normals",
                 *common]) == 0
    assert np.median(laspy.read(tmp_path / "kept.laz").k2) == pytest.approx(-1.0, abs=0.05)  # inward tube
    assert np.median(laspy.read(tmp_path / "own.laz").k1) == pytest.approx(1.0, abs=0.05)  # outward tube
