"""Round 2: the Teach panel's Euler plot fits its slot (issue 2), and the text over the 3D
view stays readable when the cloud and its glyphs fill the view behind it (issue 3)."""

from __future__ import annotations

import numpy as np
from app_testutils import image_array, wait_result

from app.source import make_shape


def test_euler_plot_and_its_legend_fit_the_teach_panel_at_1440x900(make_window, qtbot):
    """With a guided example's text above it, the tab holding the Euler plot was 29 px lower
    than the canvas's fixed minimum height (280): the bottom of the canvas, its legend, was
    cut off. The canvas now takes its slot's height and lays the figure out at every draw."""
    window = make_window(size=(1440, 900))
    with wait_result(qtbot, window, 60_000):
        window.teach.configure(example="saddle")
    panel = window.teach.panel
    qtbot.waitUntil(lambda: panel.euler.isVisible() and "Gauss" in panel.cloud_label.text()
                    and "Point" in panel.point_label.text(), timeout=30_000)
    qtbot.wait(500)  # the labels' text laid out
    window.grab()  # every pending layout request settled, as on screen
    euler = panel.euler
    euler.draw()
    shown = euler.visibleRegion().boundingRect()
    assert shown.height() == euler.height() and shown.width() == euler.width(), (shown, euler.size())
    legends = euler.figure.legends
    assert legends, "the Euler plot has its legend"
    box = legends[0].get_window_extent(euler.get_renderer())
    fig = euler.figure.bbox
    assert box.y0 >= fig.y0 - 0.5 and box.y1 <= fig.y1 + 0.5 and box.x0 >= fig.x0 - 0.5, (box, fig)
    # nothing of the axes (tick labels, x label) runs into the legend
    axes = euler.figure.axes[0].get_tightbbox(euler.get_renderer())
    assert axes.y0 >= box.y1 - 1.0, (axes, box)


def _saturated_share(window, box) -> float:
    """Share of strongly coloured pixels (glyphs, sprites) in ``box`` (x0, y0, x1, y1 px
    from the top-left corner) of the main view."""
    image = image_array(window.plotter.grabFramebuffer())
    x0, y0, x1, y1 = box
    patch = image[y0:y1, x0:x1].astype(int)
    saturation = patch.max(axis=2) - patch.min(axis=2)
    return float(np.mean(saturation > 60))


def test_text_over_a_zoomed_cloud_with_glyphs_stays_readable(make_window, qtbot):
    """Zoomed in, sprites and e1/e2/n segments filled the view behind the caption, the colour
    bar's labels and the glyph legend (thin dark text over them: unreadable). The text now
    sits on plates of the background colour."""
    window = make_window(make_shape("sphere", 20000), size=(1200, 800), show_e1=True, show_e2=True,
                         show_normals=True, glyph_density=100.0)
    scene = window.scene
    for prop in (scene._title_actor.prop, scene._bar.GetLabelTextProperty()):
        assert prop.GetBackgroundOpacity() >= 0.5
    assert scene._bar.GetDrawBackground()
    window.plotter.renderer.GetActiveCamera().Zoom(4.0)
    window.plotter.renderer.ResetCameraClippingRange()
    window.plotter.render()
    qtbot.wait(200)
    window.plotter.render()
    caption = (6, 6, 200, 56)  # inside the caption's first three lines
    assert _saturated_share(window, (300, 300, 500, 500)) > 0.2  # the view behind is full of them
    assert _saturated_share(window, caption) < 0.05
    legend = window.plotter.actors["glyph-legend-e2"]
    assert legend.prop.GetBackgroundOpacity() >= 0.5


def test_text_plates_follow_the_theme(make_window, qtbot, torus):
    from app.theme import DARK

    import pyvista as pv

    window = make_window(torus)
    window.scene.set_theme(DARK)
    want = pv.Color(DARK.background).float_rgb
    assert np.allclose(window.scene._title_actor.prop.GetBackgroundColor(), want)
    assert np.allclose(window.scene._bar.GetBackgroundProperty().GetColor(), want)


def test_glyph_legend_stays_readable_on_the_dark_theme(make_window, qtbot, torus):
    """The glyph legend's rows are in the glyphs' own colours (e1 near black): on the dark
    theme's plate its e1 row was black on near black. Its plate is light in both themes."""
    from app.theme import DARK

    import pyvista as pv

    window = make_window(torus, show_e1=True)
    window.scene.set_theme(DARK)
    row = window.plotter.actors["glyph-legend-e1"].prop
    plate = np.array(row.GetBackgroundColor())
    ink = np.array(pv.Color(row.GetColor()).float_rgb)
    luminance = lambda c: float(np.dot(c, [0.2126, 0.7152, 0.0722]))  # noqa: E731
    assert luminance(plate) - luminance(ink) > 0.5, (plate, ink)
