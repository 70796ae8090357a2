"""Lines drawn on the surface (direction glyphs, lines of curvature) show over the point
sprites: they float above the sprites' tops (app/framing.overlay_lift). Drawn at 0.6-0.7 of
a spacing they hid inside sprites 1.7 spacings wide, so glyphs and lines never showed."""

from __future__ import annotations

import numpy as np
import pytest

from app.glyphs import FRAME_COLOURS


def _pixels_of(window, hexcolour: str, tol: int = 40) -> int:
    """Pixels of the main 3D view within ``tol`` of a colour, rendered now (a render the
    window asks for waits for the event loop)."""
    window.plotter.ren_win.Render()
    img = np.asarray(window.plotter.screenshot(return_img=True))[..., :3].astype(int)
    rgb = np.array([int(hexcolour[i:i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img - rgb).max(axis=2) <= tol).sum())


def _shown_share(window, colour: str) -> float:
    """The share of a colour's pixels that stays when the cloud's sprites are drawn too."""
    with_cloud = _pixels_of(window, colour)
    cloud = window.plotter.actors["cloud"]
    cloud.SetVisibility(False)
    alone = _pixels_of(window, colour)
    cloud.SetVisibility(True)
    assert alone > 500, alone  # the overlay is drawn at all
    return with_cloud / alone


@pytest.mark.parametrize("point_size", [5.0, 12.0])
def test_glyphs_show_over_the_point_sprites(make_window, qtbot, point_size):
    from app.source import make_shape

    window = make_window(make_shape("torus", 3000), k_auto=False, k=12, point_size=point_size)
    window.state.set(show_e2=True, glyph_density=1.0)
    qtbot.waitUntil(lambda: "glyph-e2" in window.plotter.actors, timeout=10_000)
    # about half the glyphs are on the far side of the torus, behind the near one
    assert _shown_share(window, FRAME_COLOURS["e2"]) > 0.3


def test_lines_of_curvature_show_over_the_point_sprites(make_window, qtbot):
    from app.source import make_shape

    window = make_window(make_shape("torus", 3000), k_auto=False, k=12)
    window.teach.configure(enabled=True, overlays=["lines"])
    qtbot.waitUntil(window.teach.controller.is_ready, timeout=60_000)
    assert _shown_share(window, FRAME_COLOURS["e2"]) > 0.3
    before = np.array(window.teach.controller.layer.plotter.actors["teach-lines-e2"].mapper.dataset.points)
    window.state.set(point_size=12.0)  # bigger sprites: the lines float higher
    after = np.array(window.teach.controller.layer.plotter.actors["teach-lines-e2"].mapper.dataset.points)
    assert np.linalg.norm(after - before, axis=1).min() > 0
    assert _shown_share(window, FRAME_COLOURS["e2"]) > 0.3
