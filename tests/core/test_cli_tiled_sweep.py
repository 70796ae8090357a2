"""The CLI / tiled sweep's findings (2026-12-03): a --scheduler that is not Dask's, work
directories of failed runs, LAS/LAZ output with several inputs or stdin, temporaries left
by a killed write, the crease flag of integer k in tiles, the agreement of one tile, and
checks made before the estimate."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import laspy
import numpy as np
import pytest

import core
from cli_testutils import one_line_error
from core import cli
from core.io import atomic
from core.tiled import engine, estimate_tiled

posix = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")


@pytest.fixture(scope="module")
def clouds(tmp_path_factory):
    d = tmp_path_factory.mktemp("sweep")
    for name, seed in (("a", 1), ("b", 2)):
        np.savetxt(d / f"{name}.xyz", core.shapes.sphere(400, seed=seed).points)
    return d


# ------------------------------------------------------------------ H2: not a Dask scheduler
@contextlib.contextmanager
def _service(banner: bytes):
    """A TCP server that takes connections and greets with ``banner`` (or stays silent)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    srv.settimeout(0.2)
    stop, conns = threading.Event(), []

    def serve():
        while not stop.is_set():
            try:
                conn, _ = srv.accept()
            except OSError:
                continue
            conns.append(conn)
            if banner:
                conn.sendall(banner)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"tcp://127.0.0.1:{srv.getsockname()[1]}"
    finally:
        stop.set()
        thread.join(2)
        for conn in conns:
            conn.close()
        srv.close()


def _main_within(argv, seconds):
    """``cli.main(argv)`` run in a thread that must end within ``seconds``."""
    box = {}
    thread = threading.Thread(target=lambda: box.setdefault("rc", cli.main(argv)), daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"darboux-cli still running after {seconds} s"
    return box["rc"]


@pytest.mark.parametrize("banner", [b"", b"SSH-2.0-OpenSSH_9.6\r\n" * 4], ids=["silent", "banner"])
def test_a_service_that_is_not_dask_is_one_line_and_exit_2(clouds, tmp_path, capsys, monkeypatch, banner):
    monkeypatch.setattr(engine, "SCHEDULER_TIMEOUT", 1.5, raising=False)
    out = tmp_path / "o.laz"
    with _service(banner) as address:
        rc = _main_within(["estimate", str(clouds / "a.xyz"), "-o", str(out), "--k", "15", "--scheduler", address], 120)
    assert rc == 2
    err = one_line_error(capsys, f"cannot connect to the Dask scheduler at {address}: ")
    assert "out of memory" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no output, no work directory


def test_a_port_nobody_listens_on_is_told_at_once(clouds, tmp_path, capsys, monkeypatch):
    """Told before Dask tries the address: Dask retries a refused connection until its timeout
    (30 s). Dask's connect and Client are counted, not timed (a loaded machine stretches time)."""
    import distributed
    import distributed.comm

    tries = []

    def dask_tries(*args, **kwargs):
        tries.append(args[:1])
        raise OSError("Dask was asked to connect")

    monkeypatch.setattr(distributed.comm, "connect", dask_tries)
    monkeypatch.setattr(distributed, "Client", dask_tries)
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()  # bound, then released: nothing listens there
    rc = _main_within(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.laz"), "--k", "15",
                       "--scheduler", f"tcp://127.0.0.1:{port}"], 120)
    assert rc == 2 and tries == []
    one_line_error(capsys, f"cannot connect to the Dask scheduler at tcp://127.0.0.1:{port}: ")
    assert list(tmp_path.iterdir()) == []


def test_a_memory_error_in_dask_is_not_out_of_memory(capsys, monkeypatch):
    scope = {"__name__": "distributed.comm.tcp"}
    exec("def read_frames():\n    raise MemoryError('Unable to allocate 2.82 EiB')\n", scope)

    def command(args):
        scope["read_frames"]()

    monkeypatch.setattr(core._cli_commands, "cmd_estimate", command)
    assert cli.main(["estimate", "x.xyz", "-o", "y.ply"]) == 1
    err = one_line_error(capsys, "Dask scheduler", "2.82 EiB")
    assert "out of memory" not in err


# ------------------------------------------------------- M1: the work directory of a failure
def _fail_tiles(monkeypatch, failing):
    from core.tiled.task import run_tile as real

    def run_tile(root, tile, spec):
        if tile in failing:
            raise RuntimeError("boom")
        return real(root, tile, spec)

    monkeypatch.setattr(engine, "run_tile", run_tile)


