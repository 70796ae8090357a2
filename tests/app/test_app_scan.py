"""Viewer bits of real scans: the file-normals checkbox follows the file."""

from __future__ import annotations

import numpy as np

from app.source import load_file


def test_normals_checkbox_disabled_without_file_normals(make_window, qtbot, torus, tmp_path):
    path = tmp_path / "bare.xyz"
    np.savetxt(path, torus.points)
    w = make_window(load_file(path))
    assert not w.normals_check.isEnabled()
    assert w.output is not None  # estimated its own normals
    w.set_source(torus)  # a shape comes with exact normals
    assert w.normals_check.isEnabled()


def test_repaired_normals_and_border_in_the_status_bar(make_window, tmp_path):
    """A scan-like file: an open patch whose normals are partly zero. The estimate runs
    (no "pass normals=None"), the status bar counts the repairs and the border points,
    and the border points are grey (NaN) on screen and out of the colour limits."""
    from core import shapes

    s = shapes.plane(3000, seed=3)
    normals = s.normals.copy()
    normals[::20] = 0.0
    path = tmp_path / "patch.xyz"
    np.savetxt(path, np.hstack([s.points, normals]))
    w = make_window(load_file(path))
    assert w.normals_check.isEnabled()
    text = w.status_label.text()
    assert "150 file normals repaired" in text
    border = w.output.result.border
    assert border.any() and f"{int(border.sum()):,} on a border" in text
    shown = w.scene._cloud.point_data["values"]
    assert np.isnan(shown[border]).all()


def test_a_cloud_with_no_surface_says_why_in_the_status_bar(make_window, tmp_path):
    """A file whose points lie on one line: every point invalid, and the status bar names the
    reason instead of leaving a grey cloud unexplained."""
    t = np.linspace(0.0, 1.0, 400)
    path = tmp_path / "wire.xyz"
    np.savetxt(path, np.c_[t, 2 * t, -t])
    w = make_window(load_file(path))
    text = w.status_label.text()
    assert "400 invalid" in text and "no estimate: all points lie on one straight line" in text


def test_duplicate_points_are_counted_and_coloured_like_their_place(make_window, tmp_path):
    """A merged scan with every point written twice: estimated once per place (core.duplicates),
    no point grey, and the status bar says how many copies there were."""
    from core import shapes

    s = shapes.sphere(2000, seed=3)
    path = tmp_path / "twice.xyz"
    np.savetxt(path, np.concatenate([s.points, s.points]))
    w = make_window(load_file(path))
    text = w.status_label.text()
    assert "2,000 duplicates merged" in text and "all valid" in text
    res = w.output.result
    np.testing.assert_array_equal(res.mean[2000:], res.mean[:2000])
    assert abs(np.median(res.mean) - 1.0) < 0.02


def test_rough_file_normals_and_a_volume_are_named_in_the_status_bar(make_window, tmp_path):
    """A file whose normals are cruder than the estimator's own (PCA on 6 neighbours, noisy
    torus) beside a Gaussian blob of points: the status bar says the file normals gave only
    their signs and how many points lie on no surface."""
    from scipy.spatial import cKDTree

    from core import shapes
    from core.io import write_cloud

    s = shapes.torus(3000, seed=2)
    rng = np.random.default_rng(2)
    pts = s.points + rng.normal(scale=0.03, size=s.points.shape)
    idx = cKDTree(pts).query(pts, 6)[1]
    q = pts[idx] - pts[idx].mean(axis=1, keepdims=True)
    crude = np.linalg.eigh(np.einsum("nki,nkj->nij", q, q))[1][:, :, 0]
    crude *= np.sign(np.einsum("ij,ij->i", crude, s.normals))[:, None]
    blob = rng.normal(scale=0.3, size=(1500, 3)) + [0, 0, 6]
    path = tmp_path / "scan.ply"
    write_cloud(path, np.vstack([pts, blob]), normals=np.vstack([crude, np.tile([0.0, 0.0, 1.0], (1500, 1))]))
    w = make_window(load_file(path))
    text = w.status_label.text()
    assert "file normals rough: used for their signs only" in text
    volume = w.output.result.params["volumetric"]
    assert volume >= 1400 and f"{volume:,} on no surface" in text
