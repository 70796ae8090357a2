"""``python -m app --screenshot``: a real process, a real window, a PNG (under Xvfb)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from app_testutils import colour_stats, image_array, run_app_cli

ROOT = Path(__file__).resolve().parents[2]


def test_screenshot_of_a_shape_with_glyphs_and_pick(tmp_path, qapp):
    from PySide6.QtGui import QImage

    out = tmp_path / "torus.png"
    proc = run_app_cli("--shape", "torus", "--points", "2000", "--field", "K", "--glyphs", "e1", "--pick", "5",
                "--size", "1100x700", "--screenshot", str(out))
    assert proc.returncode == 0, proc.stderr
    image = QImage(str(out))
    assert (image.width(), image.height()) == (1100, 700)
    stats = colour_stats(image_array(image))
    assert stats["unique"] > 150 and stats["coloured"] > 0.02, stats


def test_screenshot_of_a_bad_file_fails_with_a_message(tmp_path):
    bad = tmp_path / "garbage.ply"
    bad.write_bytes(b"\x00\x01 not a ply")
    out = tmp_path / "never.png"
    proc = run_app_cli(str(bad), "--screenshot", str(out))
    assert proc.returncode == 1
    assert "garbage.ply" in proc.stderr
    assert not out.exists()


def test_ctrl_c_quits_the_viewer_with_130(tmp_path):
    """Ctrl-C in the terminal ends an interactive viewer: exit status 130, no traceback
    (Qt's event loop alone would never return to Python's signal handler)."""
    import signal
    import time

    env = dict(os.environ, HOME=str(tmp_path), XDG_CONFIG_HOME=str(tmp_path / "config"))
    env.pop("QT_QPA_PLATFORM", None)
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.Popen([sys.executable, "-m", "app", "--shape", "sphere", "--points", "500"], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(15)  # imports and the window; the handler is installed before the window
        assert proc.poll() is None, proc.stderr.read()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err, err


def test_ctrl_c_before_the_event_loop_runs_still_quits(qapp):
    """Ctrl-C between the handler's installation and ``exec()`` (the window being built, the
    first cloud opening) quits once the loop starts: a plain ``quit()`` there was lost and
    the viewer ran on, deaf to Ctrl-C (here until a 5 s guard quit the loop)."""
    import signal

    from PySide6.QtCore import QTimer

    from app.__main__ import _quit_on_sigint

    before = signal.getsignal(signal.SIGINT)
    outcome = {"code": 0}
    timer = _quit_on_sigint(qapp, outcome)
    guard = QTimer()
    guard.setSingleShot(True)
    guard.timeout.connect(lambda: (outcome.update(guard=True), qapp.quit()))
    try:
        signal.raise_signal(signal.SIGINT)  # the Python handler runs here, before exec()
        guard.start(5000)
        qapp.exec()
    finally:
        timer.stop()
        guard.stop()
        signal.signal(signal.SIGINT, before)
    assert outcome == {"code": 130}, outcome  # quit by Ctrl-C's quit, not the guard


def test_run_ends_the_process_at_once_when_a_job_is_still_running(monkeypatch):
    """``darboux`` (app.__main__.run) does not finalise the interpreter around a background
    job that is still running (numba compiling when Ctrl-C came crashed it): it ends the
    process with the viewer's status; with no job left it exits normally."""
    import app.__main__ as entry

    ended = []
    monkeypatch.setattr(entry, "main", lambda: 130)
    monkeypatch.setattr(os, "_exit", lambda code: ended.append(code))
    monkeypatch.setattr(entry, "live_job_threads", lambda: ["darboux-estimate"])
    with pytest.raises(SystemExit):  # the stand-in os._exit returns: run() goes on to sys.exit
        entry.run()
    assert ended == [130]
    ended.clear()
    monkeypatch.setattr(entry, "live_job_threads", lambda: [])
    with pytest.raises(SystemExit) as exc:
        entry.run()
    assert exc.value.code == 130 and not ended


def test_darboux_quiets_ctrl_c_before_the_viewer_loads(monkeypatch):
    """The ``darboux`` command (app.launch.run) sets Ctrl-C to end the process before it
    imports the viewer (Qt, VTK, numba: a second or more, where a Ctrl-C printed a
    KeyboardInterrupt traceback)."""
    import signal
    import types

    import app.launch as launch

    seen = {}
    viewer = types.ModuleType("app.__main__")
    viewer.run = lambda: seen.setdefault("handler", signal.getsignal(signal.SIGINT))
    monkeypatch.setitem(sys.modules, "app.__main__", viewer)
    before = signal.getsignal(signal.SIGINT)
    try:
        launch.run()
    finally:
        signal.signal(signal.SIGINT, before)
    assert seen["handler"] is launch.exit_at_once


def test_ctrl_c_while_the_viewer_loads_ends_with_130_and_no_traceback():
    code = ("import os, signal, time\nimport app.launch\napp.launch.quiet_ctrl_c()\n"
            "os.kill(os.getpid(), signal.SIGINT)\ntime.sleep(20)\nprint('not ended')")
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 130, proc.stderr
    assert proc.stdout == "" and "Traceback" not in proc.stderr, proc.stderr
