"""Camera framing and on-screen point size of a cloud (GUI thread, VTK renderer calls).

The camera is fitted to the cloud's projected points, not to its bounding sphere, so a
cube or a small cloud fills the part of the view above the colour bar. The sprite size
follows the mean point spacing as it appears on screen, so a sparse cloud is not dust
and a dense one shows no see-through holes (CloudCompare's "adaptive" point size).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["look_from", "VIEWS", "projection", "free_region", "fit_to_region", "cloud_spacing", "sprite_size",
           "FIT_SAMPLE"]

#: Points projected per fitting step: the cloud's extreme points along 13 directions plus
#: a random subset (app/geometry.py); 4000 projections cost < 1 ms.
FIT_SAMPLE = 4000
#: Free margin around the fitted cloud, as a fraction of the free region (each side).
FIT_PAD = 0.04
#: Top of the colour bar: position_y + height in the scene (0.03 + 0.075 of the view),
#: its height capped at the bar's SetMaximumHeightInPixels (90 px).
BAR_BOTTOM, BAR_HEIGHT, BAR_MAX_PX = 0.03, 0.075, 90.0
#: Left edge and width of the colour bar, viewport fractions (the glyph legend keeps clear of it).
BAR_LEFT, BAR_WIDTH = 0.25, 0.5
#: Sprite diameter over the point spacing on screen. The spacing is the mean distance to
#: the 3rd nearest neighbour, about 1 / sqrt(density) for a grid (1.0) and for a random
#: sampling (0.94) alike, whereas the nearest-neighbour distance is 1.0 vs 0.5. Discs of
#: diameter 1.7 / sqrt(density) cover a grid and 90 % of a random sampling (1 - exp(-pi
#: 1.7^2 / 4)); the back of a closed surface fills most of the rest (looked at: cube,
#: torus, 300-point sphere, bunny).
SPRITE_OVERLAP = 1.7
#: The "Point size" control's default: the user's size divided by this scales the sprites.
DEFAULT_SIZE = 5.0
SPRITE_MIN, SPRITE_MAX = 1.5, 48.0
#: Lines drawn on the surface (direction glyphs, lines of curvature) float this many drawn
#: spacings above the point sprites' tops (:func:`overlay_lift`)
LIFT_MARGIN = 0.25
#: Spacing estimate: 3rd-neighbour distances of SPACING_QUERIES random points against
#: the whole cloud (tree build on 1M points 0.19 s, 20k queries 0.03 s on this VM). Above
#: SPACING_TREE points the tree holds a random subset and the distance is scaled by
#: sqrt(m / N) (a surface's spacing goes as 1 / sqrt(density)).
SPACING_QUERIES, SPACING_TREE = 20_000, 2_000_000


#: Preset views: direction from the cloud to the camera, and the up vector.
VIEWS = {
    "front": ([0.35, 0.25, 1.0], [0, 1, 0]),
    "oblique": ([0.55, -1.0, 0.75], [0, 0, 1]),
    "xy": ([0, 0, 1], [0, 1, 0]),
    "xz": ([0, -1, 0], [0, 0, 1]),
    "yz": ([1, 0, 0], [0, 0, 1]),
}


def look_from(renderer, centre: np.ndarray, radius: float, view: str) -> None:
    """Point the camera at the cloud's box ``centre`` from the preset ``view`` (see VIEWS),
    ``radius`` (half the box diagonal) times 3.2 away."""
    centre = np.asarray(centre, dtype=float)
    radius = float(radius) or 1.0
    direction, up = (np.asarray(v, dtype=float) for v in VIEWS[view])
    direction /= np.linalg.norm(direction)
    cam = renderer.GetActiveCamera()
    cam.SetFocalPoint(*centre)
    cam.SetPosition(*(centre + direction * radius * 3.2))
    cam.SetViewUp(*up)


#: Pixels: a view narrower or lower than this is not framed for (:func:`narrowest`).
MIN_VIEW_PX = 48


def projection(renderer, points: np.ndarray):
    """Display coordinates (x, y in pixels, origin bottom-left) and depth of points."""
    cam = renderer.GetActiveCamera()
    aspect = renderer.GetTiledAspectRatio()
    vtk_m = cam.GetCompositeProjectionTransformMatrix(aspect, -1.0, 1.0)
    m = np.array([[vtk_m.GetElement(i, j) for j in range(4)] for i in range(4)])
    hom = np.c_[points, np.ones(len(points))] @ m.T
    w = hom[:, 3:4]
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc = hom[:, :3] / w
    vx0, vy0, vx1, vy1 = renderer.GetViewport()
    width, height = renderer.GetRenderWindow().GetSize()
    x = (vx0 + (ndc[:, 0] + 1.0) * 0.5 * (vx1 - vx0)) * width
    y = (vy0 + (ndc[:, 1] + 1.0) * 0.5 * (vy1 - vy0)) * height
    return x, y, ndc[:, 2]


def _viewport_px(renderer) -> tuple[float, float, float, float]:
    """(x0, y0, width, height) of the renderer's viewport in pixels."""
    vx0, vy0, vx1, vy1 = renderer.GetViewport()
    width, height = renderer.GetRenderWindow().GetSize()
    return vx0 * width, vy0 * height, max((vx1 - vx0) * width, 1.0), max((vy1 - vy0) * height, 1.0)


