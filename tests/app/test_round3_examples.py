"""Guided examples: the text is shown whole and the telling point faces the camera."""

from __future__ import annotations

import html
import re

import numpy as np
import pytest


@pytest.mark.parametrize("key", ["sphere", "cylinder", "torus", "saddle"])
def test_a_guided_example_shows_its_whole_text_and_a_point_the_camera_sees(make_window, qtbot, key):
    """The torus's text, shown as rich text, ended at "(hyperbolic, K": its "K < 0" opened a
    tag. The saddle's point was on the peanut's underside and the torus's on the near inner
    wall, hidden behind the tube: the frame and the sections were drawn where no one saw them."""
    from app.teach.examples import EXAMPLES
    from app_testutils import wait_result

    window = make_window()
    with wait_result(qtbot, window):
        window.teach.run_example(key)
    qtbot.waitUntil(lambda: window.state.picked is not None, timeout=10_000)
    label = window.teach.panel.example_label
    plain = html.unescape(re.sub(r"<[^>]*>", "", label.text()))
    assert EXAMPLES[key].text in plain
    res, picked = window.teach.controller.result, window.state.picked
    camera = np.asarray(window.plotter.camera.position)
    towards = camera - res.points[picked]
    assert np.dot(res.normals[picked], towards) > 0.3 * np.linalg.norm(towards)  # faces the camera
    # and nothing of the cloud lies on the segment to the camera (the near wall of the tube)
    seg = towards / np.linalg.norm(towards)
    rel = res.points - res.points[picked]
    along = rel @ seg
    off = np.linalg.norm(rel - np.outer(along, seg), axis=1)
    spacing = np.sqrt(4 * np.pi * np.ptp(res.points, axis=0).max() ** 2 / len(res.points)) / 4
    assert not np.any((along > 3 * spacing) & (off < spacing))
