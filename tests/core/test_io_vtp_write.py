"""Results written as VTK XML PolyData (.vtp) for ParaView: VTK itself reads the points,
one vertex cell each, the normals as the point data's normals and e1, e2 as 3-component
vectors; the file reads back through :func:`core.io.read_cloud` to the same numbers."""

from __future__ import annotations

import io

import numpy as np
import pytest

import core
from core.io import read_cloud, write_cloud, write_result

pv = pytest.importorskip("pyvista")


def test_vtk_reads_points_vertex_cells_normals_and_direction_vectors(tmp_path):
    res = core.estimate(core.shapes.torus(800, seed=1).points, k=15)
    path = write_result(tmp_path / "torus.vtp", res)
    mesh = pv.read(path)
    assert mesh.n_points == len(res.points) and mesh.n_verts == len(res.points)  # drawn as points, no filter
    np.testing.assert_array_equal(mesh.points, res.points)
    np.testing.assert_array_equal(mesh.point_data.active_normals, res.normals)
    np.testing.assert_array_equal(mesh.point_data["e1"], res.e1)
    np.testing.assert_array_equal(mesh.point_data["mean"], res.mean)
    assert mesh.point_data["valid"].dtype == np.uint8 and mesh.point_data["k"].dtype == res.k_point.dtype
    back = read_cloud(path)
    np.testing.assert_array_equal(back.normals, res.normals)
    np.testing.assert_array_equal(back.fields["e2_z"], res.e2[:, 2])


def test_names_that_xml_would_misread_and_a_stream(tmp_path):
    pts = np.random.default_rng(0).random((5, 3))
    fields = {"a<b&c>": np.arange(5.0), "q'": np.arange(5, dtype=np.int16)}
    path = write_cloud(tmp_path / "odd.vtp", pts, fields=fields)
    back = read_cloud(path)
    np.testing.assert_array_equal(back.fields["a<b&c>"], np.arange(5.0))
    assert back.fields["q'"].dtype == np.int16 and back.normals is None
    stream = io.BytesIO()
    write_cloud(stream, pts, fields=fields, format="vtp")
    assert stream.getvalue() == path.read_bytes()
