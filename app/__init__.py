"""Darboux viewer: a thin Qt/PyVista layer over :mod:`core`.

Layout (one responsibility per module):

- :mod:`app.state`    the one observable state object (parameters the user set)
- :mod:`app.source`   the loaded cloud (file or synthetic shape); no Qt
- :mod:`app.fields`   displayable scalar fields and colour limits; numpy only
- :mod:`app.worker`   frozen requests, the estimate worker thread and its controller
- :mod:`app.scene`    every pyvista/VTK call (GUI thread only)
- :mod:`app.errors`   the one notifier that errors reach the user through
- :mod:`app.window`   the main window, composition only
- :mod:`app.widgets`  one small widget per file, each bound to the state
- :mod:`app.glyphs`   ± segment geometry for direction glyphs; numpy only
- :mod:`app._refguard` works around a PySide6 6.12 reference-count bug
"""

from pathlib import Path

__all__ = ["RESOURCES", "DEFAULT_CLOUD", "ICON"]

#: Bundled data, next to the package (``<repo>/resources``).
RESOURCES = Path(__file__).resolve().parent.parent / "resources"
#: The cloud opened when no file is given: the Stanford bunny.
DEFAULT_CLOUD = RESOURCES / "bunny.ply"
#: The application icon.
ICON = RESOURCES / "darboux.svg"
