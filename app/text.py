"""Text that is safe to hand to Qt and VTK.

A file name that is not valid UTF-8 reaches Python as a ``str`` with lone surrogates
(``os.fsdecode``'s ``surrogateescape``). VTK's text actors crash and Qt drops the
characters on such strings (issue 10), so every name and message shown is passed
through :func:`safe_text` first: undecodable bytes become U+FFFD.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["safe_text", "display_name"]


def safe_text(text) -> str:
    """``text`` as valid Unicode: lone surrogates (undecodable bytes) become U+FFFD."""
    text = str(text)
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "replace").encode(
            "utf-8", "replace").decode("utf-8")


def display_name(path) -> str:
    """The file name of ``path`` (str, bytes or Path) for titles and messages."""
    return safe_text(Path(os.fsdecode(path)).name)
