"""The ``darboux`` command's first instant: Ctrl-C ends it quietly from the start.

The viewer's modules (Qt, VTK, numba's kernels) take a second or more to import, and a
Ctrl-C in that time raised KeyboardInterrupt inside one of them: a traceback and status -2
(measured: Ctrl-C 0.3-1.0 s after launch, 3 of 3). This module imports nothing heavy: it
sets Ctrl-C to end the process with status 130 at once (nothing is open, nothing to
save), then imports the viewer and runs :func:`app.__main__.run`, whose window takes
Ctrl-C over. Only the installed command starts here; ``python -m app`` imports the viewer
first (Python runs ``app/__main__.py`` whole).
"""

from __future__ import annotations

import signal

from .hard_exit import exit_at_once


def quiet_ctrl_c() -> None:
    """From now on Ctrl-C ends the process with status 130 (until the viewer takes it over)."""
    signal.signal(signal.SIGINT, exit_at_once)


def run() -> None:
    """The ``darboux`` command: Ctrl-C quiet, then the viewer (:func:`app.__main__.run`)."""
    quiet_ctrl_c()
    from .__main__ import run as viewer  # noqa: PLC0415 - the heavy imports, under the handler above

    viewer()
