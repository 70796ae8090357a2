"""Writes that must not lose or leave anything: SIGTERM mid-write, long names, FIFOs,
read-only targets, streams."""

from __future__ import annotations

import io
import os
import signal
import stat
import subprocess
import sys
import threading

import numpy as np
import pytest

import core
from core.io import CloudFileError, read_cloud, write_cloud

PTS = np.random.default_rng(0).random((50, 3))
posix = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and FIFOs")

SLOW_WRITER = """
import sys, numpy as np
from core.io import text, write_cloud
real = text.write_text
def slow(f, columns, **kw):
    f.write(b"x,y,z\\n"); f.flush()
    print("writing", flush=True)
    import time; time.sleep(60)
text.write_text = slow
from core.io import write as w
from functools import partial
w._WRITERS["csv"] = partial(slow, delimiter=",", header=True)
write_cloud(sys.argv[1], np.zeros((10, 3)))
"""


@posix
def test_sigterm_during_write_leaves_no_temp_file(tmp_path):
    target = tmp_path / "out.csv"
    env = {**os.environ, "PYTHONPATH": os.getcwd()}
    proc = subprocess.Popen([sys.executable, "-c", SLOW_WRITER, str(target)], stdout=subprocess.PIPE, env=env,
                            cwd=os.getcwd(), text=True)
    try:
        assert proc.stdout.readline().strip() == "writing"
        assert len(list(tmp_path.iterdir())) == 1  # the temporary file
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(timeout=20) == -signal.SIGTERM
    finally:
        proc.kill()
    assert list(tmp_path.iterdir()) == []


def test_long_legal_name_works(tmp_path):
    target = tmp_path / ("n" * 246 + ".ply")
    assert len(target.name) == 250
    write_cloud(target, PTS)
    np.testing.assert_array_equal(read_cloud(target).points, PTS)
    assert [p.name for p in tmp_path.iterdir()] == [target.name]


@posix
def test_fifo_is_written_into_not_replaced(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    write_cloud(fifo, PTS)
    reader.join(10)
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    assert got and got[0].startswith(b"x,y,z\n") and got[0].count(b"\n") == 51
    assert [p.name for p in tmp_path.iterdir()] == ["pipe.csv"]


@posix
def test_read_only_target_refused_and_untouched(tmp_path):
    target = write_cloud(tmp_path / "keep.ply", PTS)
    before = target.read_bytes()
    os.chmod(target, 0o444)
    try:
        with pytest.raises(CloudFileError, match=r"keep\.ply: cannot be written: the file is read-only \(mode 0444\)"):
            write_cloud(target, PTS[:3])
        assert target.read_bytes() == before and stat.S_IMODE(target.stat().st_mode) == 0o444
        assert [p.name for p in tmp_path.iterdir()] == ["keep.ply"]
    finally:
        os.chmod(target, 0o644)


def test_stream_needs_format_and_gets_text():
    buf = io.BytesIO()
    with pytest.raises(ValueError, match="format= is required"):
        write_cloud(buf, PTS)
    write_cloud(buf, PTS, format="csv")
    assert buf.getvalue().startswith(b"x,y,z\n") and buf.getvalue().count(b"\n") == 51


def test_result_to_stream():
    res = core.estimate(core.shapes.sphere(200, seed=0).points, k=15)
    buf = io.BytesIO()
    core.io.write_result(buf, res, format="ply")
    assert buf.getvalue().startswith(b"ply\n")
