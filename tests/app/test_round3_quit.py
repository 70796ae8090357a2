"""Round 3: ``app.__main__.main()`` called from a script, returning while a background job
still runs (item 2 of the brief).

The window's shutdown abandons a job that does not reach a cancel check within ~0.8 s (a
kernel numba compiles has none); the ``darboux`` command then ends the process at once
(app.__main__.run), but a script that called ``main()`` went on to finalise the interpreter
around the running job: "terminate called without an active exception" (an abort), or
SIGSEGV inside LLVM. Now the process waits at its exit for the job to end.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

from app_testutils import ROOT

SCRIPT = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    import core
    import app.worker
    from app.__main__ import main
    from app.jobs import live_job_threads

    marker = Path(sys.argv[1])

    def compiling(*args, progress=None, **kwargs):
        # what numba compiling a kernel is to the job: a while with no cancel check
        time.sleep(3.0)
        marker.write_text("the job ended")
        raise core.Cancelled("cancelled after the compile")

    app.worker.core.estimate = compiling
    qapp = QApplication([sys.argv[0]])

    def close_when_busy():
        for widget in QApplication.topLevelWidgets():
            if type(widget).__name__ == "MainWindow" and widget.estimator.busy:
                QTimer.singleShot(300, widget.close)
                return
        QTimer.singleShot(50, close_when_busy)

    QTimer.singleShot(0, close_when_busy)
    code = main(["--shape", "sphere", "--points", "2000"])
    print("main returned", code, "running:", live_job_threads(), flush=True)
""")


def test_a_script_whose_main_returns_mid_job_waits_for_the_job_at_exit(tmp_path):
    """Old code: the process finalised Python with the job still inside its kernel (the
    marker the job writes at its end was never written: the interpreter was torn down
    under it). Now: main() returns at once (the script goes on), and the process waits at
    its exit until the job has ended, then exits 0."""
    script = tmp_path / "script.py"
    script.write_text(SCRIPT)
    marker = tmp_path / "ended.txt"
    env = dict(os.environ, HOME=str(tmp_path), XDG_CONFIG_HOME=str(tmp_path / "config"))
    env.pop("QT_QPA_PLATFORM", None)  # DISPLAY is pytest-xvfb's
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    proc = subprocess.run([sys.executable, str(script), str(marker)], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=180)
    assert "main returned 0 running: ['darboux-estimate']" in proc.stdout, (proc.stdout, proc.stderr)
    assert proc.returncode == 0, proc.stderr
    assert "terminate called" not in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert "waiting for a background job to stop" in proc.stderr, proc.stderr
    assert marker.exists(), "the interpreter was finalised while the job was still running"


def test_the_exit_wait_is_bounded_and_silent_without_jobs(monkeypatch, capsys):
    import app.__main__ as entry

    joined = []
    monkeypatch.setattr(entry, "live_job_threads", lambda: [])
    monkeypatch.setattr(entry, "join_job_threads", lambda timeout: joined.append(timeout) or [])
    entry.join_jobs_at_exit()
    assert joined == [] and capsys.readouterr().err == ""
    monkeypatch.setattr(entry, "live_job_threads", lambda: ["darboux-estimate"])
    entry.join_jobs_at_exit()
    assert joined == [entry.EXIT_JOIN_S] and 0 < entry.EXIT_JOIN_S <= 300
