"""``darboux [FILE]`` / ``python -m app``: open the viewer.

With ``--screenshot PATH`` the window opens, estimates, renders, saves a PNG of the
whole window and exits (0 on success, 1 with a message on failure).
"""

from __future__ import annotations

import argparse
import atexit
import math
import signal
import sys

from PySide6.QtCore import QSettings, QTimer
from PySide6.QtWidgets import QApplication

import core
import core.shapes
from core.tuning import AUTO_PASSES

from . import DEFAULT_CLOUD
from . import file_fields
from .fields import is_file_field, resolve_field
from .hard_exit import end_now, exit_at_once
from .jobs import join_job_threads, live_job_threads
from .persist import restore_layout, restore_state
from .state import ORIENTATIONS, ViewerState

from .teach import cli as teach_cli

__all__ = ["main", "run", "build_parser"]


def _viewpoint(text: str) -> tuple:
    """``--viewpoint X,Y,Z`` (core's CLI spelling) as a tuple of 3 finite floats."""
    try:
        vals = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"viewpoint {text!r} must be x,y,z (three numbers)") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"viewpoint {text!r} must be x,y,z (three finite numbers)")
    return vals


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="darboux",
        description="Live curvature of a point cloud (normal fitting after Cheng & Zhang 2009). "
        "Without FILE or --shape the bundled Stanford bunny is shown.",
    )
    p.add_argument("file", nargs="?", metavar="FILE", help="point cloud to open (PLY, XYZ/CSV, LAS, ... as core reads)")
    p.add_argument("--shape", metavar="NAME", help="open a synthetic shape instead (torus, sphere, cylinder, saddle, ...)")
    p.add_argument("--points", type=int, default=5000, metavar="N", help="points of the synthetic shape (default 5000)")
    p.add_argument("--k", metavar="N|auto", help="neighbours per point, or auto (default: auto for NF/NR)")
    p.add_argument("--method", metavar="NAME", help="estimator from core.METHODS (default nr)")
    p.add_argument("--passes", type=int, metavar="N",
                   help=f"NR refinement passes (0 = NF; default {AUTO_PASSES}, a maximum with automatic k)")
    orient = p.add_mutually_exclusive_group()
    orient.add_argument("--orientation", choices=list(ORIENTATIONS),
                        help="how estimated normals are oriented: auto (outward; the file's normals kept, the "
                        "default), propagate (up, +z) or keep (the file's normals)")
    orient.add_argument("--viewpoint", type=_viewpoint, metavar="X,Y,Z",
                        help="orient the normals toward this point (the scanner's position, for scans of scenes; "
                        "write --viewpoint=-1,0,2 when X is negative)")
    p.add_argument("--noise", type=float, metavar="PCT", help="Gaussian noise, sigma in %% of the mean spacing")
    p.add_argument("--field", metavar="NAME", help="displayed field: mean (H), gaussian (K), k1, k2, shape_index, "
                   "curvedness, k_point, degree_point, normal_dev, err_mean, err_gaussian, ...; or the file's own: "
                   "rgb (its colours), file:NAME (its field NAME: file:intensity, file:scan, ...)")
    p.add_argument("--compare", metavar="METHOD", help="show a second method side by side")
    p.add_argument("--glyphs", metavar="LIST", help="comma-separated glyphs to show: e1,e2,normals")
    p.add_argument("--pick", type=int, metavar="INDEX", help="inspect this point (panel, neighbourhood, frame)")
    teach_cli.add_arguments(p)
    p.add_argument("--screenshot", metavar="PATH", help="save a PNG of the window once the result is shown, then exit")
    p.add_argument("--view-only", action="store_true",
                   help="with --screenshot: hide the panels and save only the 3D view(s), at --size")
    p.add_argument("--size", default="1440x900", metavar="WxH", help="window size (default 1440x900)")
    p.add_argument("--timeout", type=float, default=300.0, metavar="S", help="give up on --screenshot after S seconds")
    return p


_GLYPHS = {"e1": "show_e1", "e2": "show_e2", "n": "show_normals", "normals": "show_normals"}


