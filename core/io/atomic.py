"""Atomic file writes: write a temporary file next to the target, then rename it over.

A temporary file never outlives its write: it is removed when the block raises, and when
the process gets SIGTERM or SIGHUP during the write (the signal then does what it did
before). One that a killed process left (SIGKILL, a power cut) is removed by the next write
to the same target (:func:`_sweep_stale`: only names of that target's temporaries, and only
when their writer is gone).
Targets that are not regular files (``/dev/null``, a FIFO, a terminal) are written into
directly, never replaced; a read-only target is refused, not silently replaced; an output
that is one of the inputs is refused before any work (:func:`refuse_input_as_output`).
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import pathlib
import re
import secrets
import signal
import socket
import stat
import threading
import time

#: temporary files of the writes in progress, removed on SIGTERM / SIGHUP
_LIVE: set[str] = set()
_LOCK = threading.Lock()
#: signal -> the handler before ours (installed once, from the main thread)
_previous: dict = {}
_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
#: the temporary name keeps at most this much of the target's name: with the prefix and
#: the random suffix it stays below the 255 bytes a file name may have
_NAME_KEPT = 64
#: a target's temporary whose writer cannot be asked (another machine or container on a
#: shared folder, or a name without one) counts as left behind once nobody has written to
#: it for this long; one of a process of this machine is left behind once the process is gone
STALE_SECONDS = 30 * 60
#: a temporary's name: .TARGET.<machine>-<pid>-<random>.tmp (before: .TARGET.<random>.tmp)
_TEMP_TAIL = re.compile(r"(?:(?P<machine>[0-9a-f]{8})-(?P<pid>[0-9]{1,10})-)?[0-9a-f]{12}")


def _machine() -> str:
    """This machine and process namespace (a pid means the same process only within it)."""
    with contextlib.suppress(OSError):
        namespace = os.readlink("/proc/self/ns/pid")
        return hashlib.sha1(f"{socket.gethostname()}/{namespace}".encode()).hexdigest()[:8]
    return hashlib.sha1(socket.gethostname().encode()).hexdigest()[:8]


_MACHINE = _machine()


@contextlib.contextmanager
def atomic_write(path, *, sweep: bool = True):
    """Open a binary file object whose content replaces ``path`` only if the block succeeds.

    The data goes to a hidden temporary file in the target's directory, which is flushed,
    fsync'ed and renamed over ``path`` with :func:`os.replace`. On any exception the
    temporary file is removed and an existing ``path`` is left untouched. A symlink target
    is followed (the file it points to is replaced); an existing file's permissions are kept.
    ``sweep``: first remove this target's temporaries that killed writes left
    (:func:`_sweep_stale`; it lists the folder: a caller writing many files into one folder
    of its own, as a tiled run's work directory, passes False).

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
    if sweep:
        _sweep_stale(target)
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
    _install_signal_cleanup()
    while True:
        tmp = str(target.with_name(f"{_temp_prefix(target)}{_MACHINE}-{os.getpid()}-{secrets.token_hex(6)}.tmp"))
        with _LOCK:
            try:
                fd = os.open(tmp, flags, 0o666)  # the umask applies, as for a plain open()
            except FileExistsError:  # pragma: no cover - 48 random bits collided
                continue
            _LIVE.add(tmp)
        return fd, tmp


def _temp_prefix(target: pathlib.Path) -> str:
    return f".{target.name[:_NAME_KEPT]}."


def _sweep_stale(target: pathlib.Path) -> None:
    """Remove the temporaries of ``target`` that writes killed outright left next to it: only
    regular files named exactly as :func:`_create_temp` names them for this target (or as it
    did before the name held the writer), and only when the writer is gone (a process of
    this machine that no longer runs; else nobody wrote to it for STALE_SECONDS)."""
    prefix = _temp_prefix(target)
    try:
        with os.scandir(target.parent) as entries:
            found = [e for e in entries if e.name.startswith(prefix) and e.name.endswith(".tmp")]
    except OSError:
        return
    now = time.time()
    for entry in found:
        tail = _TEMP_TAIL.fullmatch(entry.name[len(prefix):-len(".tmp")])
        with contextlib.suppress(OSError):
            if tail is not None and entry.is_file(follow_symlinks=False) and _left_behind(entry, tail, now):
                os.unlink(entry.path)


def _left_behind(entry, tail, now: float) -> bool:
    if tail["machine"] == _MACHINE:
        pid = int(tail["pid"])
        if pid == os.getpid():
            with _LOCK:
                return entry.path not in _LIVE
        return not _running(pid)
    return now - entry.stat(follow_symlinks=False).st_mtime > STALE_SECONDS


def _running(pid: int) -> bool:
    """Whether process ``pid`` exists (of this machine; if it cannot be told: yes)."""
    if os.name != "posix":  # pragma: no cover - os.kill(pid, 0) would end it on Windows
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # it exists, owned by someone else
        return True
    return True


def _install_signal_cleanup() -> None:
    """Once, from the main thread: on SIGTERM and SIGHUP let the previous handler act; if
    that is the default one (the process ends), remove the live temporary files first. A
    signal that is ignored (SIGHUP under nohup) or handled from C is left alone."""
    if _previous or threading.current_thread() is not threading.main_thread():
        return
    for signum in _SIGNALS:
        previous = _previous[signum] = signal.getsignal(signum)
        if previous is not None and previous != signal.SIG_IGN:
            signal.signal(signum, _on_signal)


def _on_signal(signum, frame) -> None:
    previous = _previous.get(signum, signal.SIG_DFL)
    if callable(previous):  # it may raise (then the write's own cleanup runs) or go on
        previous(signum, frame)
    elif previous == signal.SIG_DFL:  # the process ends now: nothing else will clean up
        for tmp in list(_LIVE):
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)


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
