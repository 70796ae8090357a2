"""Ending the viewer's process at once, without finalising the interpreter: Ctrl-C before
the event loop runs (:func:`exit_at_once`, set by :mod:`app.launch` and :func:`app.__main__.main`)
and a background job still running at exit (:func:`app.__main__.run`)."""

from __future__ import annotations

import os
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
