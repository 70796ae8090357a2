"""paper_fig2_4_<surface>.png and paper_fig5_<surface>.png: error against noise per method."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._table import error_panels, style
from .config import FIG2_4, FIG2_4_EXACT, FIG5, FIG5_EXACT, QUANTITIES, QUANTITY_TITLES
from .experiment import SurfaceTable


def _ymax(tab: SurfaceTable, quantity: str, methods) -> float | None:
    """Top of the y axis: 4x the largest mean error that is not dominated by a few blown-up
    points (mean > 5x median); None (automatic) when nothing is blown up."""
    cols = [tab.methods.index(m) for m in methods if m in tab.methods]
    mean, median = tab.mean[quantity][:, cols], tab.median[quantity][:, cols]
    blown = mean > 5 * median
    if not blown.any() or blown.all():
        return None
    return float(4 * np.nanmax(np.where(blown, np.nan, mean)))


def plot(tab: SurfaceTable, out: Path) -> list[Path]:
    """The two figures of ``tab``: fig 2–4 (points vs normals) and fig 5 (CF/CT/NF/NR)."""
    x = list(tab.levels)
    xlabel = "noise σ  (fraction of mean point spacing)"
    paths = []
    for fname, est, exact, what in (
        (f"paper_fig2_4_{tab.surface}.png", FIG2_4, FIG2_4_EXACT, "fitting to points (dashed) vs normals (solid)"),
        (f"paper_fig5_{tab.surface}.png", FIG5, FIG5_EXACT, "CF, CT, NF, NR"),
    ):
        panels = []
        for q, _, ylabel in QUANTITIES:
            curves = [(m.upper(), tab.mean[q][:, tab.methods.index(m)], style(m))
                      for m in est if m in tab.methods]
            hlines = [(m.upper() + "E", tab.exact_mean[q][tab.methods.index(m)], style(m, exact=True))
                      for m in exact if m in tab.methods]
            panels.append(dict(ylabel=ylabel, title=QUANTITY_TITLES[q], curves=curves, hlines=hlines,
                               ymax=_ymax(tab, q, est)))
        title = (f"{tab.title[0].upper()}{tab.title[1:]}: {what} — N = {tab.n_points} points, k = {tab.k}, "
                 f"{tab.repeats} repeat(s); dotted: noise-free, exact normals (…E)")
        paths.append(error_panels(out / fname, x, panels, title=title, xlabel=xlabel, logy=True,
                                  ncol=len(est) + len(exact)))
    return paths
