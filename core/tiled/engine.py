"""Run the tile tasks on Dask (``dask.distributed``), or in this process.

By default a :class:`distributed.LocalCluster` sized to the machine: one single-threaded
worker process per core (numba and the kd-tree each use their worker's core), each with
the memory budget as its limit; ``client=`` or ``scheduler=ADDRESS`` use an existing
cluster (dask-jobqueue, Kubernetes, ...) unchanged. Only a tile id and a few parameters
go to the workers: each task reads its tile from the shared work directory. The
dashboard link and a progress line with an ETA (from the points done per second) are
reported through ``progress``.
"""

from __future__ import annotations

import os
import socket
import threading
import time

from .task import run_tile

#: seconds an existing scheduler (``scheduler=ADDRESS``) has to take the connection and
#: answer Dask's handshake. Dask's own connect timeout does not cover the handshake: a port
#: that takes the connection and stays silent (a web server, the dashboard's port) hung the
#: run for good, and one that greets first (SSH, SMTP) had its banner read as the length of
#: a message (a MemoryError)
SCHEDULER_TIMEOUT = 15.0
#: Dask's scheduler port, when an address has none
_DEFAULT_PORT = 8786

#: Dask settings of the local cluster this module starts (an existing cluster keeps its own).
#: Dask's defaults watch a worker closely: a statistical profiler samples every task's stack
#: every 10 ms, a tick checks the event loop every 20 ms, a system monitor reads psutil every
#: 0.5 s and the nanny the worker's memory every 0.1 s. Idle, a 2-worker cluster spent 2.75
#: CPU s per 30 s on them (2026-12-01, load 10), 0.55 with these values; the dashboard's
#: task stream and progress stay, its profile page is empty. The memory limit is still
#: enforced 5 times a second.
DASK_CONFIG = {"distributed.worker.profile.enabled": False, "distributed.admin.tick.interval": "1s",
               "distributed.admin.system-monitor.interval": "2s",
               "distributed.admin.system-monitor.gil.enabled": False,
               "distributed.worker.memory.monitor-interval": "200ms"}


def run_tasks(root, tiles, sizes, spec, *, client=None, scheduler=None, workers=None, memory=None,
              label="input", progress=None, fn=None, stage="tiles") -> list:
    """Run ``fn(root, tile, spec)`` (default :func:`run_tile`) for every tile id in
    ``tiles``; returns their summaries. ``stage`` names the round in the progress.

    ``sizes`` (points per tile) weighs the progress and the ETA. ``workers=0`` runs the
    tiles one by one in this process (no cluster). A failing tile raises ValueError naming
    ``label`` (the input file) and the tile.
    """
    tiles = list(tiles)
    fn = fn or run_tile
    if not tiles:
        return []
    clock = _Clock(sum(sizes[t] for t in tiles), progress, stage)
    if client is None and scheduler is None and workers == 0:
        out = []
        for t in tiles:
            out.append(_guarded(fn, root, t, spec, label))
            clock.done(sizes[t])
        return out
    return _on_dask(fn, root, tiles, sizes, spec, clock, client=client, scheduler=scheduler, workers=workers,
                    memory=memory, label=label)


def timed(fn, root, tile, spec) -> dict:
    """``fn(root, tile, spec)``'s summary with the CPU seconds the task took ("cpu"), in
    the process that ran it (a Dask worker's own time is its tasks' plus its runtime's)."""
    cpu = time.process_time()
    summary = fn(root, tile, spec)
    return {**summary, "cpu": time.process_time() - cpu}


def _guarded(fn, root, tile, spec, label):
    try:
        return timed(fn, root, tile, spec)
    except Exception as exc:
        raise ValueError(f"{label}: tile {tile} failed: {type(exc).__name__}: {exc}") from exc


#: what a tile's KilledWorker most often means
_KILLED = ("; the workers running it died, most often of the memory limit: lower --tile-points or raise "
           "--memory")


