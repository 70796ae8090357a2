"""Teaching mode: the Darboux frame, normal sections, Dupin indicatrix, Euler's formula,
lines of curvature, point types, the Gauss map and Gauss-Bonnet, live on the cloud.

The window calls :func:`install_teach` once; everything else lives in this package. Importing
it does not import Qt (the command line parses its flags first).
"""

from __future__ import annotations

from .examples import EXAMPLES, OVERLAYS

__all__ = ["install_teach", "OVERLAYS", "EXAMPLES"]


def install_teach(window):
    """Add the Teach dock (hidden) and its menu to a :class:`app.window.MainWindow`; returns
    the :class:`app.teach.mode.Teach` (GUI thread)."""
    from .mode import Teach

    return Teach(window)
