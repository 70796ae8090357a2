"""``python -m core bench accuracy``: the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._args import levels as _levels
from .._args import positive as _positive
from .config import DEFAULT_LEVELS, EVALUATE, QUICK, ROBUST_LEVELS, SHAPES
from .experiment import run
from .plots import plot
from .report import markdown
from .tables import text_tables
from .verdicts import reading


def _shapes(text: str):
    vals = tuple(x.strip() for x in text.split(",") if x.strip())
    bad = [v for v in vals if v not in SHAPES]
    if not vals or bad:
        raise argparse.ArgumentTypeError(f"shapes must be a comma-separated subset of {','.join(SHAPES)}, got {text!r}")
    return vals


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m core bench accuracy",
        description="Accuracy race on analytic shapes: NR (k=15, auto, best k) vs MeshLab's APSS curvature "
                    "(pymeshlab, optional) and jet fitting at their best scales; outlier robustness; NR options.",
    )
    p.add_argument("--points", type=_positive, default=None, help="points per sample (default 5000; --quick 1000)")
    p.add_argument("--levels", type=_levels, default=None,
                   help="noise σ as fractions of the mean spacing, comma-separated (default 0,0.05,0.1,0.2,0.5,1; --quick 0.1)")
    p.add_argument("--seeds", type=_positive, default=None, help="samples averaged per entry (default 2; --quick 1)")
    p.add_argument("--shapes", type=_shapes, default=tuple(SHAPES),
                   help=f"comma-separated subset of {','.join(SHAPES)} (default all)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    p.add_argument("--evaluate", type=int, default=None,
                   help=f"points evaluated per cloud, the same for every method (default {EVALUATE}; 0: all)")
    p.add_argument("--no-apss", action="store_true", help="skip MeshLab's APSS even if pymeshlab is installed")
    p.add_argument("--out", default="docs/bench", help="directory for accuracy.md and the PNGs (default docs/bench)")
    p.add_argument("--quick", action="store_true",
                   help="1000 points, σ=0.1 only, 1 seed, small grids (seconds; for tests)")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    q = args.quick
    points = args.points or (QUICK["points"] if q else 5000)
    levels = args.levels or (QUICK["levels"] if q else DEFAULT_LEVELS)
    seeds = args.seeds or (QUICK["seeds"] if q else 2)
    evaluate = args.evaluate if args.evaluate is not None else (QUICK["evaluate"] if q else EVALUATE)
    if evaluate < 0:
        print("accuracy: error: --evaluate must be >= 0", file=sys.stderr)
        return 2
    kw = dict(k_grid=QUICK["k_grid"], apss_scales=QUICK["apss_scales"], apss_pca_k=QUICK["apss_pca_k"],
              options_levels=QUICK["options_levels"], options_passes=QUICK["options_passes"]) if q else {}
    robust_levels = tuple(lv for lv in ROBUST_LEVELS if lv in levels) or (max(levels),)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    def report(msg):
        print(msg, file=sys.stderr, flush=True)

    result = run(points=points, levels=levels, seeds=seeds, seed=args.seed, shapes_=args.shapes, evaluate=evaluate,
                 use_apss=not args.no_apss, robust_levels=robust_levels, progress=report, **kw)
    print(text_tables(result))
    print()
    for sentence in reading(result):
        print("- " + sentence)
    images = {name: plot(tab, out) for name, tab in result.tables.items()}
    cmd = "python -m core bench accuracy" + (" --quick" if q else "")
    if args.points:
        cmd += f" --points {points}"
    if args.levels:
        cmd += f" --levels {','.join(f'{x:g}' for x in levels)}"
    if args.seeds:
        cmd += f" --seeds {seeds}"
    if tuple(args.shapes) != tuple(SHAPES):
        cmd += f" --shapes {','.join(args.shapes)}"
    if args.seed:
        cmd += f" --seed {args.seed}"
    if args.evaluate is not None:
        cmd += f" --evaluate {evaluate}"
    if args.no_apss:
        cmd += " --no-apss"
    cmd += f" --out {args.out}"
    md = out / "accuracy.md"
    md.write_text(markdown(result, command=cmd, images=images) + "\n", encoding="utf-8")
    print(f"\nwrote {md} and {', '.join(str(p) for p in images.values())} ({result.seconds:.1f} s)")
    return 0


