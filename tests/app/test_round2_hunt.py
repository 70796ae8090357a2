"""Round 2, found by hunting: a small window with the compare view framed the cloud off the
main view, and points without a value were drawn in a grey that the diverging map's centre
(H = 0 on a flat part, shaded) is drawn in too."""

from __future__ import annotations

import numpy as np
from app_testutils import wait_result

from app.source import make_shape


def test_a_small_window_with_the_compare_view_still_shows_the_cloud_in_both(make_window, qtbot):
    """At --size 480x320 the splitter left the compare view 0 px wide; the fit framed the
    narrowest view, that one, and the main view showed no cloud (old code: sprites filling
    it, zoomed far in). Now the compare view has a minimum size and a squeezed view does not
    count for the fit."""
    from app import framing

    window = make_window(make_shape("torus", 3000), size=(480, 320))
    with wait_result(qtbot, window, 60_000):
        window.compare_combo.setCurrentIndex(window.compare_combo.findData("ct"))
    qtbot.wait(300)
    for plotter in (window.plotter, window.compare.plotter):
        plotter.render()
        width, height = plotter.render_window.GetSize()
        assert width >= 200 and height >= 200, (width, height)
        x, y, _ = framing.projection(plotter.renderer, window.output.points)
        inside = (x >= 0) & (x < width) & (y >= 0) & (y < height)
        assert inside.mean() == 1.0
        assert np.ptp(x) > 0.3 * width  # framed, not a speck


def test_narrowest_skips_a_view_squeezed_to_nothing(make_window, qtbot, torus):
    from app import framing

    window = make_window(torus)

    class Squeezed:
        def GetViewport(self):
            return (0.0, 0.0, 1.0, 1.0)

        def GetRenderWindow(self):
            class Window:
                def GetSize(self):
                    return (1, 600)
            return Window()

    assert framing.narrowest([window.plotter.renderer, Squeezed()]) is window.plotter.renderer


def test_points_without_a_value_stand_apart_from_every_colour_of_the_map(make_window, qtbot):
    """The no-value colour is farther from every colour of the map it is drawn over than the
    map's own neighbouring shades are from each other (old: #b0b0b0 beside RdBu_r's #f7f7f7
    centre, both drawn light grey on shaded sprites)."""
    import matplotlib
    import pyvista as pv

    from app import legend
    from app.fields import DIVERGING, ERROR, SEQUENTIAL

    for cmap in (DIVERGING, SEQUENTIAL, ERROR):
        nan = np.array(pv.Color(legend.nan_colour(cmap)).float_rgb)
        colours = matplotlib.colormaps[cmap](np.linspace(0, 1, 256))[:, :3]
        for shade in (1.0, 0.7, 0.5):  # lit and shaded sides of a sprite
            assert np.min(np.linalg.norm(colours * shade - nan, axis=1)) > 0.12, (cmap, shade)
    window = make_window(make_shape("plane", 2000))
    assert window.scene._lut.nan_color.hex_rgb == legend.nan_colour(window.shown["cmap"])
