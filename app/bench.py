"""``python -m app.bench``: how the viewer answers a hand on a slider (issue 11).

Prints one table (Markdown) with, per cloud size:

- start to first picture, cold and warm numba cache (a fresh ``python -m app`` process
  each, ``--screenshot``; the cold one with an empty ``NUMBA_CACHE_DIR``);
- slider change (passes) -> first updated picture (preview) and -> final result;
- the longest stall of the GUI thread (a 10 ms ``QTimer`` heartbeat) while the file
  is read and estimated, up to the final result arriving, and including its first draw;
- cancel -> idle (busy flag down, progress hidden);
- frame time while turning the camera (level of detail active), and still;
- with ``--cycles N``, resident memory over N open/close cycles of the main window.

Heavy: 1M/5M take minutes and GBs; pick sizes with ``--sizes``. Run it on a quiet machine.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PySide6.QtCore import QCoreApplication, QEvent, QSettings, QTimer
from PySide6.QtWidgets import QApplication

import core.io
import core.shapes

from . import DEFAULT_CLOUD

__all__ = ["main"]

_SIZES = {"bunny": None, "200k": 200_000, "1M": 1_000_000, "5M": 5_000_000}


class Heartbeat:
    """The longest gap between 10 ms timer ticks on the GUI thread."""

    def __init__(self):
        self.last = time.perf_counter()
        self.worst = 0.0
        self.timer = QTimer()
        self.timer.setInterval(10)
        self.timer.timeout.connect(self._tick)

    def _tick(self):
        now = time.perf_counter()
        self.worst = max(self.worst, now - self.last)
        self.last = now

    def start(self):
        self.last, self.worst = time.perf_counter(), 0.0
        self.timer.start()

    def stop(self) -> float:
        self.timer.stop()
        return self.worst


def _wait(app, predicate, timeout: float) -> float:
    t0 = time.perf_counter()
    while not predicate():
        if time.perf_counter() - t0 > timeout:
            raise TimeoutError(f"no answer within {timeout:g} s")
        app.processEvents()
        time.sleep(0.002)
    return time.perf_counter() - t0


def _cloud_file(label: str, tmp: Path) -> Path:
    n = _SIZES[label]
    if n is None:
        return DEFAULT_CLOUD
    path = tmp / f"torus-{label}.ply"
    if not path.exists():
        s = core.shapes.torus(n, seed=1)
        core.io.write_cloud(path, s.points, normals=s.normals)
    return path


def _load_and_estimate(app, window, path: Path, timeout: float) -> dict:
    beat, got = Heartbeat(), {}
    window.result_shown.connect(lambda out: got.setdefault("final", time.perf_counter()))
    window.estimator.result.connect(lambda out: got.setdefault("arrived", time.perf_counter()))
    beat.start()
    t0 = time.perf_counter()
    window.open_file(path, remember=False)
    _wait(app, lambda: "arrived" in got, timeout)
    stall_estimate = beat.worst
    _wait(app, lambda: "final" in got, timeout)
    _wait(app, lambda: time.perf_counter() - got["final"] > 0.3, timeout)
    return {"load+estimate s": got["final"] - t0, "stall load+estimate ms": 1000 * stall_estimate,
            "stall incl. first draw ms": 1000 * beat.stop()}


def _slider(app, window, timeout: float) -> dict:
    got = {}
    window.preview_shown.connect(lambda out: got.setdefault("preview", time.perf_counter()))
    window.result_shown.connect(lambda out: got.setdefault("final2", time.perf_counter()))
    t0 = time.perf_counter()
    window.state.set(passes=2 if window.state.passes != 2 else 3)
    window.request_estimate()  # what the debounce timer does 120 ms after the last move
    _wait(app, lambda: "final2" in got, timeout)
    first = got.get("preview", got["final2"])
    return {"slider -> first picture s": first - t0, "slider -> final s": got["final2"] - t0}


def _cancel(app, window, timeout: float) -> dict:
    window.state.set(noise=5.0)  # a new noisy copy: the whole pipeline runs again
    window.request_estimate()
    _wait(app, lambda: window.estimator.busy, timeout)
    t_busy = time.perf_counter()
    _wait(app, lambda: time.perf_counter() - t_busy > 0.5, timeout)  # well inside the estimate
    t0 = time.perf_counter()
    window.progress.cancel.click()
    _wait(app, lambda: not window.estimator.busy and not window.progress.shown, timeout)
    return {"cancel -> idle ms": 1000 * (time.perf_counter() - t0)}


def _frames(app, window, n: int = 6) -> dict:
    scene, plotter = window.scene, window.plotter
    out = {}
    for label, moving in (("frame moving s", True), ("frame still s", False)):
        if moving:
            scene.lod.begin()
        times = []
        for _ in range(n if moving else 2):
            plotter.camera.Azimuth(5)
            t = time.perf_counter()
            plotter.render()
            times.append(time.perf_counter() - t)
        if moving:
            scene.lod.end(render=False)
        out[label] = float(np.median(times))
    return out


def bench_size(label: str, tmp: Path, timeout: float) -> dict:
    """All in-process measurements for one cloud."""
    from .window import MainWindow  # noqa: PLC0415 - after QApplication exists

    app = QApplication.instance() or QApplication([sys.argv[0]])
    path = _cloud_file(label, tmp)
    settings = QSettings(str(tmp / "bench.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings=settings, dialogs=False)
    window.resize(1440, 900)
    window.show()
    _wait(app, window.isVisible, 10)
    row = {"cloud": label}
    try:
        row.update(_load_and_estimate(app, window, path, timeout))
        row.update(_slider(app, window, timeout))
        row.update(_frames(app, window))
        row.update(_cancel(app, window, timeout))
    finally:
        window.close()
        QCoreApplication.processEvents()
    return row


def frames_only(label: str) -> dict:
    """Frame times of a big cloud without estimating it (5M: the estimate alone takes minutes)."""
    from .scene import CloudScene, make_plotter  # noqa: PLC0415 - after QApplication exists

    app = QApplication.instance() or QApplication([sys.argv[0]])
    pts = core.shapes.torus(_SIZES[label] or 28_088, seed=1).points
    plotter = make_plotter()
    plotter.resize(1100, 850)
    plotter.show()
    _wait(app, plotter.isVisible, 10)
    scene = CloudScene(plotter)
    scene.set_cloud(pts, reset_camera="oblique")
    scene.set_values(pts[:, 2], title="z", cmap="RdBu_r", clim=(-1.0, 1.0))
    plotter.render()

    class _Window:  # what _frames reads
        pass

    window = _Window()
    window.scene, window.plotter = scene, plotter
    try:
        return {"cloud": f"{label} (frames only)", **_frames(app, window)}
    finally:
        scene.close()
        plotter.close()


def cycles(n: int, tmp: Path, timeout: float) -> str:
    """Resident memory over ``n`` open/estimate/close cycles of the main window (a 5000-point
    torus each): a closed window must be freed (issue 10 saw 583 -> 2406 MB over 50)."""
    import gc  # noqa: PLC0415 - only this measurement needs it

    from .source import make_shape  # noqa: PLC0415
    from .window import MainWindow  # noqa: PLC0415 - after QApplication exists

    app = QApplication.instance() or QApplication([sys.argv[0]])
    cloud, settings = make_shape("torus", 5000), QSettings(str(tmp / "cycles.ini"), QSettings.Format.IniFormat)
    rss = []
    for _ in range(n):
        window, got = MainWindow(settings=settings, dialogs=False), {}
        window.show()
        window.result_shown.connect(lambda out: got.setdefault("done", True))
        window.set_source(cloud)
        _wait(app, lambda: "done" in got, timeout)
        window.close()
        window.deleteLater()
        del window
        for _ in range(3):
            QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
            QCoreApplication.processEvents()
        gc.collect()
        with open(f"/proc/{os.getpid()}/statm") as f:
            rss.append(int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20)
    warm = min(4, n - 1)
    return (f"{n} open/close cycles: RSS {rss[0]:.0f} MB after the first, {rss[warm]:.0f} MB after cycle "
            f"{warm + 1}, {rss[-1]:.0f} MB after the last ({rss[-1] - rss[warm]:+.0f} MB)")


def startup(cold: bool, tmp: Path, timeout: float) -> float:
    """Seconds from ``python -m app --screenshot`` to the first full picture saved."""
    env = dict(os.environ)
    if cold:
        env["NUMBA_CACHE_DIR"] = tempfile.mkdtemp(prefix="darboux-cold-", dir=tmp)
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "app", "--screenshot", str(tmp / "start.png"),
                           "--timeout", str(timeout)], env=env, capture_output=True, text=True, timeout=timeout + 60)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr.strip()[-500:])
    return time.perf_counter() - t0


def _table(rows: list[dict]) -> str:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        cells = [f"{r[k]:.3g}" if isinstance(r.get(k), float) else str(r.get(k, "")) for k in keys]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m app.bench", description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="bunny,200k", help=f"comma-separated from {', '.join(_SIZES)}")
    p.add_argument("--frames", default="", help="sizes to time turning only, without estimating (e.g. 5M)")
    p.add_argument("--startup", action="store_true", help="also time start-up, cold and warm numba cache")
    p.add_argument("--cycles", type=int, default=0, help="also measure memory over N open/close cycles (e.g. 50)")
    p.add_argument("--timeout", type=float, default=600.0)
    args = p.parse_args(argv)
    sizes = [s.strip() for s in args.sizes.split(",") if s.strip()]
    frames = [s.strip() for s in args.frames.split(",") if s.strip()]
    bad = [s for s in sizes + frames if s not in _SIZES]
    if bad:
        p.error(f"--sizes {bad!r} unknown; valid: {', '.join(_SIZES)}")
    with tempfile.TemporaryDirectory(prefix="darboux-bench-") as tmp:
        tmp = Path(tmp)
        if args.startup:
            cold, warm = startup(True, tmp, args.timeout), startup(False, tmp, args.timeout)
            print(f"start -> first picture (bunny, --screenshot): cold cache {cold:.1f} s, warm {warm:.1f} s\n")
        rows = []
        for label in sizes:
            rows.append(bench_size(label, tmp, args.timeout))
            print(f"{label}: done", file=sys.stderr, flush=True)
        rows += [frames_only(label) for label in frames]
        if rows:
            print(_table(rows))
        if args.cycles > 0:
            print("\n" + cycles(args.cycles, tmp, args.timeout))
    return 0


if __name__ == "__main__":
    sys.exit(main())
