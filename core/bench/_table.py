"""Small helpers shared by the benchmarks: number formatting, text and markdown tables,
and error-vs-noise plots with one consistent style per method."""

from __future__ import annotations

import math
from typing import Sequence

#: colour and marker per method (the same in every benchmark plot)
_COLOURS = {
    "qp": "#1f77b4", "qn": "#ff7f0e", "cf": "#2ca02c", "cn": "#d62728",
    "ct": "#9467bd", "nf": "#8c564b", "nr": "#000000", "jet": "#7f7f7f",
}
_MARKERS = {"qp": "s", "qn": "o", "cf": "^", "cn": "v", "ct": "D", "nf": "P", "nr": "*", "jet": "x"}
#: methods whose fit uses point positions (dashed); the others fit normals only (solid)
POINT_FITTING = frozenset({"qp", "cf", "jet"})


def fmt(x, digits: int = 3) -> str:
    """``x`` with ``digits`` significant digits; plain notation from 1e-4 to 1e6."""
    if x is None or not math.isfinite(x):
        return "nan" if x is None or math.isnan(x) else ("inf" if x > 0 else "-inf")
    if x == 0:
        return "0"
    mag = math.floor(math.log10(abs(x)))
    if mag < -4 or mag >= 6:
        return f"{x:.{digits - 1}e}"
    return f"{x:.{max(digits - 1 - mag, 0)}f}"


def text_table(header: Sequence[str], rows: Sequence[Sequence[str]], *, title: str | None = None) -> str:
    """A plain-text table: first column left-aligned, the others right-aligned."""
    cells = [list(map(str, header))] + [list(map(str, r)) for r in rows]
    width = [max(len(r[j]) for r in cells) for j in range(len(header))]

    def line(r):
        return "  ".join(c.ljust(width[0]) if j == 0 else c.rjust(width[j]) for j, c in enumerate(r)).rstrip()

    out = [title] if title else []
    out += [line(cells[0]), "  ".join("-" * w for w in width)]
    out += [line(r) for r in cells[1:]]
    return "\n".join(out)


def markdown_table(header: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """A GitHub markdown table, numeric columns right-aligned."""
    out = ["| " + " | ".join(map(str, header)) + " |",
           "|" + "|".join([":---"] + ["---:"] * (len(header) - 1)) + "|"]
    out += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    return "\n".join(out)


def style(method: str, *, exact: bool = False) -> dict:
    """matplotlib line keywords for ``method``.

    Normal-fitting methods are solid, point-fitting ones dashed; ``exact`` (noise-free
    data with exact normals, a single value) is a thin dotted horizontal reference line.
    """
    colour = _COLOURS.get(method, "#17becf")
    if exact:
        return dict(color=colour, linestyle=":", linewidth=1.4, alpha=0.9)
    return dict(
        color=colour, linestyle="--" if method in POINT_FITTING else "-", linewidth=1.8,
        marker=_MARKERS.get(method, "o"), markersize=6 if method != "nr" else 9,
    )


def error_panels(path, x, panels, *, title: str, xlabel: str, logy: bool = True, ncol: int | None = None):
    """Save a row of error-vs-noise panels as a PNG.

    panels : list of dicts with keys ``ylabel``, ``title``, ``curves`` (list of
        ``(label, y, style)`` plotted against ``x``), ``hlines`` (list of
        ``(label, value, style)`` drawn across the whole x range) and optionally ``ymax``:
        the top of the y axis; values above it are listed in a box in the panel.
    One shared legend goes below the panels.
    """
    # Figure + Agg canvas directly: no pyplot, so no global backend switch (the app uses Qt)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import LogLocator, NullFormatter

    fig = Figure(figsize=(5.0 * len(panels), 4.6))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(panels), squeeze=False)
    handles = {}
    for ax, panel in zip(axes[0], panels):
        for label, y, kw in panel.get("curves", ()):
            (h,) = ax.plot(x, y, label=label, **kw)
            handles.setdefault(label, h)
        for label, value, kw in panel.get("hlines", ()):
            if value is not None and math.isfinite(value) and (value > 0 or not logy):
                h = ax.axhline(value, label=label, **kw)
                handles.setdefault(label, h)
        if logy:
            ax.set_yscale("log")
            ax.yaxis.set_major_locator(LogLocator(base=10, numticks=12))
            ax.yaxis.set_minor_locator(LogLocator(base=10, subs=range(2, 10), numticks=120))
            ax.yaxis.set_minor_formatter(NullFormatter())
        ymax = panel.get("ymax")
        if ymax is not None and math.isfinite(ymax):
            off = [f"{label}: {fmt(v)} (σ={xv:g})" for label, y, _ in panel.get("curves", ())
                   for xv, v in zip(x, y) if math.isfinite(v) and v > ymax]
            if off:
                lo, _ = ax.get_ylim()
                ax.set_ylim(lo, ymax)
                ax.text(0.02, 0.98, "off scale:\n" + "\n".join(off), transform=ax.transAxes, fontsize=7.5,
                        va="top", ha="left", bbox=dict(boxstyle="round", fc="white", ec="0.7", alpha=0.9))
        ax.set_xlabel(xlabel)
        ax.set_ylabel(panel["ylabel"])
        ax.set_title(panel.get("title", ""), fontsize=11)
        ax.set_xticks(list(x))
        ax.tick_params(axis="x", labelrotation=0, labelsize=8)
        ax.grid(True, which="major", alpha=0.35)
        ax.grid(True, which="minor", alpha=0.12)
    fig.suptitle(title, fontsize=12)
    n = len(handles)
    fig.legend(list(handles.values()), list(handles), loc="lower center", ncol=ncol or min(n, 8),
               frameon=False, fontsize=9)
    rows = math.ceil(n / (ncol or min(n, 8)))
    fig.tight_layout(rect=(0, 0.05 + 0.045 * rows, 1, 0.95))
    fig.savefig(path, dpi=110)
    return path
