"""A LAS/LAZ result carries the input's own fields (classes, intensity, returns, GPS time,
colours, extra bytes): they were written as zeros, and a classified scan came back
"never classified" (the CLI sweep). Both the whole-cloud and the tiled writer."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.cli import main

laspy = pytest.importorskip("laspy")


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    path = tmp_path_factory.mktemp("fields") / "scan.las"
    pts = core.shapes.torus(3000, seed=4).points + [5e5, 5e6, 100.0]
    rng = np.random.default_rng(0)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-4), np.floor(pts.min(axis=0))
    header.add_extra_dims([laspy.ExtraBytesParams(name="reflectance", type=np.float32),
                           laspy.ExtraBytesParams(name="k1", type=np.float64)])  # clashes with a result field
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.intensity = rng.integers(1, 60000, len(pts))
    las.classification = rng.choice([2, 5, 6], len(pts))
    las.return_number, las.number_of_returns = np.ones(len(pts), int), np.full(len(pts), 2)
    las.scan_angle_rank = rng.integers(-30, 30, len(pts))
    las.gps_time = np.arange(len(pts)) * 1e-3 + 3e5
    las.red, las.green, las.blue = (rng.integers(1, 65000, len(pts)) for _ in range(3))
    las.reflectance = rng.normal(size=len(pts)).astype(np.float32)
    las.k1 = np.full(len(pts), 123.0)
    las.write(str(path))
    return path


@pytest.mark.parametrize("tiles", [[], ["--tile-points", "800", "--workers", "0"]])
def test_the_input_s_fields_are_carried(scan, tmp_path, tiles):
    out = tmp_path / "out.laz"
    assert main(["estimate", str(scan), "-o", str(out), "--k", "15", "-q", *tiles]) == 0
    src, res = laspy.read(scan), laspy.read(out)
    assert res.header.point_format.id == 7  # RGB kept
    np.testing.assert_array_equal(res.xyz, src.xyz)
    for name in ("intensity", "classification", "return_number", "number_of_returns", "gps_time",
                 "red", "green", "blue", "reflectance"):
        np.testing.assert_array_equal(np.asarray(res[name]), np.asarray(src[name]), err_msg=name)
    np.testing.assert_allclose(np.asarray(res.scan_angle) * 0.006, np.asarray(src.scan_angle_rank), atol=0.003)
    assert np.median(np.asarray(res.k1)) == pytest.approx(1.0, abs=0.1)  # the result's k1, not the input's 123


def test_a_result_from_a_non_las_input_has_no_carried_fields(tmp_path):
    src = tmp_path / "cloud.xyz"
    np.savetxt(src, core.shapes.torus(2000, seed=1).points)
    out = tmp_path / "out.las"
    assert main(["estimate", str(src), "-o", str(out), "--k", "15", "-q"]) == 0
    res = laspy.read(out)
    assert res.header.point_format.id == 6 and not np.asarray(res.intensity).any()
