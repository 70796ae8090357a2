"""Atomic file writes: write a temporary file next to the target, then rename it over."""

from __future__ import annotations

import contextlib
import os
import pathlib
import secrets


@contextlib.contextmanager
def atomic_write(path):
    """Open a binary file object whose content replaces ``path`` only if the block succeeds.

    The data goes to a hidden temporary file in the target's directory, which is flushed,
    fsync'ed and renamed over ``path`` with :func:`os.replace`. On any exception the
    temporary file is removed and an existing ``path`` is left untouched. A symlink target
    is followed (the file it points to is replaced); an existing file's permissions are kept.
    """
    target = pathlib.Path(os.path.realpath(path))
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    while True:
        tmp = target.with_name(f".{target.name}.{secrets.token_hex(6)}.tmp")
        try:
            fd = os.open(tmp, flags, 0o666)  # the umask applies, as for a plain open()
            break
        except FileExistsError:  # pragma: no cover - 48 random bits collided
            continue
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        if target.exists():
            os.chmod(tmp, target.stat().st_mode & 0o7777)
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