def _on_dask(fn, root, tiles, sizes, spec, clock, *, client, scheduler, workers, memory, label):
    from distributed import Client, LocalCluster, as_completed

    own_cluster = own_client = None
    if client is None:
        if scheduler is not None:
            client = own_client = connect(scheduler)
        else:
            import dask

            n = workers or max(1, os.cpu_count() or 1)
            with dask.config.set(DASK_CONFIG):  # the nannies hand this config to their workers
                own_cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, memory_limit=memory,
                                           dashboard_address=":0", silence_logs=40)
                client = own_client = Client(own_cluster)
    clock.note(f"dask dashboard {client.dashboard_link}")
    key = f"darboux-{stage_key(clock.stage)}"
    futures = {client.submit(timed, fn, str(root), t, spec, key=f"{key}-{t}-{time.time_ns()}", pure=False): t
               for t in tiles}
    out = []
    try:
        for fut in as_completed(futures, loop=client.loop):  # this client's: a scheduler's is not the default
            t = futures[fut]
            if fut.status == "error":
                exc = fut.exception()
                hint = _KILLED if type(exc).__name__ == "KilledWorker" else ""
                raise ValueError(f"{label}: tile {t} failed: {type(exc).__name__}: {exc}{hint}")
            out.append(fut.result())
            clock.done(sizes[t])
    finally:
        for fut in futures:
            fut.cancel()
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
    return out


def connect(address, timeout: float | None = None):
    """A ``distributed.Client`` of the scheduler at ``address``, within ``timeout`` seconds
    (default SCHEDULER_TIMEOUT); else ValueError "cannot connect to the Dask scheduler at
    ADDRESS: <reason>". A TCP port nobody listens on is told at once; the handshake is
    tried first on a connection of its own, which a timeout can end (a Client's cannot)."""
    from distributed import Client

    timeout = SCHEDULER_TIMEOUT if timeout is None else float(timeout)
    _listening(address, timeout)
    error = _handshake_error(address, timeout)
    if error is None:
        try:
            return Client(address, timeout=timeout, set_as_default=False)
        except Exception as exc:  # noqa: BLE001 - every failure to connect is told alike
            error = exc
    raise ValueError(f"cannot connect to the Dask scheduler at {address}: {_reason(error, timeout)}") from error


def _handshake_error(address, timeout: float):
    """None when ``address`` answers Dask's handshake within ``timeout``, else the error
    (in a thread of its own: the caller may be running an event loop)."""
    import asyncio

    from distributed.comm import connect as dask_connect
    from distributed.comm.addressing import parse_address

    if parse_address(str(address))[0] == "inproc":  # this process: nothing to wait for
        return None

    async def shake():
        comm = await asyncio.wait_for(dask_connect(address, timeout=timeout), timeout)
        await comm.close()

    box = {"error": TimeoutError()}

    def attempt():
        try:
            asyncio.run(shake())
            box["error"] = None
        except BaseException as exc:  # noqa: BLE001 - handed to the caller
            box["error"] = exc

    thread = threading.Thread(target=attempt, name="darboux-dask-handshake", daemon=True)
    thread.start()
    thread.join(timeout + 2.0)
    return box["error"]


def _listening(address, timeout: float) -> None:
    """Raise ValueError at once when a TCP/TLS ``address`` refuses the connection (Dask
    retries it until its timeout) or does not resolve."""
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(str(address))
        host, port = parse_host_port(location, default_port=_DEFAULT_PORT)
    except (ValueError, TypeError):
        return  # Dask says what is wrong with it
    if scheme not in ("tcp", "tls"):
        return
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        raise ValueError(f"cannot connect to the Dask scheduler at {address}: {_reason(exc, timeout)}") from None


def _reason(error, timeout: float) -> str:
    if isinstance(error, (TimeoutError, socket.timeout)):
        return (f"no answer to Dask's handshake within {timeout:g} s (is it the scheduler's port, not "
                "its dashboard's or another service's?)")
    if isinstance(error, MemoryError):
        return "the answer is not Dask's protocol (it announced a message too large to hold; another service?)"
    if isinstance(error, OSError) and error.strerror:
        return error.strerror
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0]}" if text else type(error).__name__


def stage_key(stage: str) -> str:
    """A Dask key part from a stage name (the dashboard groups tasks by it)."""
    return "-".join(stage.split()) or "tile"


class _Clock:
    """Progress over points done, with an ETA from the rate so far."""

    def __init__(self, total, progress, stage="tiles"):
        self.stage = stage
        self.total = max(int(total), 1)
        self.progress = progress
        self.count = 0
        self.t0 = time.perf_counter()

    def note(self, text):
        if self.progress is not None:
            self.progress(self.count / self.total, text)

    def done(self, points):
        self.count += int(points)
        if self.progress is None:
            return
        elapsed = time.perf_counter() - self.t0
        eta = elapsed * (self.total - self.count) / max(self.count, 1)
        self.progress(self.count / self.total, f"{self.stage}, ETA {eta:5.0f} s")
