"""The result's flags travel with it: write_result's named properties, read back."""

from __future__ import annotations

import types

import numpy as np
import pytest

import core
from core import noise, shapes, shapes_thin
from core.io import RESULT_FLAGS, read_cloud, write_result

laspy = pytest.importorskip("laspy")


@pytest.fixture(scope="module")
def result():
    """A noisy plate with outliers: every flag has both values somewhere."""
    s = shapes_thin.thin_plate(4000, seed=2)
    pts, _ = noise.add_outliers(noise.add_noise(s.points, 0.1, seed=1), 0.01, seed=2)
    return core.estimate(pts, k=30)


@pytest.mark.parametrize("ext", ["ply", "csv", "xyz"])
def test_flags_written_and_read_back(tmp_path, result, ext):
    path = write_result(tmp_path / f"r.{ext}", result)
    f = read_cloud(path).fields
    assert list(f)[-len(RESULT_FLAGS):] == list(RESULT_FLAGS)
    np.testing.assert_array_equal(f["k"], result.k_point)
    np.testing.assert_array_equal(f["degree"], result.degree_point)
    for name in ("border", "outlier", "crease", "striped"):
        values = getattr(result, name)
        assert values.any() or name == "striped", name  # the fixture exercises both values
        np.testing.assert_array_equal(f[name].astype(bool), values, err_msg=name)
    np.testing.assert_array_equal(f["point_type"], core.point_types(result))
    for name in ("orientation_confidence", "outlier_score", "anisotropy"):
        np.testing.assert_allclose(f[name], getattr(result, name), rtol=1e-12, equal_nan=True, err_msg=name)


def test_ply_types_are_compact(tmp_path, result):
    f = read_cloud(write_result(tmp_path / "r.ply", result)).fields
    assert all(f[name].dtype == np.uint8 for name in ("border", "outlier", "crease", "striped"))
    assert f["point_type"].dtype == np.int8 and set(np.unique(f["point_type"])) <= {-1, 0, 1, 2, 3, 4}


def test_a_bare_result_writes_what_it_has(tmp_path):
    """Anything with the base attributes is written; flags it lacks are left out."""
    r = core.estimate(shapes.sphere(300, seed=0).points, k=15)
    bare = types.SimpleNamespace(**{name: getattr(r, name) for name in ("points", "normals", *core.io.RESULT_FIELDS)},
                                 border=r.border)
    f = read_cloud(write_result(tmp_path / "bare.csv", bare)).fields
    assert "border" in f and "anisotropy" not in f and "k" not in f


def test_tiled_laz_carries_the_flags(tmp_path):
    from core.tiled import estimate_tiled

    s = shapes.torus(6000, seed=3)
    pts = noise.add_noise(s.points, 0.05, seed=1)
    src = tmp_path / "scan.las"
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.scales, header.offsets = np.full(3, 1e-6), pts.min(axis=0)
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.write(src)
    pts = laspy.read(src).xyz
    mem = core.estimate(pts, k=15)
    estimate_tiled(src, tmp_path / "out.laz", k=15, tile_points=1500, workers=1, memory="1GB")
    out = laspy.read(tmp_path / "out.laz")
    for name in ("border", "outlier", "crease", "striped"):
        assert np.mean(np.asarray(out[name]).astype(bool) == getattr(mem, name)) > 0.995, name
    np.testing.assert_array_equal(np.asarray(out.degree), mem.degree_point)
    np.testing.assert_allclose(np.asarray(out.outlier_score), mem.outlier_score, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(np.asarray(out.anisotropy), mem.anisotropy, atol=1e-5)
    assert np.mean(np.abs(np.asarray(out.orientation_confidence) - mem.orientation_confidence) < 1e-5) > 0.99
    f = read_cloud(estimate_tiled(src, tmp_path / "out.ply", k=15, tile_points=1500, workers=1,
                                  memory="1GB").output).fields
    assert list(f)[-len(RESULT_FLAGS) + 1:] == [n for n in RESULT_FLAGS if n != "point_type"]
