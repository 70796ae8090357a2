"""Histogram of the displayed field, coloured like the cloud (matplotlib, GUI thread)."""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from PySide6.QtCore import QTimer
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from ..fields import subsample
from ..legend import band_map


#: Above this many values the bars are counted on a fixed random subset and scaled (the
#: bars' shape is the same to a pixel: ~0.2 % noise in a bin of 1 % of 200k); it saves the
#: GUI thread ~40 ms per recolour of a 1M-point cloud (np.clip + np.histogram, measured).
SAMPLE = 200_000
#: A changed histogram is drawn this many ms after the change and after the last 3D frame
#: (:meth:`Histogram.after_frame`), in a pass of the event loop of its own: the 3D view's
#: repaint of the same change runs first, input and timers are served, then the figure's
#: ~15-30 ms Agg draw. Drawn in the same pass as the 3D render, both added up into one GUI
#: stall (matplotlib's draw_idle posts its draw at 0 ms, which Qt delivered with the
#: repaint). Changes within the delay make one draw.
DRAW_DELAY_MS = 30
#: While a 3D frame is on its way (:attr:`Histogram.frame_due`) the draw waits for it, at most
#: this many delays (a hidden 3D view never renders).
MAX_WAITS = 10


class Histogram(FigureCanvasQTAgg):
    """Distribution of the shown values; the colour limits are marked, values beyond
    them are gathered in the end bins, and NaNs are counted in the title."""

    def __init__(self, parent=None, bins: int = 60):
        # fixed pixel margins (_place) instead of layout="constrained", which re-solves the
        # layout at every draw: 71 -> 33 ms of GUI thread a redraw (measured, 2 cores)
        self.figure = Figure(figsize=(3.2, 1.9), dpi=100)
        super().__init__(self.figure)
        self.setParent(parent)
        self.setMinimumHeight(150)
        self.bins = bins
        self.ax = self.figure.add_subplot(111)
        self.counts = np.zeros(0)
        self.text_colour, self.axes_colour = "#222222", "#444444"
        self._draw_timer = QTimer(self)
        self._draw_timer.setSingleShot(True)
        self._draw_timer.setInterval(DRAW_DELAY_MS)
        self._draw_timer.timeout.connect(self._on_timer)
        self._waits = 0
        #: set by the window: whether a 3D frame has been asked for and not rendered yet
        self.frame_due = lambda: False
        # made once, updated in place by set_data
        self._bars = list(self.ax.bar(np.arange(bins), np.zeros(bins), width=1.0, linewidth=0))
        self._limits = [self.ax.axvline(x, linewidth=0.8, linestyle="--") for x in (0.0, 1.0)]
        self._message = self.ax.text(0.5, 0.5, "", ha="center", va="center", transform=self.ax.transAxes,
                                     fontsize=8, visible=False)
        self.ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
        self.ax.set_yticks([])
        self._style()
        self._place()
        self._show_bars(False)

    #: Margins in pixels around the axes: tick labels (7 pt) below, the title (8 pt) above,
    #: room for half a tick label at the sides.
    MARGINS_PX = dict(left=16, right=16, bottom=26, top=22)

    def draw_later(self) -> None:
        """Draw the figure in a later pass of the event loop (:data:`DRAW_DELAY_MS`);
        several changes before it make one draw."""
        if not self._draw_timer.isActive():
            self._waits = 0
            self._draw_timer.start()

    def _on_timer(self) -> None:
        if self.frame_due() and self._waits < MAX_WAITS:
            self._waits += 1  # the frame first: after_frame starts the delay again
            self._draw_timer.start()
            return
        self.draw()

    def after_frame(self) -> None:
        """A 3D frame was just rendered: a pending draw waits :data:`DRAW_DELAY_MS` from now,
        so that the event loop serves input and timers between the two."""
        if self._draw_timer.isActive():
            self._draw_timer.start()

    @property
    def draw_pending(self) -> bool:
        return self._draw_timer.isActive()

    def flush(self) -> None:
        """Draw now if a draw is pending (before a screenshot of the window)."""
        if self._draw_timer.isActive():
            self._draw_timer.stop()
            self.draw()

    def _place(self) -> None:
        """The axes inside :data:`MARGINS_PX` of the figure, whatever its size."""
        w, h = max(self.figure.bbox.width, 60.0), max(self.figure.bbox.height, 60.0)
        m = self.MARGINS_PX
        self.figure.subplots_adjust(left=m["left"] / w, right=1.0 - m["right"] / w, bottom=m["bottom"] / h,
                                    top=1.0 - m["top"] / h)

    def resizeEvent(self, event) -> None:  # noqa: N802 - Qt's name
        super().resizeEvent(event)
        self._place()

    def _style(self) -> None:
        ax = self.ax
        ax.tick_params(labelsize=7, colors=self.text_colour)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
        for side in ("bottom", "left"):
            ax.spines[side].set_color(self.axes_colour)
        ax.title.set_color(self.text_colour)
        self._message.set_color(self.text_colour)

    def set_theme(self, theme) -> None:
        """Background and text colours of an :class:`app.theme.Theme`."""
        self.text_colour, self.axes_colour = theme.text, theme.axes
        self.figure.set_facecolor(theme.background)
        self.ax.set_facecolor(theme.background)
        self._style()
        self.draw_later()

    def clear(self) -> None:
        """No data (a new cloud is being estimated)."""
        self._show_bars(False)
        self.ax.set_title("")
        self.counts = np.zeros(0)
        self.draw_later()

    def _show_bars(self, on: bool, message: str = "") -> None:
        for artist in (*self._bars, *self._limits):
            artist.set_visible(on)
        self._message.set_text(message)
        self._message.set_visible(bool(message))

    def set_data(self, values: np.ndarray, *, clim: tuple[float, float], cmap: str, label: str, bands: int = 0) -> None:
        """Show the distribution of ``values`` with the colour limits ``clim`` marked, coloured
        by ``cmap`` (sampled at ``bands`` colours for a categorical field, as the cloud's are).

        The bars, limit lines and ticks are made once and updated in place (``ax.clear()``
        and new bars cost the GUI thread ~0.1 s a change; updating them a few ms)."""
        values = np.asarray(values, dtype=float)
        n_shown = int(np.count_nonzero(~np.isnan(values)))  # +-inf (an outlier score's lone points) fall in the end bars
        n_nan = values.size - n_shown
        shown = subsample(values, SAMPLE)
        shown = shown[~np.isnan(shown)]
        lo, hi = float(clim[0]), float(clim[1])
        if shown.size == 0 or not hi > lo:
            self.counts = np.zeros(0)
            self._show_bars(False, "no values")
            self.ax.set_title("")
            self.draw_later()
            return
        pad = 0.1 * (hi - lo)
        # a bin count and range, not an array of edges: numpy's equal-bin path (no sort of the values)
        counts, edges = np.histogram(np.clip(shown, lo - pad, hi + pad), bins=self.bins, range=(lo - pad, hi + pad))
        if values.size > SAMPLE:  # counted on a fixed random subset: scaled to the whole
            counts = np.rint(counts * (n_shown / shown.size)).astype(np.int64)
        centres = 0.5 * (edges[:-1] + edges[1:])
        colormap = band_map(cmap, bands) if bands else matplotlib.colormaps[cmap]
        colours = colormap(np.clip((centres - lo) / (hi - lo), 0.0, 1.0))
        width = edges[1] - edges[0]
        for bar, x0, count, colour in zip(self._bars, edges[:-1], counts, colours):
            bar.set_bounds(x0, 0.0, width, count)
            bar.set_facecolor(colour)
        for line, x in zip(self._limits, (lo, hi)):
            line.set_xdata([x, x])
            line.set_color(self.axes_colour)
        self._show_bars(True)
        self.ax.set_xlim(edges[0], edges[-1])
        self.ax.set_ylim(0.0, 1.05 * max(int(counts.max()), 1))
        title = f"{label}   ({n_shown:,} pts"
        title += f", {n_nan:,} nan)" if n_nan else ")"
        self.ax.set_title(title, fontsize=8, color=self.text_colour)
        self.counts = counts
        self.draw_later()
