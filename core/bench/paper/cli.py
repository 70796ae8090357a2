"""``python -m core bench paper``: the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .._args import levels as _levels
from .._args import positive as _positive
from .config import DEFAULT_LEVELS, QUICK
from .experiment import run
from .plots import plot
from .report import markdown
from .tables import text_tables
from .verdicts import reading


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m core bench paper",
        description="Reproduce Cheng & Zhang (2009) Figures 2–5: mean absolute error of K, H and the "
                    "principal direction vs noise on a torus and a saddle surface.",
    )
    p.add_argument("--points", type=_positive, default=None, help="points per sample (default 5000; --quick 1000)")
    p.add_argument("--k", type=_positive, default=15, help="neighbourhood size (default 15)")
    p.add_argument("--levels", type=_levels, default=None,
                   help="noise σ as fractions of the mean spacing, comma-separated "
                        "(default 0,0.05,0.1,0.15,0.2,0.3,0.4; --quick 0,0.4)")
    p.add_argument("--repeats", type=_positive, default=None, help="samples averaged per entry (default 3; --quick 1)")
    p.add_argument("--seed", type=int, default=0, help="base seed (default 0)")
    p.add_argument("--surface", choices=("torus", "saddle", "both"), default="both", help="default both")
    p.add_argument("--out", default="docs/bench", help="directory for paper.md and the PNGs (default docs/bench)")
    p.add_argument("--quick", action="store_true", help="1000 points, 2 noise levels, 1 repeat (seconds)")
    return p


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    quick = QUICK if args.quick else dict(points=5000, levels=DEFAULT_LEVELS, repeats=3)
    points = args.points or quick["points"]
    levels = args.levels or quick["levels"]
    repeats = args.repeats or quick["repeats"]
    surfaces = ("torus", "saddle") if args.surface == "both" else (args.surface,)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    def report(msg):
        print(msg, file=sys.stderr, flush=True)

    result = run(points=points, k=args.k, levels=levels, repeats=repeats, seed=args.seed,
                 surfaces=surfaces, progress=report)
    print(text_tables(result))
    print()
    for sentence in reading(result):
        print(sentence)
    images = {name: plot(tab, out) for name, tab in result.tables.items()}
    cmd = (f"python -m core bench paper --points {points} --k {args.k} "
           f"--levels {','.join(f'{x:g}' for x in levels)} --repeats {repeats} --seed {args.seed} "
           f"--surface {args.surface} --out {args.out}")
    md = out / "paper.md"
    md.write_text(markdown(result, command=cmd, images=images) + "\n", encoding="utf-8")
    print(f"\nwrote {md} and {', '.join(str(p) for ps in images.values() for p in ps)} "
          f"({result.seconds:.1f} s)")
    return 0