def free_region(renderer, inset: float = 0.0) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) in display pixels of the view above the colour bar, less a pad
    and ``inset`` pixels (half a sprite: the points are drawn as discs around the centres)."""
    x0, y0, w, h = _viewport_px(renderer)
    bar_top = y0 + BAR_BOTTOM * h + min(BAR_HEIGHT * h, BAR_MAX_PX)
    top = y0 + h - (bar_top - y0)  # as much room above as the bar takes below: centred, clear of the title
    pad_x, pad_y = FIT_PAD * w, FIT_PAD * (top - bar_top)
    pad_x, pad_y = pad_x + inset, pad_y + inset
    return x0 + pad_x, bar_top + pad_y, x0 + w - pad_x, top - pad_y


def narrowest(renderers):
    """Of renderers sharing one camera, the one whose free region is narrowest for its
    height: a cloud framed there fits in the others, centred too (every free region is).
    Views squeezed below :data:`MIN_VIEW_PX` do not count (the first one does if all are):
    a compare view a splitter left 0 px wide framed the cloud off the main view."""
    def aspect(renderer):
        x0, y0, x1, y1 = free_region(renderer)
        return (x1 - x0) / max(y1 - y0, 1.0)

    usable = [r for r in renderers if min(_viewport_px(r)[2:]) >= MIN_VIEW_PX] or list(renderers)[:1]
    return min(usable, key=aspect)


def fit_to_region(renderer, sample: np.ndarray, region=None, steps: int = 4) -> None:
    """Dolly and pan the camera so the projected ``sample`` fills ``region`` (display px).

    Keeps the viewing direction and the view angle. A perspective projection is not
    linear in the dolly, so a few steps of "scale, then centre" converge (< 1 % after 3).
    """
    if len(sample) == 0:
        return
    cam = renderer.GetActiveCamera()
    rx0, ry0, rx1, ry1 = free_region(renderer) if region is None else region
    for _ in range(steps):
        renderer.ResetCameraClippingRange()
        x, y, _ = projection(renderer, sample)
        if not (np.isfinite(x).all() and np.isfinite(y).all()):
            return
        extent = max((x.max() - x.min()) / (rx1 - rx0), (y.max() - y.min()) / (ry1 - ry0), 1e-9)
        cam.Dolly(float(np.clip(1.0 / extent, 0.2, 5.0)))
        renderer.ResetCameraClippingRange()
        x, y, _ = projection(renderer, sample)
        _pan(renderer, 0.5 * (rx0 + rx1) - 0.5 * (x.min() + x.max()), 0.5 * (ry0 + ry1) - 0.5 * (y.min() + y.max()))
    renderer.ResetCameraClippingRange()


def _pan(renderer, dx: float, dy: float) -> None:
    """Move the camera (focal point and position) so the focal plane shifts by (dx, dy) px."""
    cam = renderer.GetActiveCamera()
    _, _, _, h = _viewport_px(renderer)
    position, focal = np.array(cam.GetPosition()), np.array(cam.GetFocalPoint())
    forward = focal - position
    distance = np.linalg.norm(forward)
    up = np.array(cam.GetViewUp())
    right = np.cross(forward / distance, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward / distance)
    per_px = 2.0 * distance * np.tan(np.radians(cam.GetViewAngle()) / 2.0) / h
    shift = -(dx * right + dy * up) * per_px  # the scene moves by +d when the camera moves by -d
    cam.SetPosition(*(position + shift))
    cam.SetFocalPoint(*(focal + shift))


def cloud_spacing(points: np.ndarray) -> float:
    """Mean distance to the 3rd nearest neighbour, ~1 / sqrt(density) on a surface whether
    sampled on a grid or at random (on a subsample for a huge cloud); 0 if unknown."""
    pts = points[np.isfinite(points).all(axis=1)]
    n = len(pts)
    if n < 2:
        return 0.0
    rng = np.random.default_rng(0)
    m = min(n, SPACING_TREE)
    tree = pts if m == n else pts[rng.choice(n, size=m, replace=False)]
    query = tree if m <= SPACING_QUERIES else tree[rng.choice(m, size=SPACING_QUERIES, replace=False)]
    d, _ = cKDTree(tree, balanced_tree=False, compact_nodes=False).query(query, k=min(4, m))
    nearest = d[:, -1][np.isfinite(d[:, -1]) & (d[:, -1] > 0)]
    return float(np.mean(nearest) * np.sqrt(m / n)) if len(nearest) else 0.0


def sprite_size(renderer, centre: np.ndarray, spacing: float, user_size: float, ceiling: float | None = None) -> float:
    """Sprite diameter in pixels: the spacing seen at ``centre``, times the user's factor.

    ``ceiling`` (px at the default factor) is the size the fitted view gave: zooming in past
    the fit spreads the points apart instead of growing them, so close-ups (a picked point's
    frame, normal sections) show individual points, not a wall of spheres over the overlays."""
    if spacing <= 0:
        return float(user_size)
    cam = renderer.GetActiveCamera()
    _, _, _, h = _viewport_px(renderer)
    if cam.GetParallelProjection():
        world_height = 2.0 * cam.GetParallelScale()
    else:
        depth = float(np.dot(np.asarray(centre) - np.array(cam.GetPosition()), _forward(cam)))
        world_height = 2.0 * max(depth, 1e-12) * np.tan(np.radians(cam.GetViewAngle()) / 2.0)
    px = SPRITE_OVERLAP * spacing * h / world_height * (user_size / DEFAULT_SIZE)
    top = SPRITE_MAX if ceiling is None else min(SPRITE_MAX, max(ceiling, SPRITE_MIN))
    return float(np.clip(px, SPRITE_MIN, top * user_size / DEFAULT_SIZE))


def overlay_lift(spacing: float, user_size: float) -> float:
    """How far along the normal a line drawn on the surface must float to clear the point
    sprites, in world units: their radius (:data:`SPRITE_OVERLAP` / 2 of the drawn points'
    ``spacing`` at the fitted view or farther; less when zoomed in), scaled by the user's
    point size, plus :data:`LIFT_MARGIN`. Below it the sprites' depth hides the line: the
    glyphs at 0.6 spacing and the lines of curvature at 0.7 did not show at all between
    sprites 1.7 spacings wide."""
    return (0.5 * SPRITE_OVERLAP * user_size / DEFAULT_SIZE + LIFT_MARGIN) * spacing


def _forward(cam) -> np.ndarray:
    d = np.array(cam.GetFocalPoint()) - np.array(cam.GetPosition())
    return d / np.linalg.norm(d)
