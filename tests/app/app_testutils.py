"""Shared by the viewer tests: image checks, waiting for a result, an estimate held until let go,
and what holds the GUI thread (:class:`GuiBeat`)."""

from __future__ import annotations

import contextlib
import gc
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np


def image_array(qimage) -> np.ndarray:
    """(H, W, 3) uint8 RGB copy of a QImage."""
    from PySide6.QtGui import QImage

    img = qimage.convertToFormat(QImage.Format.Format_RGB888)
    w, h, stride = img.width(), img.height(), img.bytesPerLine()
    buf = np.frombuffer(img.constBits(), dtype=np.uint8, count=stride * h).reshape(h, stride)
    return buf[:, : 3 * w].reshape(h, w, 3).copy()


def colour_stats(arr: np.ndarray) -> dict:
    """How much of an image is not background, and how colourful it is."""
    flat = arr.reshape(-1, 3).astype(int)
    background = np.all(flat >= 245, axis=1)
    fg = flat[~background]
    saturation = (fg.max(axis=1) - fg.min(axis=1)) if len(fg) else np.zeros(0)
    return {
        "foreground": float(np.mean(~background)),
        "unique": int(len(np.unique(flat // 8, axis=0))),
        "coloured": float(np.mean(saturation > 60)) if len(fg) else 0.0,
        "std": float(flat.std()),
    }


class _Result:
    """What :func:`wait_result` collected: ``args`` like pytest-qt's blocker."""

    def __init__(self):
        self.out = None
        self.failure = None

    @property
    def args(self):
        return [self.out]


@contextlib.contextmanager
def wait_result(qtbot, window, timeout: int = 60_000):
    """Wait for the window's next drawn result; fail at once if the estimate fails."""
    import pytest

    got = _Result()

    def on_result(out):
        if got.out is None:
            got.out = out

    def on_failed(message):
        if got.failure is None:
            got.failure = message

    window.result_shown.connect(on_result)
    window.estimator.failed.connect(on_failed)
    try:
        yield got
        qtbot.waitUntil(lambda: got.out is not None or got.failure is not None, timeout=timeout)
    finally:
        window.result_shown.disconnect(on_result)
        window.estimator.failed.disconnect(on_failed)
    if got.out is None:
        pytest.fail(f"the estimate failed: {got.failure}")


ROOT = Path(__file__).resolve().parents[2]


def run_app_cli(*args, timeout=240):
    """``python -m app ARGS`` in a process of its own, on the X server pytest-xvfb started."""
    env = dict(os.environ)
    env.pop("QT_QPA_PLATFORM", None)  # DISPLAY is inherited
    env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
    return subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=timeout)


def on_next_preview(window, action):
    """Run ``action(out)`` inside the next preview's signal (before its full result can come)."""
    seen = []

    def slot(out):
        window.preview_shown.disconnect(slot)
        seen.append(action(out))

    window.preview_shown.connect(slot)
    return seen


class GuiBeat:
    """A 0 ms timer on the GUI thread, one beat a turn of the event loop. ``longest_block()``:
    the most CPU seconds the GUI thread spent between two beats (``time.thread_time``): the work
    that held the event loop, not the wall time a loaded machine made it wait, so a busy CI
    machine does not stretch it; compare it with :func:`full_frames_cpu` of the same run.
    The collector is off from :meth:`start` to :meth:`stop` (its pauses block no view)."""

    def __init__(self):
        from PySide6.QtCore import QTimer

        self.cpu = []
        self.timer = QTimer()
        self.timer.setInterval(0)
        self.timer.timeout.connect(lambda: self.cpu.append(time.thread_time()))

    def start(self) -> None:
        gc.disable()
        self.timer.start()

    def stop(self) -> None:
        self.timer.stop()
        gc.enable()

    def longest_block(self) -> float:
        return float(np.max(np.diff(self.cpu))) if len(self.cpu) > 1 else 0.0


def full_frames_cpu(plotters, repeats: int = 3) -> float:
    """The GUI thread's CPU seconds to render each of ``plotters`` once as it stands (the
    median of ``repeats``): the yardstick of a frame on this machine, in this run."""
    spent = []
    for _ in range(repeats):
        start = time.thread_time()
        for plotter in plotters:
            plotter.render_window.Render()
        spent.append(time.thread_time() - start)
    return float(np.median(spent))


def hold_first_estimate(monkeypatch):
    """The viewer's ``core.estimate``: the first call runs until it is cancelled, however fast
    the machine, then ends only when the test sets the event returned (or after 30 s); the
    later calls are real. Returns ``(event, states)``: the first call's "running", then "ended"."""
    import app.worker
    import core

    real, states, release = core.estimate, [], threading.Event()

    def hold_first(*args, progress=None, **kwargs):
        if states:
            return real(*args, progress=progress, **kwargs)
        states.append("running")
        t0 = time.monotonic()
        while progress(0.0, "held") is not False and time.monotonic() - t0 < 30:
            time.sleep(0.02)
        release.wait(30)
        states.append("ended")
        raise core.Cancelled("held until cancelled")

    monkeypatch.setattr(app.worker.core, "estimate", hold_first)
    return release, states
