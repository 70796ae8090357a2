"""The Teach dock's words: the picked point and the cloud's Gauss-Bonnet check (HTML)."""

from __future__ import annotations

import html

import numpy as np

import core
from core.point_types import TYPE_TEXT

__all__ = ["point_text", "cloud_text"]


def point_text(fit, theta_deg: float, res, index) -> str:
    if fit is None:
        if res is not None and index is not None and 0 <= index < len(res.points) and not res.valid[index]:
            return f"Point {index} is invalid (degenerate neighbourhood): it has no frame."
        return "Pick a point (click on the cloud) to see its frame, sections and Euler plot."
    kt = float(fit.normal_curvature(np.radians(theta_deg)))
    desc = html.escape(TYPE_TEXT[fit.kind])  # "K < 0" is not a tag

    def radius(k):
        return f"{1 / abs(k):.3g}" if k else "∞"

    return (f"<b>Point {fit.index}: {fit.kind}</b> — {desc}<br>"
            f"k1 = {fit.k1:.4g} (radius {radius(fit.k1)}), k2 = {fit.k2:.4g} (radius {radius(fit.k2)})<br>"
            f"K = k1·k2 = {fit.k1 * fit.k2:.4g}, H = (k1+k2)/2 = {0.5 * (fit.k1 + fit.k2):.4g}<br>"
            f"<span style='color:#d95f02'>k<sub>n</sub>({theta_deg:.0f}°) = k1 cos²θ + k2 sin²θ = {kt:.4g}</span>"
            f" &nbsp;({len(fit.neighbours)} neighbours)<br>"
            f"Gauss map: area of the nearest normals on the sphere / their area on the surface = "
            f"{fit.gauss_map_ratio():.3g} ≈ |K|")


def cloud_text(maths, failure: str | None = None) -> str:
    """Gauss-Bonnet, the point types and the lines in words; ``failure``: why the cloud-wide
    maths gave nothing (None while they run)."""
    if maths is None and failure:
        return ("<b>Gauss–Bonnet, lines of curvature and point types could not be computed</b>: "
                + html.escape(failure))
    if maths is None:
        return "<i>Gauss–Bonnet, lines of curvature and point types: computing…</i>"
    notes = maths.notes
    return "<br>".join((_gauss_bonnet_text(maths.gauss_bonnet, notes.get("gauss_bonnet")),
                        _types_text(maths.types, notes.get("types")),
                        _lines_text(maths.lines, notes.get("lines"))))


def _gauss_bonnet_text(gb, note) -> str:
    if gb is None:
        return f"<b>Gauss–Bonnet</b>: {html.escape(note or 'not computed')}."
    text = f"<b>Gauss–Bonnet</b>: ∫K dA = {gb.total:.4g} over an area of {gb.area:.4g}"
    if gb.closed:
        return text + f"; χ = ∫K dA / 2π = <b>{gb.chi:.3f}</b> (sphere 2, torus 0)"
    return text + f"; the cloud has a boundary ({int(gb.boundary.sum())} points): χ needs a closed surface"


def _types_text(types, note) -> str:
    if types is None:
        return f"Point types could not be computed: {html.escape(note or 'unknown error')}."
    shares = ", ".join(f"{name} {np.mean(types == i):.0%}" for i, name in enumerate(core.TYPE_NAMES)
                       if np.any(types == i))
    return f"Point types: {shares or 'none (no valid point)'}."


def _lines_text(lines, note) -> str:
    count = sum(len(v) for v in lines.values())
    if note:
        return f"{count} lines of curvature traced; tracing failed: {html.escape(note)}."
    return f"{count} lines of curvature traced."
