"""Teach mode's cloud-wide maths end, with words, on awkward clouds: points stored twice, too
few points for Gauss-Bonnet, a part of the maths failing, a new cloud whose estimate fails."""

from __future__ import annotations

import numpy as np

import core


def _teach_window(make_window, qtbot, points, name="cloud"):
    from app.source import CloudSource

    window = make_window(k_auto=False, k=15)
    window.teach.configure(enabled=True, overlays=["types", "lines"])
    window.set_source(CloudSource(name=name, points=points))
    qtbot.waitUntil(window.teach.controller.is_ready, timeout=120_000)
    return window


def _errors(window):
    return [n.message for n in window.notifier.history if n.level == "error"]


def test_a_cloud_stored_twice_gets_its_gauss_bonnet_and_lines(make_window, qtbot):
    sphere = core.shapes.sphere(1500, seed=0).points
    window = _teach_window(make_window, qtbot, np.repeat(sphere, 2, axis=0), "doubled sphere")
    maths, text = window.teach.controller.maths, window.teach.panel.cloud_label.text()
    assert maths is not None and not maths.notes, maths.notes
    assert abs(maths.gauss_bonnet.chi - 2) < 0.2  # the copies share their cell: not 4
    assert "computing" not in text and "χ" in text
    assert not _errors(window)


def test_too_few_points_for_gauss_bonnet_says_so_and_shows_the_rest(make_window, qtbot):
    window = _teach_window(make_window, qtbot, core.shapes.sphere(30, seed=0).points, "30 points")
    maths, text = window.teach.controller.maths, window.teach.panel.cloud_label.text()
    assert maths.gauss_bonnet is None and maths.types is not None
    assert "unavailable for so few points" in text and "30" in text
    assert "Point types:" in text and "lines of curvature traced" in text
    assert "types" in window.teach.controller.layer.names
    assert not _errors(window)


def test_a_failing_part_is_told_and_the_others_show(make_window, qtbot, monkeypatch):
    def broken(*_args, **_kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(core, "curvature_lines", broken)
    window = _teach_window(make_window, qtbot, core.shapes.sphere(800, seed=0).points)
    text = window.teach.panel.cloud_label.text()
    assert "computing" not in text and "χ" in text and "Point types:" in text
    assert "ZeroDivisionError: float division by zero" in text


def test_a_whole_failure_ends_computing_with_its_reason(make_window, qtbot, monkeypatch):
    def broken(*_args, **_kwargs):
        raise FloatingPointError("no scale")

    monkeypatch.setattr(core, "curvature_scale", broken)
    window = _teach_window(make_window, qtbot, core.shapes.sphere(800, seed=0).points)
    text = window.teach.panel.cloud_label.text()
    assert "computing" not in text and "could not be computed" in text and "no scale" in text
    assert any("no scale" in message for message in _errors(window))
    shot = []
    window.teach.when_ready(lambda: shot.append(True))  # a screenshot waiting on it goes ahead
    assert shot


def test_a_new_cloud_clears_the_previous_ones_words(make_window, qtbot):
    from app.source import CloudSource

    window = _teach_window(make_window, qtbot, core.shapes.sphere(800, seed=0).points)
    window.state.set(picked=3)
    panel = window.teach.panel
    assert "χ" in panel.cloud_label.text() and "Point 3" in panel.point_label.text()
    before = len(window.notifier.history)
    four = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    window.set_source(CloudSource(name="four", points=four))  # its estimate fails
    qtbot.waitUntil(lambda: len(window.notifier.history) > before, timeout=60_000)
    qtbot.wait(200)
    assert "χ" not in panel.cloud_label.text() and "∫K" not in panel.cloud_label.text()
    assert "Point 3" not in panel.point_label.text()
    assert window.teach.controller.layer.names == set()
