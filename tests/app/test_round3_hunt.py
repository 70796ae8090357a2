"""Round 3: problems found by using the viewer as a user would."""

from __future__ import annotations

import numpy as np
from PySide6.QtGui import QColor, QPalette

from app.source import make_shape


def test_the_3d_views_and_histogram_follow_a_palette_change_while_running(make_window, qtbot, qapp):
    """The desktop switches to a dark palette with the viewer open: the Qt widgets turned
    dark, the 3D views (both, compare on) and the histogram stayed white (old code: themed
    only when the window was built, screenshot /tmp/v/dark_runtime.png); and back."""
    window = make_window(make_shape("torus", 2000), compare_method="ct")
    assert window.compare is not None and window.compare.isVisible()
    views = (window.plotter, window.compare.plotter)
    assert all(np.mean(v.background_color.float_rgb) > 0.9 for v in views)
    old = qapp.palette()
    dark = QPalette(old)
    dark.setColor(QPalette.ColorRole.Window, QColor("#2b2b2b"))
    dark.setColor(QPalette.ColorRole.WindowText, QColor("#e0e0e0"))
    try:
        qapp.setPalette(dark)
        qtbot.waitUntil(lambda: all(np.mean(v.background_color.float_rgb) < 0.3 for v in views), timeout=5_000)
        assert np.mean(window.histogram.figure.get_facecolor()[:3]) < 0.3
        assert window.scene.theme.name == window.compare.scene.theme.name == "dark"
        # the glyph switches' labels, in the glyphs' colours (e1 near-black): on a light plate
        e1 = window.glyph_controls.boxes["show_e1"]
        assert "background-color: #f4f4f4" in e1.styleSheet(), e1.styleSheet()
        img = e1.grab().toImage()
        light = sum(img.pixelColor(x, img.height() // 2).lightness() > 200 for x in range(img.width()))
        assert light > img.width() // 3, (light, img.width())  # (old code: dark text on the dark panel)
    finally:
        qapp.setPalette(old)
    qtbot.waitUntil(lambda: all(np.mean(v.background_color.float_rgb) > 0.9 for v in views), timeout=5_000)
    assert np.mean(window.histogram.figure.get_facecolor()[:3]) > 0.9
    assert "background" not in window.glyph_controls.boxes["show_e1"].styleSheet()


def _png_size(path) -> tuple[int, int]:
    import struct

    with open(path, "rb") as f:
        head = f.read(24)
    return struct.unpack(">II", head[16:24])


def test_the_size_note_of_a_screenshot_gives_the_size_of_the_picture(tmp_path):
    """``--compare ct --size 640x480 --screenshot``: the window cannot be that small with its
    panels and says so. Old code: the note was printed when the window first showed (763x480
    here) and the compare view then widened it: the PNG was 1007x480, the note wrong."""
    import re

    from app_testutils import run_app_cli

    target = tmp_path / "small.png"
    proc = run_app_cli("--shape", "torus", "--points", "3000", "--compare", "ct", "--size", "640x480",
                       "--screenshot", str(target))
    assert proc.returncode == 0 and target.exists(), proc.stderr
    width, height = _png_size(target)
    sizes = re.findall(r"it is (\d+)x(\d+)", proc.stderr)
    if (width, height) == (640, 480):
        assert not sizes, proc.stderr
    else:
        assert sizes == [(str(width), str(height))], (proc.stderr, width, height)
