"""accuracy_<shape>.png: error against noise, one curve per column."""

from __future__ import annotations

import math
from pathlib import Path

from .cases import ShapeTable
from .config import APSSE, LABELS, NFE, QUANTITIES, QUANTITY_TITLES, REF_LABELS, _styles


def _panels(path, x, panels, *, title, xlabel, ncol):
    """Like ``_table.error_panels`` (log y, one shared legend) but with labelled 1-2-5 ticks,
    so that narrow log ranges still show readable numbers."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    fig = Figure(figsize=(5.4 * len(panels), 4.9))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(panels), squeeze=False)[0]
    handles = {}
    for ax, panel in zip(axes, panels):
        for label, y, kw in panel["curves"]:
            (h,) = ax.plot(x, y, label=label, **kw)
            handles.setdefault(label, h)
        for label, value, kw in panel.get("hlines", ()):
            if value is not None and math.isfinite(value) and value > 0:
                handles.setdefault(label, ax.axhline(value, label=label, **kw))
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=20))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_locator(LogLocator(base=10, subs=(3.0, 4.0, 6.0, 7.0, 8.0, 9.0), numticks=100))
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.tick_params(axis="y", labelsize=8)
        ax.set_xticks(list(x))
        ax.set_xticklabels([f"{v:g}" for v in x], fontsize=8)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(panel["ylabel"])
        ax.set_title(panel["title"], fontsize=11)
        ax.grid(True, which="major", alpha=0.35)
        ax.grid(True, which="minor", alpha=0.12)
    fig.suptitle(title, fontsize=12)
    n = len(handles)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=ncol, frameon=False, fontsize=9)
    rows = math.ceil(n / ncol)
    fig.tight_layout(rect=(0, 0.05 + 0.045 * rows, 1, 0.95))
    fig.savefig(path, dpi=110)
    return path


def plot(tab: ShapeTable, out: Path) -> Path:
    """accuracy_<shape>.png: K, H and e1 error vs noise, one curve per column."""
    st = _styles()
    x = list(tab.levels)
    panels = []
    for q, _, ylabel in QUANTITIES:
        curves = [(LABELS[c], tab.err[c][q], st[c]) for c in tab.columns]
        hlines = [(REF_LABELS[r], tab.ref[r][q], st[r]) for r in (NFE, APSSE) if r in tab.ref]
        panels.append(dict(ylabel=ylabel, title=QUANTITY_TITLES[q], curves=curves, hlines=hlines))
    title = (f"{tab.title[0].upper()}{tab.title[1:]}: error vs noise — 'best' = k or scale chosen with the truth "
             "(oracle); dotted: σ=0 with exact normals")
    n = len(tab.columns) + len(tab.ref)
    return _panels(out / f"accuracy_{tab.shape}.png", x, panels, title=title,
                   xlabel="noise σ  (fraction of mean point spacing)", ncol=min(n, 8))