def _k_values(text: str, parser) -> dict:
    if text.lower() == "auto":
        return {"k_auto": True}
    try:
        k = int(text)
    except ValueError:
        parser.error(f"--k must be an integer or auto, got {text!r}")
    if k < 3:
        parser.error(f"--k must be at least 3, got {k}")
    return {"k": k, "k_auto": False}


def _method_values(args, parser) -> dict:
    values = {}
    for flag, key, name in (("method", "method", args.method), ("compare", "compare_method", args.compare)):
        if name is not None:
            if name.lower() not in core.METHODS:
                parser.error(f"--{flag} {name!r} is unknown; valid methods: {', '.join(core.METHODS)}")
            values[key] = name.lower()
    return values


def _display_values(args, parser) -> dict:
    values = {}
    if args.field:
        try:
            values["field"] = resolve_field(args.field)
        except ValueError as exc:
            parser.error(str(exc))
    for g in (x.strip().lower() for x in (args.glyphs or "").split(",") if x.strip()):
        if g not in _GLYPHS:
            parser.error(f"--glyphs: {g!r} is unknown; valid: e1, e2, normals")
        values[_GLYPHS[g]] = True
    if args.pick is not None:
        values["picked"] = args.pick
    return values


def _state_from_args(args, parser) -> ViewerState:
    """Validated start-up parameters (raises SystemExit via parser.error)."""
    values = _method_values(args, parser)
    if args.k is not None:
        values.update(_k_values(args.k, parser))
    for flag, number in (("passes", args.passes), ("noise", args.noise)):
        if number is not None:
            if not number >= 0:
                parser.error(f"--{flag} must be >= 0, got {number}")
            values[flag] = number
    if args.viewpoint is not None or args.orientation is not None:
        values["orientation"] = args.viewpoint if args.viewpoint is not None else args.orientation
    values.update(_display_values(args, parser))
    state = ViewerState()
    state.set(**values)
    state.given = set(values)  # what the command line fixed (not overridden by remembered values)
    return state


#: ``--size`` bounds, pixels: the 3D view's minimum size (app/window.py) and the largest
#: frame buffer side OpenGL implementations commonly allow (llvmpipe's among them).
MIN_SIZE, MAX_SIDE = (320, 240), 16384


def _window_size(text: str, parser) -> tuple[int, int]:
    """``--size WxH``, within :data:`MIN_SIZE` and :data:`MAX_SIDE`."""
    allowed = (f"allowed: WIDTHxHEIGHT in pixels, from {MIN_SIZE[0]}x{MIN_SIZE[1]} to {MAX_SIDE}x{MAX_SIDE}, "
               "like 1440x900")
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        parser.error(f"--size {text!r} is not a size; {allowed}")
    if not (MIN_SIZE[0] <= width <= MAX_SIDE and MIN_SIZE[1] <= height <= MAX_SIDE):
        parser.error(f"--size {text!r} is out of range; {allowed}")
    return width, height


def _check_args(args, parser) -> tuple[int, int]:
    width, height = _window_size(args.size, parser)
    if args.shape and args.shape not in core.shapes.SHAPES:
        parser.error(f"--shape {args.shape!r} is unknown; valid shapes: {', '.join(core.shapes.SHAPES)}")
    if args.points < 10:
        parser.error(f"--points must be at least 10, got {args.points}")
    if args.pick is not None and not 0 <= args.pick < (args.points if args.shape else math.inf):
        upper = f" and below --points {args.points} (0 to {args.points - 1})" if args.shape else ""
        parser.error(f"--pick {args.pick} is out of range; allowed: a point index >= 0{upper}")
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        parser.error(f"--timeout {args.timeout:g} is out of range; allowed: a number of seconds > 0")
    return width, height


def pick_error(pick: int | None, out) -> str | None:
    """Why ``--pick`` cannot be used on the cloud of result ``out`` (its index is past the
    last point: a file's size is known once read), or None."""
    n = len(out.points)
    if pick is None or pick < n:
        return None
    return (f"--pick {pick} is out of range for {out.request.source.name}; allowed: 0 to {n - 1:,} "
            f"(it has {n:,} points)")


def field_error(field: str, source) -> str | None:
    """Why ``--field`` cannot be shown for ``source``: a field of the file that it has not
    (the file's fields are known once it is read), or None."""
    if not is_file_field(field) or file_fields.find(field, source.field_specs) is not None:
        return None
    return file_fields.unknown_text(field, source.field_specs, source.name)


