"""A result larger than the viewer's budget opens as a level-of-detail sample with its
stored fields, refined to the region in view when zoomed (app.big_result)."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.io.atomic import atomic_write
from core.io.las_stream import LasResultWriter, result_columns

from app import big_result

laspy = pytest.importorskip("laspy")

BUDGET = 500


@pytest.fixture(scope="module")
def result_laz(tmp_path_factory):
    """A 6000-point curvature result on a wavy terrain, written as the tiled run writes it."""
    rng = np.random.default_rng(3)
    x, y = rng.uniform(0, 10, (2, 6000))
    pts = np.column_stack([x, y, 0.5 * np.sin(x) * np.cos(y)])
    res = core.estimate(pts, k=15)
    cols = result_columns(res)
    path = tmp_path_factory.mktemp("big") / "terrain_curv.laz"
    with atomic_write(path) as f, LasResultWriter(f, scales=np.full(3, 1e-4), offsets=np.zeros(3), laz=True) as w:
        w.write(pts, cols)
    return path


def _wait_shown(qtbot, view, action):
    with qtbot.waitSignal(view.shown, timeout=30_000) as got:
        action()
    view.thread.join(5)
    return got.args[0]


def test_a_result_over_the_budget_opens_as_a_sample_with_its_stored_fields(make_window, qtbot, monkeypatch,
                                                                          result_laz):
    monkeypatch.setattr(big_result, "BUDGET", BUDGET)
    assert big_result.wants(result_laz) and not big_result.wants(result_laz, budget=6000)
    window = make_window()
    with qtbot.waitSignal(window.result_shown, timeout=30_000) as got:
        assert window.open_file(result_laz) is None  # no loader ticket: the view reads it
    out = got.args[0]
    view = big_result.view_of(window)
    view.thread.join(5)
    src = window.state.source
    assert big_result.is_stored(src) and src is out.request.source and src.file_points == 6000
    assert 0 < len(out.points) <= BUDGET and src.box is None
    las = laspy.read(result_laz)
    np.testing.assert_array_equal(out.points, np.asarray(las.xyz)[src.rows])
    np.testing.assert_array_equal(out.result.k1, np.asarray(las.k1)[src.rows])  # stored, not re-estimated
    np.testing.assert_array_equal(out.fields["mean"], np.asarray(las.mean)[src.rows])
    assert window.presenter.output is out and window.shown["field"] == "mean"
    assert window.request_estimate() is None and not window.estimator.busy  # nothing to estimate
    assert "6,000 points stored" in window.status_label.text()
    assert window.recent_menu.paths()[0] == str(result_laz.resolve())


def test_zooming_in_rereads_the_region_in_view_and_zooming_out_returns(make_window, qtbot, monkeypatch, result_laz):
    monkeypatch.setattr(big_result, "BUDGET", BUDGET)
    window = make_window()
    view = big_result.view_of(window)
    overview = _wait_shown(qtbot, view, lambda: window.open_file(result_laz))
    window.plotter.camera.zoom(4.0)
    window.plotter.render()
    box, seen = view.view_box()
    assert seen < len(overview.points) / 2
    region = _wait_shown(qtbot, view, view.check_view)
    src = region.request.source
    assert src.box is not None and len(region.points) <= BUDGET
    lo, hi = map(np.asarray, src.box)
    assert ((region.points >= lo) & (region.points <= hi)).all()
    in_box = ((overview.points >= lo) & (overview.points <= hi)).all(axis=1).sum()
    assert len(region.points) >= 2 * in_box  # more detail where the camera looks
    las = laspy.read(result_laz)
    np.testing.assert_array_equal(region.result.k2, np.asarray(las.k2)[src.rows])
    window.scene.reset_camera("front")
    window.plotter.render()
    back = _wait_shown(qtbot, view, view.check_view)
    assert back is overview  # the overview is kept, not read again
