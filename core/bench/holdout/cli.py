"""``python -m core bench holdout``: the command line and the printed table."""

from __future__ import annotations

import argparse
import sys
import time

from .._args import levels as _levels
from .._args import positive as _positive
from .harness import FAR, LEVELS, LOST, QKEYS, Cache, auto_run, best, make_case, oracle_errors, score
from . import probe
from .surfaces import SETS

_SHORT = {"gaussian": "K", "mean": "H", "direction_deg": "e1"}


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m core bench holdout",
                                description="k='auto' against the best jet/APSS/NR setting (oracles) on surfaces "
                                            "the rule was not tuned on (--set holdout) or was (--set tuning).")
    p.add_argument("--set", choices=tuple(SETS), default="holdout", help="which surfaces (default holdout)")
    p.add_argument("--shapes", default=None, help="comma-separated subset of the set's surfaces")
    p.add_argument("--levels", type=_levels, default=LEVELS, help="noise as fractions of the mean spacing "
                   "(default 0,0.1,0.2,0.5)")
    p.add_argument("--points", type=_positive, default=6000, help="points per surface (default 6000)")
    p.add_argument("--evaluate", type=_positive, default=1500, help="points evaluated per cloud (default 1500)")
    p.add_argument("--seed", type=int, default=0, help="seed of the samples and the noise (default 0)")
    p.add_argument("--no-apss", action="store_true", help="leave MeshLab's APSS out of the oracles")
    p.add_argument("--cache", default=None, help="JSON file keeping the oracles' errors between runs")
    p.add_argument("--probe", action="store_true", help="instead of the race: where the default's principal "
                   "direction comes from with noise and what the alternatives give (core.bench.holdout.probe)")
    return p


def _names(args, surfaces):
    if args.shapes is None:
        return tuple(surfaces)
    names = tuple(s.strip() for s in args.shapes.split(",") if s.strip())
    bad = [s for s in names if s not in surfaces]
    if bad or not names:
        raise SystemExit(f"holdout: error: --shapes must be a subset of {','.join(surfaces)}, got {args.shapes!r}")
    return names


def _row(name, level, args, surfaces, cache):
    sample, pts, ev = make_case(surfaces[name], name, level, args.points, args.seed, args.evaluate)
    key = f"{args.set}|{name}|{level:g}|{args.points}|{args.seed}|{args.evaluate}|apss={not args.no_apss}"
    oracles = cache.get(key, lambda: oracle_errors(sample, pts, ev, not args.no_apss))
    auto = auto_run(sample, pts, ev)
    row = dict(name=name, level=level, auto=auto, best={}, ratio={})
    for q in QKEYS:
        lab, err = best(oracles, q)
        row["best"][q] = (lab, err)
        row["ratio"][q] = auto["errors"][q] / err if err > 0 else float("nan")
    return row


def _line(row) -> str:
    cells = "  ".join(f"{_SHORT[q]} {row['ratio'][q]:5.2f} ({row['best'][q][0]})" for q in QKEYS)
    a = row["auto"]
    return f"{row['name']:<11} {row['level']:4g}  k~{a['k_median']:4.0f} {a['seconds']:5.1f}s  {cells}"


def main(argv=None) -> int:
    args = parser().parse_args(argv)
    surfaces = SETS[args.set]
    names = _names(args, surfaces)
    if args.probe:
        probe.main(names, args.levels, surfaces, args)
        return 0
    cache = Cache(args.cache)
    t0 = time.perf_counter()
    print(f"set {args.set}: default / best peer per cell (best peer's setting in brackets)")
    rows = []
    for name in names:
        for level in args.levels:
            rows.append(_row(name, level, args, surfaces, cache))
            print(_line(rows[-1]), flush=True)
    s = score(rows)
    print(f"\n{args.set}: lost {s['lost']}/{s['cells']} (> {LOST:g}x), {s['far']} over {FAR:g}x, "
          f"worst {s['worst']:.2f}x, geometric mean {s['geomean']:.3f}x  ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