def _quit_on_sigint(app: QApplication, outcome: dict) -> QTimer:
    """Ctrl-C quits the event loop with exit status 130 (Qt's loop never returns to Python
    otherwise, so a Python signal handler would not run: a 200 ms timer gives it the chance)."""

    def on_sigint(*_args):
        outcome["code"] = 130
        QTimer.singleShot(0, app.quit)  # queued: a quit() before exec() starts the loop is lost (Ctrl-C ignored)

    signal.signal(signal.SIGINT, on_sigint)
    timer = QTimer()
    timer.timeout.connect(lambda: None)
    timer.start(200)
    return timer


class _Screenshot:
    """``--screenshot``: save the window once the first full result is drawn, then close."""

    def __init__(self, window, args, outcome: dict, pick, size):
        from .actions import SCREENSHOT_SUFFIX, with_default_suffix  # the window is up: its modules are loaded

        self.window, self.outcome, self.pick = window, outcome, pick
        self.target, self.whole = with_default_suffix(args.screenshot, SCREENSHOT_SUFFIX), not args.view_only
        self.size = size  # asked: (width, height)
        self.done = False
        self.field = window.state.field  # as given (the state falls back to H where it is not drawn)
        window.loader.loaded.connect(self.on_loaded)
        window.result_shown.connect(self.on_result)
        window.estimator.failed.connect(lambda msg: self.fail(f"the estimate failed: {msg}"))
        # a warning (a field not available, what a reader skipped) reaches stderr through the log
        window.notifier.notified.connect(lambda note: self.fail(note.message) if note.level == "error" else None)
        QTimer.singleShot(int(min(args.timeout, 2e6) * 1000),  # (a QTimer takes at most ~24 days)
                          lambda: self.fail(f"no result after {args.timeout:g} s"))

    def fail(self, message: str, code: int = 1) -> None:
        if not self.done:
            self.done = True
            print(f"darboux: {message}", file=sys.stderr)
            self.outcome["code"] = code
            self.window.close()

    def on_loaded(self, _ticket, source) -> None:
        """A file field the file has not is refused as an unknown field is (argparse's status 2),
        once the file is read and before its estimate."""
        problem = field_error(self.field, source)
        if problem:
            self.fail(f"error: {problem}", code=2)

    def on_result(self, out) -> None:
        problem = pick_error(self.pick, out)
        if problem:  # refused as a bad argument is (argparse's status 2), once the file's size is known
            self.fail(f"error: {problem}", code=2)
            return
        if self.pick is not None and self.window.state.picked is None:
            self.window.state.set(picked=self.pick)
        # let the event loop paint the new frame (and the teaching overlays, if shown)
        self.window.teach.when_ready(lambda: QTimer.singleShot(400, self.save))

    def save(self) -> None:
        if self.done:
            return
        self.done = True
        _size_note(self.window, *self.size, not self.whole)  # the size the picture has
        try:
            self.target.parent.mkdir(parents=True, exist_ok=True)
            ok = self.window.save_screenshot(self.target, whole_window=self.whole)
        except Exception as exc:  # noqa: BLE001
            ok = False
            print(f"darboux: could not save {self.target}: {exc}", file=sys.stderr)
        if ok:
            print(f"darboux: saved {self.target}")
        else:
            print(f"darboux: could not write the screenshot {self.target}", file=sys.stderr)
            self.outcome["code"] = 1
        self.window.close()


def _open_first(window, args, pick, *, example: bool = False) -> None:
    """Load after the window exists, so that a bad file is reported through the notifier
    (nothing when a guided example of the Teach menu loads its own shape)."""
    interactive = args.screenshot is None
    if example:
        pass
    elif args.shape:
        window.load_shape(args.shape, args.points)
    elif args.file:
        window.open_file(args.file, remember=interactive)
        if interactive and DEFAULT_CLOUD.exists():
            # keep the app useful when the file cannot be read (the error was shown)
            window.loader.failed.connect(lambda *_: window.open_default() if window.state.source is None else None)
    else:
        window.open_default()
    if pick is not None and interactive:
        def on_first_result(out):
            window.result_shown.disconnect(on_first_result)
            problem = pick_error(pick, out)
            if problem:
                window.notifier.warning(problem)
            elif window.state.picked is None:
                window.state.set(picked=pick)

        window.result_shown.connect(on_first_result)


