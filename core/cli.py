"""Command line: ``darboux-cli`` / ``python -m core`` — estimate, info, bench."""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

BENCHES = ("paper", "perf", "accuracy", "teach")


class _Bar:
    """A one-line progress bar on stderr (only when it is a terminal or forced)."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self._last = -1

    def __call__(self, fraction, stage):
        if not self.enabled:
            return
        pct = int(fraction * 100)
        if pct != self._last:
            self._last = pct
            bar = "#" * (pct // 4)
            sys.stderr.write(f"\r{stage:>12} [{bar:<25}] {pct:3d}%")
            sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")


def _parse_option(text):
    key, sep, value = text.partition("=")
    if not sep:
        raise argparse.ArgumentTypeError(f"option {text!r} must look like key=value")
    try:
        value = int(value)
    except ValueError:
        pass
    return key, value


def _k(text):
    if text == "auto":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"k {text!r} must be an integer or auto") from None


def _viewpoint(text):
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"viewpoint {text!r} must be x,y,z") from None
    if len(vals) != 3:
        raise argparse.ArgumentTypeError(f"viewpoint {text!r} must be x,y,z")
    return vals


def _cmd_estimate(args) -> int:
    import core

    cloud = core.io.read_cloud(args.input, drop_nonfinite=args.drop_nonfinite)
    normals = None if args.ignore_normals else cloud.normals
    orientation = args.viewpoint if args.viewpoint is not None else args.orientation
    bar = _Bar(not args.quiet and (sys.stderr.isatty() or args.progress))
    t0 = time.perf_counter()
    try:
        res = core.estimate(
            cloud.points, normals, k=args.k, method=args.method, passes=args.passes,
            orientation=orientation, options=dict(args.option or []), progress=bar,
        )
    finally:
        bar.close()
    elapsed = time.perf_counter() - t0
    out = core.io.write_result(args.output, res)
    if not args.quiet:
        v = res.valid
        print(f"{cloud.path}: {len(res)} points, method {res.method}, k {res.k}, passes {res.passes}, "
              f"{elapsed:.2f} s")
        print(f"invalid points: {res.n_invalid}")
        if v.any():
            for name in ("mean", "gaussian", "k1", "k2"):
                f = res.field(name)[v]
                print(f"  {name:>9}: median {np.median(f):+.4g}  [p5 {np.percentile(f, 5):+.4g}, "
                      f"p95 {np.percentile(f, 95):+.4g}]")
        print(f"wrote {out}")
    return 0


def _cmd_info(args) -> int:
    import core

    for path in args.files:
        info = core.io.describe(path)
        print(path)
        for key, val in info.items():
            print(f"  {key}: {val}")
    return 0


def _cmd_bench(args) -> int:
    import importlib

    module = importlib.import_module(f"core.bench.{args.which}")
    return module.main(args.rest)


def build_parser() -> argparse.ArgumentParser:
    from core.methods import METHODS

    p = argparse.ArgumentParser(
        prog="darboux-cli",
        description="Normals, principal curvatures and directions of point clouds (Cheng & Zhang 2009).",
    )
    sub = p.add_subparsers(dest="command", required=True)

    e = sub.add_parser("estimate", help="estimate the Darboux frame of every point and write PLY/CSV")
    e.add_argument("input", help="point cloud file (PLY, XYZ/PTS/TXT/CSV, PCD, OBJ, STL, VTK/VTP, LAS/LAZ)")
    e.add_argument("-o", "--output", required=True, help="output file (.ply or .csv)")
    e.add_argument("--k", type=_k, default="auto",
                   help="neighbours per point, itself included, or auto (default; chosen per point, NF/NR)")
    e.add_argument("--method", default="nr", choices=list(METHODS), help="estimator (default nr)")
    e.add_argument("--passes", type=int, default=None, help="normal refinement passes (default: method's)")
    e.add_argument("--orientation", default="auto", choices=["auto", "propagate", "outward", "keep"])
    e.add_argument("--viewpoint", type=_viewpoint, default=None, help="orient normals towards x,y,z")
    e.add_argument("--option", type=_parse_option, action="append", help="method option key=value")
    e.add_argument("--ignore-normals", action="store_true", help="estimate normals even if the file has some")
    e.add_argument("--drop-nonfinite", action="store_true", help="drop points with NaN/inf coordinates")
    e.add_argument("--progress", action="store_true", help="show the progress bar even when not a terminal")
    e.add_argument("-q", "--quiet", action="store_true")
    e.set_defaults(func=_cmd_estimate)

    i = sub.add_parser("info", help="describe point cloud files")
    i.add_argument("files", nargs="+")
    i.set_defaults(func=_cmd_info)

    b = sub.add_parser("bench", help="benchmarks: paper (torus experiment), perf (speed/memory), accuracy, teach")
    b.add_argument("which", choices=BENCHES)
    b.add_argument("rest", nargs=argparse.REMAINDER, help="options of the benchmark (see --help)")
    b.set_defaults(func=_cmd_bench)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (ValueError, OSError) as exc:  # bad input: one clear line, no traceback
        print(f"darboux-cli: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
