"""Darboux viewer: a thin Qt/PyVista layer over :mod:`core`.

Layout (one responsibility per module):

- :mod:`app.state`    the one observable state object (parameters the user set)
- :mod:`app.source`   the loaded cloud (file or synthetic shape); no Qt
- :mod:`app.fields`   displayable scalar fields and colour limits; numpy only
- :mod:`app.request`  the frozen estimate request, built from the state (its keys derived once)
- :mod:`app.worker`   the estimate pipeline as the worker thread runs it (preview, then full)
- :mod:`app.estimator` GUI-thread controller: generations, stale results dropped, cancel
- :mod:`app.loader`   reading files / generating shapes on a job thread
- :mod:`app.jobs`     daemon job threads (never block the exit, never abort it)
- :mod:`app.launch`   the ``darboux`` command: Ctrl-C quiet from the first instant, then the viewer;
  :mod:`app.hard_exit` the process ended at once (Ctrl-C before the loop, a job left at exit)
- :mod:`app.preview`  the fast first picture: k = 15 on a subsample, spread to every point
- :mod:`app.scene`    every pyvista/VTK call (GUI thread only); :mod:`app.lod` level of detail
- :mod:`app.errors`   the one notifier that errors reach the user through
- :mod:`app.window`   the main window, composition; :mod:`app.layout` its docks;
  :mod:`app.actions` menus, dialogs, export, drag-and-drop; :mod:`app.status` the status bar
- :mod:`app.persist`  what is remembered between runs (QSettings); :mod:`app.theme` light/dark
- :mod:`app.compiling` tells the user when numba compiles; :mod:`app.text` safe names
- :mod:`app.bench`    ``python -m app.bench``: the interaction benchmark
- :mod:`app.widgets`  one small widget per file, each bound to the state
- :mod:`app.glyphs`   ± segment geometry for direction glyphs; numpy only; :mod:`app.legend` their legend
- :mod:`app._refguard` works around a PySide6 6.12 reference-count bug
"""

from pathlib import Path

__all__ = ["RESOURCES", "DEFAULT_CLOUD", "ICON"]



def _resources_dir() -> Path:
    """The bundled data: the package data ``app/resources`` of an installed wheel, else
    ``<repo>/resources`` of a checkout (or an editable install)."""
    here = Path(__file__).resolve().parent
    installed = here / "resources"
    return installed if (installed / "bunny.ply").is_file() else here.parent / "resources"


#: Bundled data (see :func:`_resources_dir`).
RESOURCES = _resources_dir()
#: The cloud opened when no file is given: the Stanford bunny.
DEFAULT_CLOUD = RESOURCES / "bunny.ply"
#: The application icon.
ICON = RESOURCES / "darboux.svg"
