"""Where numba caches the compiled kernels, chosen before any kernel is defined.

numba caches next to the source (``__pycache__``) or in ``~/.cache/numba``; with a
read-only installation and a read-only home it finds neither and ``@njit(cache=True)``
fails at import ("cannot cache function ...: no locator available"). Then the cache goes
to a writable user or temporary directory, and if there is none caching is switched off
with a one-line notice: the kernels are compiled again in every process, but they work.

The cache directory is keyed by a hash of every kernel source (and numba's version):
numba stamps a cached kernel with its own file's size and time only, so a kernel whose
callee in another file changed would load stale machine code (seen in a development
checkout; a wheel reinstall rewrites every file and hid it). A new key starts a new
directory; the in-tree ones of earlier keys are removed.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
import tempfile
from pathlib import Path

#: the files that define compiled kernels; any change to one of them changes the cache key
_KERNEL_SOURCES = ("kernels/*.py", "gauss_bonnet.py", "io/float_repr.py")

#: a cache directory given by the environment (the user's, or a parent process's choice)
_GIVEN = os.environ.get("NUMBA_CACHE_DIR")
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


def source_key() -> str:
    """A short hash of the kernel sources and numba's version: the cache directory's name."""
    import numba

    here = Path(__file__).resolve().parent
    digest = hashlib.sha1(numba.__version__.encode())
    for path in sorted(p for pattern in _KERNEL_SOURCES for p in here.glob(pattern)):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def configure(in_tree: Path | None = None, fallbacks: list[Path] | None = None) -> str:
    """Make sure numba can cache (or knows not to); returns where the cache goes."""
    key = source_key()
    in_tree = in_tree or Path(__file__).resolve().parent / "__pycache__" / "numba"
    if _GIVEN:
        STATE["where"] = "env"
    elif _usable(in_tree / key):
        _prune(in_tree, keep=key)
        _set_cache_dir(str(in_tree / key))
        STATE["where"] = "in-tree"
    else:
        bases = _fallbacks() if fallbacks is None else fallbacks
        found = next((d / key for d in bases if _usable(d / key)), None)
        if found is not None:
            _set_cache_dir(str(found))
            STATE["where"] = str(found)
        else:
            _disable_caching()
            STATE["where"] = "off"
            print("darboux: no writable directory for numba's cache; kernels are compiled in every run "
                  "(set NUMBA_CACHE_DIR to keep them)", file=sys.stderr)
    return STATE["where"]


def _prune(root: Path, keep: str) -> None:
    """Remove the in-tree caches of earlier kernel sources (best effort)."""
    for old in root.iterdir():
        if old.is_dir() and old.name != keep:
            shutil.rmtree(old, ignore_errors=True)


def _set_cache_dir(directory: str) -> None:
    from numba.core import config

    os.environ["NUMBA_CACHE_DIR"] = directory  # for subprocesses, and numba's config reloads
    config.CACHE_DIR = directory


def _disable_caching() -> None:
    from numba.core.dispatcher import Dispatcher

    Dispatcher.enable_caching = lambda self: None
