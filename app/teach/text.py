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


def cloud_text(maths) -> str:
    if maths is None:
        return "<i>Gauss–Bonnet, lines of curvature and point types: computing…</i>"
    gb = maths.gauss_bonnet
    text = (f"<b>Gauss–Bonnet</b>: ∫K dA = {gb.total:.4g} over an area of {gb.area:.4g}")
    if gb.closed:
        text += f"; χ = ∫K dA / 2π = <b>{gb.chi:.3f}</b> (sphere 2, torus 0)"
    else:
        text += f"; the cloud has a boundary ({int(gb.boundary.sum())} points): χ needs a closed surface"
    shares = ", ".join(f"{name} {np.mean(maths.types == i):.0%}" for i, name in enumerate(core.TYPE_NAMES)
                       if np.any(maths.types == i))
    lines = sum(len(v) for v in maths.lines.values())
    return text + f"<br>Point types: {shares}.<br>{lines} lines of curvature traced."
