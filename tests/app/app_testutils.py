"""Image checks shared by the viewer tests."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
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
