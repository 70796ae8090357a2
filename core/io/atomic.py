"""Atomic file writes: write a temporary file next to the target, then rename it over.

A temporary file never outlives its write: it is removed when the block raises, and when
the process gets SIGTERM during the write (the signal then does what it did before).
Targets that are not regular files (``/dev/null``, a FIFO, a terminal) are written into
directly, never replaced; a read-only target is refused, not silently replaced; an output
that is one of the inputs is refused before any work (:func:`refuse_input_as_output`).
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import secrets
import signal
import stat
import threading

#: temporary files of the writes in progress, removed on SIGTERM
_LIVE: set[str] = set()
_LOCK = threading.Lock()
_previous_handler = None
#: the temporary name keeps at most this much of the target's name: with the prefix and
#: the random suffix it stays below the 255 bytes a file name may have
_NAME_KEPT = 64


@contextlib.contextmanager
def atomic_write(path):
    """Open a binary file object whose content replaces ``path`` only if the block succeeds.

    The data goes to a hidden temporary file in the target's directory, which is flushed,
    fsync'ed and renamed over ``path`` with :func:`os.replace`. On any exception the
    temporary file is removed and an existing ``path`` is left untouched. A symlink target
    is followed (the file it points to is replaced); an existing file's permissions are kept.

    Raises
    ------
    PermissionError
        ``path`` exists and has no write permission bit (e.g. mode 0444), even for root.
    """
    target = pathlib.Path(os.path.realpath(path))
    mode = _existing_mode(target)
    if mode is not None and not stat.S_ISREG(mode):  # a device, FIFO or socket: write into it
        with open(target, "wb") as f:
            yield f
        return
    if mode is not None and not mode & 0o222:
        raise PermissionError(13, f"the file is read-only (mode {stat.S_IMODE(mode):04o}); make it writable "
                                  "or choose another name")
    fd, tmp = _create_temp(target)
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        if mode is not None:
            os.chmod(tmp, stat.S_IMODE(mode))
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    finally:
        with _LOCK:
            _LIVE.discard(tmp)


def _existing_mode(target: pathlib.Path):
    try:
        return target.stat().st_mode
    except FileNotFoundError:
        return None


def _create_temp(target: pathlib.Path):
    """``(fd, name)`` of a new hidden file next to ``target``, registered for SIGTERM cleanup."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    _install_sigterm_cleanup()
    while True:
        tmp = str(target.with_name(f".{target.name[:_NAME_KEPT]}.{secrets.token_hex(6)}.tmp"))
        with _LOCK:
            try:
                fd = os.open(tmp, flags, 0o666)  # the umask applies, as for a plain open()
            except FileExistsError:  # pragma: no cover - 48 random bits collided
                continue
            _LIVE.add(tmp)
        return fd, tmp


def _install_sigterm_cleanup() -> None:
    """Once, from the main thread: on SIGTERM let the previous handler act; if that is the
    default one (the process ends), remove the live temporary files first."""
    global _previous_handler
    if _previous_handler is not None or threading.current_thread() is not threading.main_thread():
        return
    if not hasattr(signal, "SIGTERM"):  # pragma: no cover
        return
    _previous_handler = signal.getsignal(signal.SIGTERM)
    if _previous_handler is None:  # set from C (not by Python): leave it alone
        _previous_handler = signal.SIG_DFL
        return
    signal.signal(signal.SIGTERM, _on_sigterm)


def _on_sigterm(signum, frame) -> None:
    previous = _previous_handler
    if callable(previous):  # it may raise (then the write's own cleanup runs) or go on
        previous(signum, frame)
    elif previous == signal.SIG_DFL:  # the process ends now: nothing else will clean up
        for tmp in list(_LIVE):
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)


def refuse_input_as_output(inputs, output) -> None:
    """Raise ValueError when ``output`` is the same file as any of ``inputs`` (paths; "-" and
    arrays are skipped): the same name, a symlink or a hard link to it. An output that does
    not exist yet is a new file, never an input. Every output of the CLI and of
    :func:`core.tiled.estimate_tiled` goes through this check before any work."""
    if not isinstance(output, (str, os.PathLike)) or os.fspath(output) == "-":
        return
    for src in inputs:
        if isinstance(src, (str, os.PathLike)) and os.fspath(src) != "-" and _same_file(src, output):
            raise ValueError(f"output {os.fspath(output)!r} is the input file; choose another name")


def _same_file(a, b) -> bool:
    """Whether paths ``a`` and ``b`` name one file (by device and inode when both exist)."""
    if not (os.path.lexists(a) and os.path.lexists(b)):
        return False
    try:
        return os.path.samefile(a, b)
    except OSError:  # a dangling link or an unreadable folder: compare the resolved paths
        return os.path.realpath(a) == os.path.realpath(b)
