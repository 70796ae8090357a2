"""The colour bar of a 3D view, and its glyph legend: one coloured row per glyph kind shown
(GUI thread, VTK calls).

Lower-left, beside the colour bar when the view is wide enough for both; in a narrower view
(the compare view, a window with its docks) above the bar and its title, so it is never
drawn over the bar or its tick labels (saved figures carry it).
"""

from __future__ import annotations

import numpy as np
import pyvista as pv

from . import glyphs
from .framing import BAR_BOTTOM, BAR_HEIGHT, BAR_LEFT, BAR_MAX_PX, BAR_WIDTH

__all__ = ["update_legend", "place_legend", "KINDS", "add_bar", "label_categories", "band_map", "plate",
           "PLATE_OPACITY"]

#: Glyph kinds, bottom row first.
KINDS = ("normals", "e2", "e1")
#: Left edge of the legend, a viewport fraction.
LEFT = 0.012
#: Pixels: a row, the room the bar's title takes above it, half a tick label left of the bar.
ROW_PX, TITLE_PX, TICK_PX = 20.0, 26.0, 30.0


#: Text over the cloud (caption, colour bar, legend) sits on a plate of the view's background
#: this opaque: zoomed in, the point sprites and glyph segments filled the view behind it and
#: the thin text over them could not be read.
PLATE_OPACITY = 0.8


def plate(prop, background) -> None:
    """Put the text of the vtkTextProperty ``prop`` on a plate of colour ``background``."""
    prop.SetBackgroundColor(pv.Color(background).float_rgb)
    prop.SetBackgroundOpacity(PLATE_OPACITY)


def plate_bar(bar, background) -> None:
    """A plate behind the whole colour bar: its title, the bar and its tick labels."""
    bar.SetDrawBackground(True)
    bar.GetBackgroundProperty().SetColor(pv.Color(background).float_rgb)
    bar.GetBackgroundProperty().SetOpacity(PLATE_OPACITY)
    plate(bar.GetLabelTextProperty(), background)  # (the end labels reach past the plate)


def restyle(bar, texts, theme) -> None:
    """The colours of ``theme`` (:class:`app.theme.Theme`) on a colour bar and text actors."""
    for text in filter(None, texts):
        text.prop.color = theme.text
        plate(text.prop, theme.background)
    if bar is not None:
        for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
            prop.SetColor(pv.Color(theme.text).float_rgb)
        plate_bar(bar, theme.background)


#: Colour of the points with no value (invalid, border): a grey unlike any of the map's,
#: shaded as the sprites are. The mid grey (#b0b0b0) of before was 126 against the 171 that a
#: value at the centre of the diverging map (its near-white, H = 0) is drawn in: a flat part
#: and the invalid points looked alike. The dark grey stands apart from the light centre and
#: the coloured ends; magma (errors, black at 0) keeps the mid grey, which it has not.
NAN_COLOURS = {"magma": "#b0b0b0"}
NAN_DEFAULT = "#3c3c3c"


def nan_colour(cmap: str) -> str:
    """The colour points without a value are drawn in over the map ``cmap``."""
    return NAN_COLOURS.get(str(cmap), NAN_DEFAULT)


def band_map(cmap: str, bands: int):
    """A categorical field's colour map: the first ``bands`` colours of the qualitative map
    ``cmap`` (tab10, tab20), one a value, for the cloud and its histogram alike. Sampled over
    its whole range instead, two scans took the map's two ends, blue and cyan."""
    import matplotlib
    from matplotlib.colors import ListedColormap

    return ListedColormap(list(matplotlib.colormaps[cmap].colors[:bands]), name=f"{cmap}_{bands}")


#: the glyph legend's plate in either theme: its rows are in the glyphs' own colours (a near-black
#: e1), chosen to show on the coloured points, and on the dark theme's plate e1 was unreadable
GLYPH_PLATE = "#f4f4f4"


def update_legend(plotter, shown, colours: dict, background=GLYPH_PLATE) -> tuple | None:
    """A row for each glyph kind in ``shown`` (colours: kind -> colour), on plates of
    ``background``, then place them (:func:`place_legend`; its window size is returned)."""
    labels = dict(zip(("e1", "e2", "normals"), (text for text, _ in glyphs.LEGEND)))
    for kind in KINDS:
        name = f"glyph-legend-{kind}"
        if kind not in shown:
            plotter.remove_actor(name, render=False)
            continue
        actor = plotter.add_text(f"\u2014 {labels[kind]}", position=(LEFT, 0.03), viewport=True, font_size=7,
                                 color=colours[kind], name=name, render=False)
        actor.prop.font_size = 13
        actor.prop.bold = True
        plate(actor.prop, background)
    return place_legend(plotter)


def place_legend(plotter) -> tuple | None:
    """Stack the legend rows beside the colour bar, or above it when they would reach it.
    Returns the window size it was placed for (None if there is no window yet)."""
    renderer = plotter.renderer
    window = renderer.GetRenderWindow()
    actors = [plotter.actors[f"glyph-legend-{k}"] for k in KINDS if f"glyph-legend-{k}" in plotter.actors]
    if window is None or not actors:
        return None
    x0, y0, x1, y1 = renderer.GetViewport()
    width, height = window.GetSize()
    w, h = max((x1 - x0) * width, 1.0), max((y1 - y0) * height, 1.0)
    widest = 0.0
    for actor in actors:
        box = [0.0] * 4
        actor.GetBoundingBox(renderer, box)
        widest = max(widest, box[1] - box[0])
    beside = LEFT * w + widest + TICK_PX < BAR_LEFT * w
    bottom = BAR_BOTTOM * h + (0.0 if beside else min(BAR_HEIGHT * h, BAR_MAX_PX) + TITLE_PX)
    for row, actor in enumerate(actors):
        actor.SetPosition(LEFT, (bottom + ROW_PX * row) / h)
    return tuple(window.GetSize())


def add_bar(plotter, lut, title: str, colour, background="white"):
    """The horizontal colour bar of ``lut`` along the bottom of the view (once per scene),
    on a plate of ``background``."""
    bar = plotter.add_scalar_bar(
        title=title or " ", lookup_table=lut, vertical=False, position_x=BAR_LEFT, position_y=BAR_BOTTOM,
        width=BAR_WIDTH, height=BAR_HEIGHT, title_font_size=14, label_font_size=12, n_labels=3, fmt="%.3g",
        color=colour, render=False,
    )
    bar.SetMaximumHeightInPixels(90)
    # tick labels below the bar, the title above it: the title no longer sits on the middle tick label
    bar.SetTextPositionToPrecedeScalarBar()
    plate_bar(bar, background)
    return bar


def label_categories(bar, clim, bands: int) -> None:
    """Tick labels at the integers of a categorical field (``bands`` of them over ``clim``,
    labelled 10 at most), or the bar's own three for a continuous one."""
    bar.SetUseCustomLabels(bool(bands))
    bar.SetLabelFormat("%.0f" if bands else "%.3g")
    if bands:
        bar.SetCustomLabels(pv.convert_array(np.arange(clim[0] + 0.5, clim[1], -(-bands // 10), dtype=float)))
