"""Where numba caches the compiled kernels, chosen before any kernel is defined.

numba caches next to the source (``__pycache__``) or in ``~/.cache/numba``; with a
read-only installation and a read-only home it finds neither and ``@njit(cache=True)``
fails at import ("cannot cache function ...: no locator available"). Then the cache goes
to a writable user or temporary directory, and if there is none caching is switched off
with a one-line notice: the kernels are compiled again in every process, but they work.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

#: where the cache went, for ``darboux-cli warmup`` and the tests: "in-tree", "env", a
#: directory, or "off"
STATE = {"where": None}


def _usable(directory: Path) -> bool:
    """The test numba itself applies: the directory can be created and written into."""
    try:
        os.makedirs(directory, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError:
        return False
    return True


def _fallbacks() -> list[Path]:
    user = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    uid = os.getuid() if hasattr(os, "getuid") else "user"
    return [Path(user) / "darboux" / "numba", Path(tempfile.gettempdir()) / f"darboux-numba-{uid}"]


def configure(in_tree: Path | None = None, fallbacks: list[Path] | None = None) -> str:
    """Make sure numba can cache (or knows not to); returns where the cache goes."""
    if os.environ.get("NUMBA_CACHE_DIR"):
        STATE["where"] = "env"
    elif _usable(in_tree or Path(__file__).resolve().parent / "__pycache__"):
        STATE["where"] = "in-tree"
    else:
        found = next((d for d in (_fallbacks() if fallbacks is None else fallbacks) if _usable(d)), None)
        if found is not None:
            _set_cache_dir(str(found))
            STATE["where"] = str(found)
        else:
            _disable_caching()
            STATE["where"] = "off"
            print("darboux: no writable directory for numba's cache; kernels are compiled in every run "
                  "(set NUMBA_CACHE_DIR to keep them)", file=sys.stderr)
    return STATE["where"]


def _set_cache_dir(directory: str) -> None:
    from numba.core import config

    os.environ["NUMBA_CACHE_DIR"] = directory  # for subprocesses, and numba's config reloads
    config.CACHE_DIR = directory


def _disable_caching() -> None:
    from numba.core.dispatcher import Dispatcher

    Dispatcher.enable_caching = lambda self: None
