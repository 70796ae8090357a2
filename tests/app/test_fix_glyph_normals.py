"""The normal glyphs show: each starts at its point's sprite top and points outward along the
(oriented) normal. Centred on the point, as the tangent glyphs are, the sprites hid them."""

from __future__ import annotations

import numpy as np

from app.glyphs import FRAME_COLOURS, segments


def _pixels_of(window, hexcolour: str, tol: int = 40) -> int:
    """Pixels of the main 3D view within ``tol`` of a colour, rendered now."""
    window.plotter.ren_win.Render()
    img = np.asarray(window.plotter.screenshot(return_img=True))[..., :3].astype(int)
    rgb = np.array([int(hexcolour[i:i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - rgb).max(axis=2) <= tol).sum())


def test_outward_segments_start_at_the_point():
    pts = np.array([[0.0, 0, 0], [1, 1, 1]])
    dirs = np.array([[0.0, 0, 2], [1, 0, 0]])
    v, lines = segments(pts, dirs, np.arange(2), 3.0, centred=False)
    np.testing.assert_allclose(v, [[0, 0, 0], [0, 0, 3], [1, 1, 1], [4, 1, 1]])
    assert list(lines) == [2, 0, 1, 2, 2, 3]


def test_normal_glyphs_rise_from_the_sprites_and_show(make_window, qtbot):
    from app.source import make_shape

    window = make_window(make_shape("sphere", 2000), k_auto=False, k=15)
    window.state.set(show_normals=True)  # default density and length
    qtbot.waitUntil(lambda: "glyph-normals" in window.plotter.actors, timeout=10_000)
    v = np.asarray(window.plotter.actors["glyph-normals"].mapper.dataset.points)
    lift, length = window.scene.overlay_lift(), window.state.glyph_length * window.scene.spacing
    r0, r1 = np.linalg.norm(v[0::2], axis=1), np.linalg.norm(v[1::2], axis=1)  # the unit sphere
    assert np.median(r0) > 1 + 0.8 * lift  # above the sprites' tops, not inside them
    assert np.median(r1 - r0) > 0.8 * length  # outward, the whole length
    shown = _pixels_of(window, FRAME_COLOURS["n"])
    window.plotter.actors["cloud"].SetVisibility(False)
    alone = _pixels_of(window, FRAME_COLOURS["n"])
    window.plotter.actors["cloud"].SetVisibility(True)
    assert alone > 300 and shown / alone > 0.4, (shown, alone)