def _size_note(window, width: int, height: int, view_only: bool) -> None:
    """Say so when the window could not take ``--size`` (e.g. smaller than its panels allow)."""
    got = (window.width(), window.height())
    if got != (width, height):
        larger = got[0] > width or got[1] > height
        why = (" (smaller than the window with its panels can be; --view-only hides them)"
               if larger and not view_only else "")
        print(f"darboux: note: the window could not be made {width}x{height}; it is {got[0]}x{got[1]}{why}",
              file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    args_list = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(args_list)
    width, height = _check_args(args, parser)
    state = _state_from_args(args, parser)
    teach = teach_cli.settings_from_args(args, parser)
    before = signal.signal(signal.SIGINT, exit_at_once)
    try:
        return _run_window(args, args_list, state, teach, (width, height))
    finally:
        signal.signal(signal.SIGINT, before)


#: How long a process that called :func:`main` itself (a script, a notebook) waits at its
#: exit for the background jobs its window left running (a kernel numba compiles), s.
EXIT_JOIN_S = 120.0


def join_jobs_at_exit() -> None:
    """At the exit of a process that called :func:`main` (``atexit``): let the jobs the window
    abandoned end before the interpreter is finalised around them (a job inside numba's
    compiler or a kernel then ended in "terminate called without an active exception", an
    abort, or SIGSEGV). :func:`run` ends the process itself first (:func:`app.hard_exit.end_now`)."""
    if live_job_threads():
        print("darboux: waiting for a background job to stop…", file=sys.stderr, flush=True)
        join_job_threads(EXIT_JOIN_S)


def _run_window(args, args_list, state, teach, size) -> int:
    """The window's life: build it, open the first cloud, run the event loop, shut down."""
    width, height = size
    from .window import MainWindow  # noqa: PLC0415 - pyvistaqt/VTK only once the arguments are valid

    app = QApplication.instance() or QApplication([sys.argv[0], *args_list])
    atexit.unregister(join_jobs_at_exit)  # (once; and before Qt's own clean-up, atexit runs the last first)
    atexit.register(join_jobs_at_exit)
    app.setApplicationName("Darboux")
    app.setOrganizationName("Darboux")
    settings = QSettings("Darboux", "darboux")
    interactive = args.screenshot is None  # a screenshot is reproducible: defaults + arguments only
    if interactive:
        restore_state(state, settings, skip=state.given)
    window = MainWindow(state=state, settings=settings, dialogs=interactive)
    outcome = {"code": 0}
    sigint_timer = _quit_on_sigint(app, outcome)
    if interactive:
        window.notifier.install_hooks()
        restore_layout(window, settings)
    elif args.view_only:
        for dock in (window.controls_dock, window.histogram_dock, window.inspector_dock):
            dock.hide()  # a figure: the 3D view(s) get the whole window
    window.resize(width, height)
    window.show()
    if interactive:  # (a screenshot says so when it is saved: the compare view can still widen the window)
        _size_note(window, width, height, args.view_only)
    if teach:
        window.teach.configure(**teach)
    pick = state.picked  # loading a cloud clears the pick: restore it on the first result
    shot = None if interactive else _Screenshot(window, args, outcome, pick, size)
    _open_first(window, args, pick, example=bool(teach.get("example")))
    code = app.exec()
    del shot
    sigint_timer.stop()
    window.shutdown()
    window.notifier.uninstall_hooks()
    return outcome["code"] or code


def run() -> None:
    """The ``darboux`` command: :func:`main`, then exit. Where a background job is still
    running (abandoned by the window's shutdown, e.g. numba compiling a kernel when Ctrl-C
    or a close came), the process ends at once instead of finalising the interpreter around
    it, which crashed (SIGSEGV, an LLVM assertion: 3 of 12 Ctrl-C tries with numba compiling).
    The window has saved its settings by then, and jobs only read (an export runs on the GUI
    thread)."""
    code = main()
    if live_job_threads():
        end_now(code)
    sys.exit(code)


if __name__ == "__main__":
    run()
