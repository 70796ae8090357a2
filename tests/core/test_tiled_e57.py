"""E57 input of a tiled estimate: scans in world coordinates, normals facing their scanner."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.io import read_cloud
from core.tiled import estimate_tiled

pye57 = pytest.importorskip("pye57")


def test_each_normal_faces_the_scanner_of_its_scan(tmp_path):
    pts = core.shapes.torus(10_000, seed=0).points
    views = [np.array([0.0, 0.0, 6.0]), np.array([0.0, 0.0, -6.0])]
    e57 = pye57.E57(str(tmp_path / "two.e57"), mode="w")
    for part, view in zip((pts[:5000], pts[5000:]), views):
        local = part - view  # stored in the scanner's frame, placed by the pose
        e57.write_scan_raw({"cartesianX": local[:, 0], "cartesianY": local[:, 1], "cartesianZ": local[:, 2]},
                           translation=view, rotation=np.array([1.0, 0.0, 0.0, 0.0]))
    e57.close()
    run = estimate_tiled(tmp_path / "two.e57", tmp_path / "out.ply", k=15, tile_points=700, workers=0)
    assert run.n_tiles >= 14
    out = read_cloud(tmp_path / "out.ply")
    np.testing.assert_allclose(out.points, pts, atol=1e-6)
    for rows, view in ((slice(0, 5000), views[0]), (slice(5000, None), views[1])):
        mem = core.estimate(out.points, k=15, orientation=view)  # the in-memory answer for this scanner
        np.testing.assert_allclose(out.normals[rows], mem.normals[rows], atol=1e-9)
        np.testing.assert_allclose(out.fields["k1"][rows], mem.k1[rows], atol=1e-9)
