"""``darboux [FILE]`` / ``python -m app``: open the viewer.

With ``--screenshot PATH`` the window opens, estimates, renders, saves a PNG of the
whole window and exits (0 on success, 1 with a message on failure).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from core.estimate import AUTO_PASSES

from .teach import cli as teach_cli

__all__ = ["main", "build_parser"]


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
    p.add_argument("--noise", type=float, metavar="PCT", help="Gaussian noise, sigma in %% of the mean spacing")
    p.add_argument("--field", metavar="NAME", help="displayed field: mean (H), gaussian (K), k1, k2, shape_index, "
                   "curvedness, normal_dev, err_mean, err_gaussian, ...")
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


def _state_from_args(args, parser):
    """Validated start-up parameters (raises SystemExit via parser.error)."""
    import core

    from .fields import resolve_field
    from .state import ViewerState

    state = ViewerState()
    values = {}
    for name, valid in (("method", args.method), ("compare", args.compare)):
        if valid is not None and valid.lower() not in core.METHODS:
            parser.error(f"--{name} {valid!r} is unknown; valid methods: {', '.join(core.METHODS)}")
    if args.method:
        values["method"] = args.method.lower()
    if args.compare:
        values["compare_method"] = args.compare.lower()
    if args.k is not None:
        if args.k.lower() == "auto":
            values["k_auto"] = True
        else:
            try:
                k = int(args.k)
            except ValueError:
                parser.error(f"--k must be an integer or auto, got {args.k!r}")
            if k < 3:
                parser.error(f"--k must be at least 3, got {k}")
            values["k"], values["k_auto"] = k, False
    if args.passes is not None:
        if args.passes < 0:
            parser.error(f"--passes must be >= 0, got {args.passes}")
        values["passes"] = args.passes
    if args.noise is not None:
        if not args.noise >= 0:
            parser.error(f"--noise must be >= 0, got {args.noise}")
        values["noise"] = args.noise
    if args.field:
        try:
            values["field"] = resolve_field(args.field)
        except ValueError as exc:
            parser.error(str(exc))
    if args.glyphs:
        for g in (x.strip().lower() for x in args.glyphs.split(",") if x.strip()):
            key = {"e1": "show_e1", "e2": "show_e2", "n": "show_normals", "normals": "show_normals"}.get(g)
            if key is None:
                parser.error(f"--glyphs: {g!r} is unknown; valid: e1, e2, normals")
            values[key] = True
    if args.pick is not None:
        values["picked"] = args.pick
    state.set(**values)
    return state


def main(argv: list[str] | None = None) -> int:
    args_list = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser()
    args = parser.parse_args(args_list)
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        parser.error(f"--size must look like 1440x900, got {args.size!r}")
    if args.shape:
        import core.shapes

        if args.shape not in core.shapes.SHAPES:
            parser.error(f"--shape {args.shape!r} is unknown; valid shapes: {', '.join(core.shapes.SHAPES)}")
    if args.points < 10:
        parser.error(f"--points must be at least 10, got {args.points}")
    state = _state_from_args(args, parser)
    teach = teach_cli.settings_from_args(args, parser)

    from PySide6.QtCore import QTimer
    from PySide6.QtWidgets import QApplication

    from . import DEFAULT_CLOUD
    from .window import MainWindow

    app = QApplication.instance() or QApplication([sys.argv[0], *args_list])
    app.setApplicationName("Darboux")
    app.setOrganizationName("Darboux")
    window = MainWindow(state=state, dialogs=args.screenshot is None)
    if args.screenshot is None:
        window.notifier.install_hooks()
    if args.screenshot and args.view_only:
        for dock in (window.controls_dock, window.histogram_dock, window.inspector_dock):
            dock.hide()  # a figure: the 3D view(s) get the whole window
    window.resize(width, height)
    window.show()
    if teach:
        window.teach.configure(**teach)

    outcome = {"code": 0}
    if args.screenshot:
        target = Path(args.screenshot)
        done = {"saved": False}

        def fail(message: str) -> None:
            if done["saved"]:
                return
            done["saved"] = True
            print(f"darboux: {message}", file=sys.stderr)
            outcome["code"] = 1
            window.close()

        def save() -> None:
            if done["saved"]:
                return
            done["saved"] = True
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
                ok = window.save_screenshot(target, whole_window=not args.view_only)
            except Exception as exc:  # noqa: BLE001
                ok = False
                print(f"darboux: could not save {target}: {exc}", file=sys.stderr)
            if ok:
                print(f"darboux: saved {target}")
            else:
                print(f"darboux: could not write the screenshot {target}", file=sys.stderr)
                outcome["code"] = 1
            window.close()

        def on_result(_out) -> None:
            if pick is not None and window.state.picked is None:
                window.state.set(picked=pick)
            # let the event loop paint the new frame (and the teaching overlays, if shown)
            window.teach.when_ready(lambda: QTimer.singleShot(400, save))

        window.result_shown.connect(on_result)
        window.estimator.failed.connect(lambda msg: fail(f"the estimate failed: {msg}"))
        window.notifier.notified.connect(lambda note: fail(note.message) if note.level == "error" else None)
        QTimer.singleShot(int(args.timeout * 1000), lambda: fail(f"no result after {args.timeout:g} s"))

    pick = state.picked  # loading a cloud clears the pick: restore it on the first result
    # load after the window exists so that a bad file is reported through the notifier
    if teach.get("example"):
        pass  # the example loads its shape
    elif args.shape:
        window.load_shape(args.shape, args.points)
    else:
        opened = window.open_file(args.file, remember=args.screenshot is None) if args.file else window.open_default()
        if not opened:
            if args.screenshot:
                window.close()
                return 1
            if args.file and DEFAULT_CLOUD.exists():
                window.open_default()  # keep the app useful; the error was shown
    if pick is not None and args.screenshot is None:
        window.result_shown.connect(lambda _o: window.state.set(picked=pick) if window.state.picked is None else None)
    code = app.exec()
    window.shutdown()
    window.notifier.uninstall_hooks()
    return outcome["code"] or code


if __name__ == "__main__":
    sys.exit(main())