def test_a_failed_run_keeps_its_work_directory_only_to_resume(tmp_path, monkeypatch):
    pts = core.shapes.sphere(1200, seed=3).points
    out, work = tmp_path / "o.laz", tmp_path / ".o.laz.tiles"
    _fail_tiles(monkeypatch, {0})  # the first tile fails: nothing to resume
    with pytest.raises(ValueError, match="tile 0 failed"):
        estimate_tiled(pts, out, k=15, tile_points=400, workers=0)
    assert not work.exists() and not out.exists()
    _fail_tiles(monkeypatch, {2})  # tiles 0 and 1 finished: kept for a rerun
    with pytest.raises(ValueError, match="tile 2 failed"):
        estimate_tiled(pts, out, k=15, tile_points=400, workers=0)
    assert work.is_dir() and len(list(work.glob("results/*.done"))) == 2


def test_a_cluster_that_does_not_start_leaves_no_work_directory(tmp_path, monkeypatch):
    import distributed

    def no_cluster(*args, **kwargs):
        raise OSError("no cluster here")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    with pytest.raises(OSError, match="no cluster here"):
        estimate_tiled(core.shapes.sphere(600, seed=3).points, tmp_path / "o.laz", k=15, tile_points=300, workers=1)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------ M3: LAS/LAZ with several inputs, stdin
def test_las_output_with_several_inputs(clouds, tmp_path):
    pattern = str(tmp_path / "{stem}_out.laz")
    argv = ["estimate", str(clouds / "a.xyz"), str(clouds / "b.xyz"), "-o", pattern, "--k", "15", "--workers", "0", "-q"]
    assert cli.main(argv) == 0
    for name in "ab":
        las = laspy.read(tmp_path / f"{name}_out.laz")
        np.testing.assert_allclose(las.xyz, np.loadtxt(clouds / f"{name}.xyz"), atol=1e-3)
        assert np.asarray(las["valid"]).all()


def test_las_output_from_standard_input(clouds, tmp_path, monkeypatch):
    data = (clouds / "a.xyz").read_bytes()
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))
    out = tmp_path / "s.las"
    assert cli.main(["estimate", "-", "-o", str(out), "--k", "15", "--workers", "0", "-q"]) == 0
    np.testing.assert_allclose(laspy.read(out).xyz, np.loadtxt(clouds / "a.xyz"), atol=1e-3)


