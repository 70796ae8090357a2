"""Where the scans were taken from: a marker and a label at each scanner position of a cloud
read from an E57 or PTX file (:attr:`core.io.Cloud.viewpoints`), as CloudCompare shows its
sensors. They explain what the default orientation faces ("oriented toward the scanners") and
why the density falls with range. View › Scanner positions toggles them; GUI thread.
"""

from __future__ import annotations

import numpy as np

__all__ = ["positions", "show_scanners"]

_MARKS = "scanners"
_LABELS = "scanners-labels"  # the actor pyvista names for the labels of name="scanners"
#: a marker's radius, as a share of the cloud's bounding-box radius
_SIZE = 0.025
_COLOUR = "#d62728"


def positions(viewpoints) -> np.ndarray:
    """The distinct scanner positions (M, 3) of per-point ``viewpoints`` (N, 3) in the order
    they first appear (scan 0's first); an empty (0, 3) array for None."""
    if viewpoints is None or len(viewpoints) == 0:
        return np.empty((0, 3))
    views = np.asarray(viewpoints, dtype=float)
    _, first = np.unique(views, axis=0, return_index=True)
    return views[np.sort(first)]


def show_scanners(plotter, at: np.ndarray | None, radius: float) -> int:
    """Draw a sphere and a label ("scanner 1", ...) at each position of ``at`` (M, 3), or
    remove them (None or empty). Not pickable, and the camera is left where it is.
    Returns the number drawn."""
    import pyvista as pv  # here: app.source reads positions() without the 3D stack

    plotter.remove_actor(_MARKS, render=False)
    plotter.remove_actor(_LABELS, render=False)
    if at is None or len(at) == 0:
        return 0
    ball = pv.Sphere(radius=_SIZE * radius, theta_resolution=16, phi_resolution=12)
    marks = pv.PolyData(np.asarray(at, dtype=float)).glyph(geom=ball, scale=False, orient=False)
    plotter.add_mesh(marks, color=_COLOUR, name=_MARKS, pickable=False, reset_camera=False, render=False)
    names = [f"scanner {i + 1}" for i in range(len(at))]
    plotter.add_point_labels(np.asarray(at, dtype=float), names, name=_MARKS, font_size=12, show_points=False,
                             shape_opacity=0.6, always_visible=True, reset_camera=False, render=False,
                             pickable=False)
    return len(at)
