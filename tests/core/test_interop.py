"""core.estimate takes point clouds of pyvista, Open3D, trimesh and laspy (duck-typed);
results convert to pyvista.PolyData."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import interop


@pytest.fixture(scope="module")
def sphere():
    return core.shapes.sphere(400, radius=2.0, seed=4)


@pytest.fixture(scope="module")
def reference(sphere):
    return core.estimate(sphere.points, k=15), core.estimate(sphere.points, sphere.normals, k=15)


class FakeVector3d:
    """Open3D's Vector3dVector: a sequence numpy converts, not an ndarray."""

    def __init__(self, array):
        self._array = np.asarray(array, dtype=np.float64)

    def __array__(self, dtype=None, copy=None):
        return self._array if dtype is None else self._array.astype(dtype)

    def __len__(self):
        return len(self._array)


class FakeOpen3D:
    def __init__(self, points, normals=None):
        self.points = FakeVector3d(points)
        self.normals = FakeVector3d(np.zeros((0, 3)) if normals is None else normals)

    def has_normals(self):
        return len(self.normals) > 0


class FakeTrimesh:
    def __init__(self, vertices):
        self.vertices = np.asarray(vertices)


def _same(a, b):
    np.testing.assert_allclose(a.mean, b.mean, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(a.valid, b.valid)


def test_open3d_like(sphere, reference):
    _same(core.estimate(FakeOpen3D(sphere.points), k=15), reference[0])
    _same(core.estimate(FakeOpen3D(sphere.points, sphere.normals), k=15), reference[1])
    assert interop.kind_of(FakeOpen3D(sphere.points)) == "open3d PointCloud"


def test_trimesh_like(sphere, reference):
    _same(core.estimate(FakeTrimesh(sphere.points), k=15), reference[0])
    assert interop.kind_of(FakeTrimesh(sphere.points)) == "trimesh"


def test_pyvista_polydata(sphere, reference):
    pv = pytest.importorskip("pyvista")
    cloud = pv.PolyData(sphere.points)
    _same(core.estimate(cloud, k=15), reference[0])
    cloud.point_data["Normals"] = sphere.normals
    _same(core.estimate(cloud, k=15), reference[1])
    cloud.point_data.active_normals_name = "Normals"
    _same(core.estimate(cloud, k=15), reference[1])


def test_given_normals_win_over_the_objects(sphere, reference):
    wrong = -sphere.normals
    res = core.estimate(FakeOpen3D(sphere.points, wrong), sphere.normals, k=15)
    _same(res, reference[1])


def test_laspy_lasdata(sphere, reference):
    laspy = pytest.importorskip("laspy")
    header = laspy.LasHeader(point_format=3, version="1.4")
    header.scales, header.offsets = [1e-7] * 3, [0.0] * 3
    las = laspy.LasData(header)
    las.x, las.y, las.z = sphere.points.T
    res = core.estimate(las, k=15)
    np.testing.assert_allclose(res.points, sphere.points, atol=1e-6)
    np.testing.assert_allclose(res.mean, reference[0].mean, atol=1e-3)


def test_io_cloud(sphere, reference, tmp_path):
    path = core.io.write_cloud(tmp_path / "s.ply", sphere.points, normals=sphere.normals)
    _same(core.estimate(core.io.read_cloud(path), k=15), reference[1])


def test_unknown_objects_still_refused():
    with pytest.raises(ValueError, match="points must"):
        core.estimate(object(), k=15)


def test_to_pyvista(reference):
    pv = pytest.importorskip("pyvista")
    res = reference[0]
    cloud = res.to_pyvista()
    assert isinstance(cloud, pv.PolyData) and cloud.n_points == len(res)
    np.testing.assert_array_equal(cloud.points, res.points)
    for name in ("k1", "k2", "mean", "gaussian", "shape_index", "curvedness", "k_point", "outlier_score"):
        np.testing.assert_array_equal(cloud.point_data[name], getattr(res, name), err_msg=name)
    np.testing.assert_array_equal(cloud.point_data["e1"], res.e1)
    np.testing.assert_array_equal(np.asarray(cloud.point_data["valid"], dtype=bool), res.valid)
    np.testing.assert_array_equal(cloud.point_data.active_normals, res.normals)
    assert cloud.active_scalars_name == "mean"
    again = core.estimate(cloud, k=15)  # and back: its normals are the refined ones
    assert again.valid.all()


def test_example_script_runs(sphere, tmp_path):
    pv = pytest.importorskip("pyvista")
    import runpy
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "docs" / "examples" / "pyvista_roundtrip.py"
    src = core.io.write_cloud(tmp_path / "s.ply", sphere.points, normals=sphere.normals)
    runpy.run_path(str(script))["main"]([str(src), "--out", str(tmp_path / "c.vtp")])
    back = pv.read(tmp_path / "c.vtp")
    assert back.n_points == 400 and abs(np.median(back.point_data["mean"]) - 0.5) < 0.05
