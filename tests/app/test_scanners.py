"""Scanner positions in the viewer: a marker and a label at each distinct viewpoint of a cloud
read from a PTX (or E57) file, toggled from the View menu, absent for a cloud without them."""

from __future__ import annotations

import numpy as np

import core
from app import scanners
from app.source import load_file

from app_testutils import wait_result

VIEWS = np.array([[0.0, 0.0, 5.0], [4.0, 0.0, 0.0]])


def _two_scan_ptx(path):
    """A sphere seen from two scanners, each scan in its own coordinates (identity turn)."""
    pts = core.shapes.sphere(800, seed=3).points
    text = ""
    for view, rows in zip(VIEWS, (pts[:, 2] > 0.3, pts[:, 0] > 0.3)):
        local = pts[rows] - view
        head = [f"{len(local)}", "1", " ".join(map(str, view)), "1 0 0", "0 1 0", "0 0 1",
                "1 0 0 0", "0 1 0 0", "0 0 1 0", " ".join(map(str, view)) + " 1"]
        text += "\n".join(head + [" ".join(f"{v!r}" for v in map(float, p)) for p in local]) + "\n"
    path.write_text(text)
    return path


def test_distinct_positions_in_the_order_they_first_appear():
    views = np.repeat([[3.0, 0, 0], [0, 0, 9.0], [3.0, 0, 0]], [2, 3, 1], axis=0)
    np.testing.assert_array_equal(scanners.positions(views), [[3, 0, 0], [0, 0, 9]])
    assert scanners.positions(None).shape == (0, 3)


def test_markers_at_the_scanners_toggled_from_the_view_menu(make_window, qtbot, tmp_path, torus):
    window = make_window()
    with wait_result(qtbot, window):
        window.set_source(load_file(_two_scan_ptx(tmp_path / "two.ptx")))
    actors = window.scene.plotter.actors
    assert "scanners" in actors and "scanners-labels" in actors
    marks = actors["scanners"].mapper.dataset
    centres = np.asarray(marks.points).reshape(2, -1, 3).mean(axis=1)  # one sphere per scanner, in order
    np.testing.assert_allclose(centres, VIEWS, atol=1e-6)
    assert window.scanners_action.isEnabled() and window.scanners_action.isChecked()
    window.scanners_action.trigger()  # off, as the user unchecks it
    assert window.state.scanners is False and "scanners" not in window.scene.plotter.actors
    window.scanners_action.trigger()
    assert "scanners" in window.scene.plotter.actors
    with wait_result(qtbot, window):
        window.set_source(torus)  # no viewpoints: no markers, nothing to toggle
    assert "scanners" not in window.scene.plotter.actors and not window.scanners_action.isEnabled()