@pytest.mark.parametrize("k", ["15", "auto"])  # in tiles, and whole into LAS
def test_the_summary_of_standard_input_names_stdin_not_its_temporary_copy(clouds, tmp_path, monkeypatch, capsys, k):
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO((clouds / "a.xyz").read_bytes())))
    assert cli.main(["estimate", "-", "-o", str(tmp_path / "s.las"), "--k", k, "--workers", "0"]
                    if k == "15" else ["estimate", "-", "-o", str(tmp_path / "s.las")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("stdin: ") and "darboux-stdin-" not in out


def test_las_output_in_a_directory_by_format(clouds, tmp_path):
    argv = ["estimate", str(clouds / "a.xyz"), str(clouds / "b.xyz"), "-o", str(tmp_path), "--format", "laz",
            "--k", "15", "--workers", "0", "-q"]
    assert cli.main(argv) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a_darboux.laz", "b_darboux.laz"]


def test_las_to_standard_output_is_refused_clearly(clouds, capsys):
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", "-", "--format", "laz"]) == 2
    one_line_error(capsys, "LAS/LAZ output needs a file name")


def test_tiles_to_standard_output_are_refused_before_any_work(clouds, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", "-", "--workers", "0"]) == 2
    one_line_error(capsys, "tiles (--workers) write a file, not -o - (standard output)")
    assert list(tmp_path.iterdir()) == []  # no work directory named for "-"


def test_help_lists_the_las_outputs(capsys):
    with pytest.raises(SystemExit):
        cli.main(["estimate", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "(.ply, .csv, .xyz, .txt, .vtp, .las, .laz)" in help_text
    assert all(ext in help_text for ext in (".e57", ".ptx", ".off"))  # the inputs, from READ_FORMATS


# --------------------------------------------------- M4: temporaries left by a killed write
def _dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@posix
def test_the_next_write_removes_what_killed_writes_left(tmp_path):
    target, hour_ago = tmp_path / "out.csv", time.time() - 3600
    me = getattr(atomic, "_MACHINE", "0" * 8)
    stale = [f".out.csv.{me}-{_dead_pid()}-0123456789ab.tmp",  # its process is gone
             ".out.csv.0123456789ab.tmp"]  # an older name, not written to for an hour
    kept = [f".out.csv.{me}-{os.getppid()}-0123456789ab.tmp",  # a process still running
            ".out.csv.ba9876543210.tmp",  # an older name written to just now
            f".out.csv.{'f' * 8}-{_dead_pid()}-0123456789ab.tmp",  # another machine's, just now
            ".out.csv.0123456789ab.tmp.bak", ".out.csv.xyz.tmp", ".other.csv.0123456789ab.tmp", "out.csv.tmp"]
    for name in stale + kept:
        (tmp_path / name).write_bytes(b"partial")
    for name in stale + [".other.csv.0123456789ab.tmp", "out.csv.tmp"]:
        os.utime(tmp_path / name, (hour_ago, hour_ago))
    core.io.write_cloud(target, np.random.default_rng(0).random((20, 3)))
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(kept + ["out.csv"])


SLOW_WRITER = """
import signal, sys, time
signal.signal(signal.SIGHUP, signal.SIG_DFL)  # as from a terminal: the test may run under nohup
from core.io.atomic import atomic_write
with atomic_write(sys.argv[1]) as f:
    f.write(b"x,y,z\\n"); f.flush()
    print("writing", flush=True)
    time.sleep(60)
"""


def _killed_mid_write(target, signum):
    env = {**os.environ, "PYTHONPATH": os.getcwd()}
    proc = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], stdout=subprocess.PIPE, env=env,
                            text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        proc.send_signal(signum)
        assert proc.wait(timeout=20) == -signum
    finally:
        proc.kill()
        proc.stdout.close()


@posix
def test_sighup_during_a_write_leaves_no_temporary(tmp_path):
    _killed_mid_write(tmp_path / "out.csv", signal.SIGHUP)
    assert list(tmp_path.iterdir()) == []


@posix
def test_a_write_after_kill_9_removes_its_temporary(tmp_path):
    _killed_mid_write(tmp_path / "out.csv", signal.SIGKILL)
    assert len(list(tmp_path.iterdir())) == 1  # what kill -9 leaves
    core.io.write_cloud(tmp_path / "out.csv", np.random.default_rng(0).random((20, 3)))
    assert [p.name for p in tmp_path.iterdir()] == ["out.csv"]


# ------------------------------------------------- L1: integer k's crease flag in tiles
def test_integer_k_creases_in_tiles_are_the_whole_clouds(tmp_path):
    rng = np.random.default_rng(1)
    pts = core.shapes.cube(6000, seed=0).points
    pts = pts + rng.normal(scale=0.01, size=pts.shape) * (pts[:, :1] > 0)  # a noisy half: tiles' medians differ
    mem = core.estimate(pts, k=15)
    run = estimate_tiled(pts, tmp_path / "t.laz", k=15, tile_points=700, workers=0)
    crease = np.asarray(laspy.read(tmp_path / "t.laz")["crease"]).astype(bool)
    assert run.n_tiles >= 8 and mem.crease.sum() > 100
    np.testing.assert_array_equal(crease, mem.crease)
    assert run.params["crease_typical"] == mem.params["crease_typical"]


# ------------------------------------------------------------ L2: one tile, no overlaps
def test_one_tile_agrees_fully(tmp_path):
    run = estimate_tiled(core.shapes.sphere(800, seed=2).points, tmp_path / "t.laz", k=15, workers=0)
    assert run.n_tiles == 1 and run.agreement == 1.0


# -------------------------------------------------------- L3: checked before the estimate
def _never(*args, **kwargs):
    raise AssertionError("the estimate ran")


def test_a_missing_output_folder_is_told_before_the_estimate(clouds, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(core, "estimate", _never)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "nodir" / "out.ply")]) == 2
    one_line_error(capsys, "the folder", "nodir does not exist")
    pattern = str(tmp_path / "nodir" / "{stem}.csv")
    assert cli.main(["estimate", str(clouds / "a.xyz"), str(clouds / "b.xyz"), "-o", pattern]) == 2
    one_line_error(capsys, "nodir does not exist")


def test_a_bad_memory_is_refused_on_the_in_memory_path_too(clouds, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(core, "estimate", _never)
    assert cli.main(["estimate", str(clouds / "a.xyz"), "-o", str(tmp_path / "o.ply"), "--memory", "abc"]) == 2
    one_line_error(capsys, "memory 'abc' is invalid")
    assert list(tmp_path.iterdir()) == []
