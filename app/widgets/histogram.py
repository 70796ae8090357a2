"""Histogram of the displayed field, coloured like the cloud (matplotlib, GUI thread)."""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator


class Histogram(FigureCanvasQTAgg):
    """Distribution of the shown values; the colour limits are marked, values beyond
    them are gathered in the end bins, and NaNs are counted in the title."""

    def __init__(self, parent=None, bins: int = 60):
        self.figure = Figure(figsize=(3.2, 1.9), dpi=100, layout="constrained")
        super().__init__(self.figure)
        self.setParent(parent)
        self.setMinimumHeight(150)
        self.bins = bins
        self.ax = self.figure.add_subplot(111)
        self.counts = np.zeros(0)
        self.text_colour, self.axes_colour = "#222222", "#444444"
        self._style()

    def _style(self) -> None:
        ax = self.ax
        ax.tick_params(labelsize=7, colors=self.text_colour)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
        for side in ("bottom", "left"):
            ax.spines[side].set_color(self.axes_colour)
        ax.title.set_color(self.text_colour)

    def set_theme(self, theme) -> None:
        """Background and text colours of an :class:`app.theme.Theme`."""
        self.text_colour, self.axes_colour = theme.text, theme.axes
        self.figure.set_facecolor(theme.background)
        self.ax.set_facecolor(theme.background)
        self._style()
        self.draw_idle()

    def clear(self) -> None:
        """No data (a new cloud is being estimated)."""
        self.ax.clear()
        self._style()
        self.counts = np.zeros(0)
        self.draw_idle()

    def set_data(self, values: np.ndarray, *, clim: tuple[float, float], cmap: str, label: str) -> None:
        ax = self.ax
        ax.clear()
        self._style()
        values = np.asarray(values, dtype=float)
        finite = values[np.isfinite(values)]
        n_nan = values.size - finite.size
        lo, hi = float(clim[0]), float(clim[1])
        if finite.size == 0 or not hi > lo:
            self.counts = np.zeros(0)
            ax.text(0.5, 0.5, "no finite values", ha="center", va="center", transform=ax.transAxes, fontsize=8,
                    color=self.text_colour)
            self.draw_idle()
            return
        pad = 0.1 * (hi - lo)
        edges = np.linspace(lo - pad, hi + pad, self.bins + 1)
        counts, edges = np.histogram(np.clip(finite, edges[0], edges[-1]), bins=edges)
        centres = 0.5 * (edges[:-1] + edges[1:])
        colours = matplotlib.colormaps[cmap](np.clip((centres - lo) / (hi - lo), 0.0, 1.0))
        ax.bar(centres, counts, width=np.diff(edges), color=colours, linewidth=0)
        for x in (lo, hi):
            ax.axvline(x, color=self.axes_colour, linewidth=0.8, linestyle="--")
        ax.set_xlim(edges[0], edges[-1])
        ax.xaxis.set_major_locator(MaxNLocator(nbins=5))
        ax.set_yticks([])
        title = f"{label}   ({finite.size:,} pts"
        title += f", {n_nan:,} nan)" if n_nan else ")"
        ax.set_title(title, fontsize=8, color=self.text_colour)
        self.counts = counts
        self.draw_idle()
