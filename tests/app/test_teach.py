"""The Teach mode: overlays on the picked point and the cloud, the plots, the flags, export."""

from __future__ import annotations

import numpy as np
import pytest


def _teach_ready(qtbot, window, timeout=60_000):
    qtbot.waitUntil(window.teach.controller.is_ready, timeout=timeout)


def test_every_overlay_follows_pick_theta_and_estimate(make_window, qtbot, torus, tmp_path):
    from app.teach import OVERLAYS

    window = make_window(torus, k_auto=False, k=15)
    teach = window.teach
    # off by default: a pick draws nothing of it
    assert not teach.dock.isVisible() and not teach.settings.enabled
    window.state.set(picked=3)
    assert teach.controller.layer.names == set()
    assert "Teach" in [a.text().replace("&", "") for a in window.menuBar().actions()]
    assert "Guided examples" in [a.text().replace("&", "") for a in window.shapes_menu.actions()]
    teach.configure(enabled=True, overlays=list(OVERLAYS), theta=30)
    window.state.set(picked=10)
    _teach_ready(qtbot, window)
    names = teach.controller.layer.names
    for expected in ("frame-e1", "frame-e2", "frame-n", "tangent-disc", "surface", "section-e1", "circle-e2",
                     "circle-theta", "section-plane", "dupin", "normals-measured", "normals-fitted",
                     "lines-e1", "lines-e2", "types"):
        assert expected in names, expected
    fit = teach.controller.fit
    assert fit is not None and fit.index == 10
    assert "χ" in teach.panel.cloud_label.text()
    assert "≈ |K|" in teach.panel.point_label.text()
    assert "&gt; 0" in teach.panel.point_label.text() or "&lt; 0" in teach.panel.point_label.text()
    assert len(teach.panel.euler.figure.axes) == 1
    teach.panel.tabs.setCurrentWidget(teach.panel.gauss_map)  # drawn when shown
    assert len(teach.panel.gauss_map.figure.axes) == 2
    _check_export(window, tmp_path)
    # theta moves the swept section and the Euler marker, not the rest
    before = np.array(teach.controller.layer.plotter.actors["teach-circle-theta"].mapper.dataset.points)
    teach.settings.set(theta=80)
    after = np.array(teach.controller.layer.plotter.actors["teach-circle-theta"].mapper.dataset.points)
    assert not np.allclose(before, after)
    assert "80°" in teach.panel.point_label.text()
    # a new pick re-fits
    window.state.set(picked=20)
    assert teach.controller.fit.index == 20
    # a new estimate recomputes the cloud-wide maths
    old = teach.controller.maths
    window.state.set(k_auto=False, k=20)
    qtbot.waitUntil(lambda: teach.controller.maths is not None and teach.controller.maths is not old, timeout=60_000)
    assert teach.controller.fit is not None and teach.controller.fit.index == 20
    # off: everything goes
    teach.configure(enabled=False)
    assert teach.controller.layer.names == set()


def test_point_type_legend_and_gauss_bonnet_on_a_sphere(make_window, qtbot):
    from app.source import make_shape

    window = make_window(make_shape("sphere", 2000), k_auto=False, k=20)
    window.teach.configure(enabled=True, overlays=["types"])
    _teach_ready(qtbot, window)
    maths = window.teach.controller.maths
    assert abs(maths.gauss_bonnet.chi - 2) < 0.06
    assert np.mean(maths.types == 4) > 0.95  # umbilic
    assert window.teach.controller._legend


def test_guided_example_loads_shape_and_picks(make_window, qtbot):
    from app_testutils import wait_result

    window = make_window()
    with wait_result(qtbot, window):
        window.teach.run_example("cylinder")
    qtbot.waitUntil(lambda: window.state.picked is not None, timeout=10_000)
    fit = window.teach.controller.fit
    assert fit is not None and fit.kind == "parabolic"
    assert "Cylinder" in window.teach.panel.example_label.text()
    _teach_ready(qtbot, window)


def _check_export(window, tmp_path):
    """Figures for slides: a 2x PNG of the view, the Euler plot as SVG and PDF."""
    paths = window.teach.export_figures(tmp_path, "slide")
    names = {p.name for p in paths}
    assert {"slide-view.png", "slide-euler.svg", "slide-euler.pdf", "slide-gauss-map.png"} <= names
    assert all(p.stat().st_size > 1000 for p in paths)
    assert (tmp_path / "slide-euler.svg").read_text().lstrip().startswith("<?xml")
    from PySide6.QtGui import QImage

    view = QImage(str(tmp_path / "slide-view.png"))
    assert view.width() >= 2 * window.plotter.width() - 2  # high resolution


def test_teach_flags_are_validated():
    from app.__main__ import build_parser
    from app.teach.cli import settings_from_args

    parser = build_parser()
    args = parser.parse_args(["--teach", "--overlays", "frame,lines", "--theta", "30", "--focus"])
    assert settings_from_args(args, parser) == {"enabled": True, "overlays": ["frame", "lines"], "theta": 30.0,
                                                "focus": True}
    assert settings_from_args(parser.parse_args([]), parser) == {}
    assert settings_from_args(parser.parse_args(["--example", "torus"]), parser)["example"] == "torus"
    for bad in (["--teach", "--overlays", "frame,bogus"], ["--theta", "30"], ["--example", "klein"]):
        with pytest.raises(SystemExit):
            settings_from_args(parser.parse_args(bad), parser)


def test_teach_settings_refuse_bad_values():
    from app.teach.dock import TeachSettings

    s = TeachSettings()
    with pytest.raises(ValueError, match="overlays"):
        s.set(overlays=["frame", "nope"])
    with pytest.raises(ValueError, match="teach setting"):
        s.set(colour="red")
    s.set(theta=200)
    assert s.theta == 20.0


def test_closing_while_the_cloud_maths_run_returns_at_once(make_window, qtbot, monkeypatch):
    """Closing waited for the lines of curvature of the whole cloud (59 s at 200k points):
    the job is now told to stop, and close returns within the estimate's own wait, with a
    job that reaches no check (here held until the test lets it go, or 30 s) still running."""
    import threading

    import app.teach.cloudwork as cloudwork
    import core
    from app.source import make_shape

    release, states = threading.Event(), []

    def held(res, *, separation=None, progress=None):
        states.append("running")
        while progress(0.0, "held") is not False and not release.is_set():
            release.wait(0.02)
        release.wait(30)
        states.append("ended")
        raise core.Cancelled("held")

    monkeypatch.setattr(cloudwork, "cloud_maths", held)
    window = make_window(make_shape("torus", 3000), k_auto=False, k=15)
    window.teach.configure(enabled=True)
    worker = window.teach.controller.worker
    qtbot.waitUntil(lambda: bool(states), timeout=10_000)
    thread = worker._thread
    window.close()
    assert states == ["running"] and thread.is_alive()
    release.set()
    qtbot.waitUntil(lambda: not thread.is_alive(), timeout=10_000)  # it stops at its next check
