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

import os
import signal
import sys


def end_now(code: int) -> None:
    """End the process with ``code`` without finalising the interpreter (what was printed
    is flushed first)."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def exit_at_once(*_args) -> None:
    """Ctrl-C before the viewer's event loop runs (its modules loading, the window being
    built): nothing to save yet, end with status 130. A KeyboardInterrupt raised inside
    VTK's imports or a Qt call printed a traceback, or was swallowed by Qt and the viewer
    went on."""
    end_now(130)


def quiet_ctrl_c() -> None:
    """From now on Ctrl-C ends the process with status 130 (until the viewer takes it over)."""
    signal.signal(signal.SIGINT, exit_at_once)


def run() -> None:
    """The ``darboux`` command: Ctrl-C quiet, then the viewer (:func:`app.__main__.run`)."""
    quiet_ctrl_c()
    from .__main__ import run as viewer  # noqa: PLC0415 - the heavy imports, under the handler above

    viewer()
