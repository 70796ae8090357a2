"""The two small matplotlib figures of the Teach dock (GUI thread): Euler's formula at the
picked point, and the Gauss map of the cloud.

Both draw into a :class:`matplotlib.figure.Figure` that :func:`save_figure` can write as
PNG, SVG or PDF for slides.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
from matplotlib.figure import Figure
from PySide6.QtCore import QSize
from PySide6.QtWidgets import QSizePolicy

from ..glyphs import FRAME_COLOURS
from .overlays import MEASURED_COLOUR, THETA_COLOUR

__all__ = ["EulerPlot", "GaussMapPlot", "draw_euler", "draw_gauss_map", "save_figure", "FIGURE_FORMATS"]

FIGURE_FORMATS = (".png", ".svg", ".pdf")
#: points drawn on the Gauss map (a random subset beyond this: the sphere is full already)
GAUSS_MAP_POINTS = 6000


def draw_euler(fig: Figure, fit, theta_deg: float) -> None:
    """k_n(theta) = k1 cos^2 theta + k2 sin^2 theta over [0, 180) degrees, the neighbours'
    measured normal curvatures as dots, k1 / k2 / the current theta marked."""
    fig.clear()
    ax = fig.add_subplot(111)
    if fit is None:
        ax.text(0.5, 0.5, "pick a point", ha="center", va="center", transform=ax.transAxes, color="#666666")
        ax.set_axis_off()
        return
    t = np.linspace(0, np.pi, 361)
    th, k = fit.measured_curvatures()
    ax.scatter(np.degrees(th), k, s=9, color=MEASURED_COLOUR, alpha=0.55, lw=0,
               label="neighbours: <n_j - n_p, t_j> / |t_j|²")
    ax.plot(np.degrees(t), fit.normal_curvature(t), color=THETA_COLOUR, lw=2.2,
            label="Euler: k1 cos²θ + k2 sin²θ")
    ax.axhline(fit.k1, color=FRAME_COLOURS["e1"], lw=1, ls="--", label=f"k1 = {fit.k1:.3g} (θ = 0°)")
    ax.axhline(fit.k2, color=FRAME_COLOURS["e2"], lw=1, ls="--", label=f"k2 = {fit.k2:.3g} (θ = 90°)")
    ax.axhline(0, color="#bbbbbb", lw=0.8)
    kt = float(fit.normal_curvature(np.radians(theta_deg)))
    ax.plot([theta_deg], [kt], "o", color=THETA_COLOUR, ms=8, mec="black", zorder=5)
    ax.set_xlim(0, 180)
    ax.set_xticks([0, 45, 90, 135, 180])
    span = max(abs(fit.k1), abs(fit.k2), 1e-12)
    lo, hi = np.percentile(k, [3, 97]) if len(k) else (fit.k2, fit.k1)
    ax.set_ylim(min(lo, fit.k2, 0) - 0.25 * span, max(hi, fit.k1, 0) + 0.25 * span)
    ax.set_xlabel("direction θ from e1 [°]")
    ax.set_ylabel("normal curvature k_n")
    ax.set_title(f"point {fit.index} ({fit.kind}):  k_n({theta_deg:.0f}°) = {kt:.3g}", fontsize=10)
    ax.grid(alpha=0.25)
    # laid out again at every draw (a canvas resized with its dock keeps the legend inside)
    fig.set_layout_engine("constrained", h_pad=0.02, w_pad=0.02)
    fig.legend(*ax.get_legend_handles_labels(), fontsize=7, loc="outside lower center", ncol=2, frameon=False)


def draw_gauss_map(fig: Figure, normals, colours, highlight=None, picked=None) -> None:
    """Each point's normal on the unit sphere (orthographic, two hemispheres seen from +z and
    -z), coloured like the main view; the picked neighbourhood's normals highlighted. The
    ratio of their spread on the sphere to the neighbourhood's area is |K|."""
    fig.clear()
    if normals is None or not len(normals):
        return
    nrm = np.asarray(normals, dtype=float)
    ok = np.isfinite(nrm).all(axis=1)
    keep = np.flatnonzero(ok)
    if len(keep) > GAUSS_MAP_POINTS:
        keep = np.sort(np.random.default_rng(0).choice(keep, GAUSS_MAP_POINTS, replace=False))
    for i, (sign, title) in enumerate(((1, "upper hemisphere (n_z > 0)"), (-1, "lower hemisphere (n_z < 0)"))):
        ax = fig.add_subplot(1, 2, i + 1)
        ax.add_patch(_circle())
        side = keep[sign * nrm[keep, 2] >= 0]
        ax.scatter(sign * nrm[side, 0], nrm[side, 1], s=3, c=colours[side] if colours is not None else "#555555",
                   lw=0)
        if highlight is not None and len(highlight):
            hl = np.asarray(highlight)
            hl = hl[ok[hl] & (sign * nrm[hl, 2] >= 0)]
            ax.scatter(sign * nrm[hl, 0], nrm[hl, 1], s=14, facecolor="#ffd92f", edgecolor="black", lw=0.4)
        if picked is not None and ok[picked] and sign * nrm[picked, 2] >= 0:
            ax.plot(sign * nrm[picked, 0], nrm[picked, 1], "o", color="#e7298a", ms=7, mec="black")
        ax.set_xlim(-1.05, 1.05)
        ax.set_ylim(-1.05, 1.05)
        ax.set_aspect("equal")
        ax.set_axis_off()
        ax.set_title(title, fontsize=8)
    fig.suptitle("Gauss map: each point's normal on the unit sphere", fontsize=9)


def _circle():
    from matplotlib.patches import Circle

    return Circle((0, 0), 1.0, facecolor="#f4f4f4", edgecolor="#999999", lw=0.8)


def save_figure(fig: Figure, path, *, dpi: int = 300) -> Path:
    """Write ``fig`` as PNG (at ``dpi``), SVG or PDF, chosen by the suffix; atomically."""
    from core.io.atomic import atomic_write

    path = Path(path)
    if path.suffix.lower() not in FIGURE_FORMATS:
        raise ValueError(f"figure path {str(path)!r}: suffix must be one of {', '.join(FIGURE_FORMATS)}")
    with atomic_write(path) as f:
        fig.savefig(f, dpi=dpi, format=path.suffix[1:].lower(), bbox_inches="tight")
    return path


#: The plots' smallest height (px): the Euler plot's axes, title, labels and legend.
MIN_HEIGHT = 240


class _Canvas(FigureCanvasQTAgg):
    """A figure that takes the height its slot has. Its minimum is a size *hint*: a
    minimum height alone (280, before) is not seen by the tab widget holding it, whose page
    then gave it less and cut off its bottom, the Euler plot's legend (1440x900 window)."""

    def __init__(self, size=(4.2, 3.4)):
        super().__init__(Figure(figsize=size, dpi=90))
        self.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Expanding)

    def minimumSizeHint(self) -> QSize:  # noqa: N802 - Qt's name
        return QSize(200, MIN_HEIGHT)


class EulerPlot(_Canvas):
    """Euler's formula at the picked point (GUI thread)."""

    def show_fit(self, fit, theta_deg: float) -> None:
        draw_euler(self.figure, fit, theta_deg)
        self.draw_idle()


class GaussMapPlot(_Canvas):
    """The Gauss map of the cloud (GUI thread)."""

    def show_map(self, normals, colours, highlight=None, picked=None) -> None:
        draw_gauss_map(self.figure, normals, colours, highlight, picked)
        self.draw_idle()
