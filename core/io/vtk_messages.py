"""VTK's messages captured while it reads a file, so that a failure becomes a CloudFileError
naming the file (:mod:`core.io.vtk`, :mod:`core.io.vtk_legacy`) instead of a message on stderr."""

from __future__ import annotations

import contextlib
import re


@contextlib.contextmanager
def vtk_messages():
    """VTK's messages captured in the vtkStringOutputWindow yielded, not printed."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

    window, previous = vtkStringOutputWindow(), vtkOutputWindow.GetInstance()
    verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    vtkOutputWindow.SetInstance(window)
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        yield window
    finally:
        vtkOutputWindow.SetInstance(previous)
        vtkLogger.SetStderrVerbosity(vtkLogger.ConvertToVerbosity(verbosity))


def vtk_output(window) -> str:
    """The text the window captured."""
    messages = window.GetOutput()
    if isinstance(messages, bytes):  # VTK hands back bytes when a message is not valid UTF-8
        messages = messages.decode("utf-8", "replace")
    return messages


def first_message(text: str) -> str:
    """The first VTK message without its 'ERROR: In file, line N' and 'vtkClass (0x...):' prefixes."""
    for line in text.splitlines():
        line = line.strip()
        if not line or re.match(r"^(ERROR|Warning|Generic Warning|Generic Error): In ", line):
            continue
        return re.sub(r"^vtk\w+ \(0x[0-9a-fA-F]+\): ", "", line)
    return "unknown VTK error"
