"""The tiled half of ``darboux-cli estimate``: its options, when to use tiles, the run.

``core.cli`` asks :func:`wanted` and hands over to :func:`run`. Tiles are used when asked
(``--tile-points``, ``--workers``, ``--scheduler``), when a LAS/LAZ input's points would
need more memory than the budget (``--memory``, default half the available memory), or
when the output is LAS/LAZ (written in chunks, with extra-bytes dimensions).
"""

from __future__ import annotations

import contextlib
import pathlib
import sys
import warnings

from .._memory import available_memory
from ..io.las_stream import open_las
from ..io.atomic import refuse_input_as_output
from ..io.cloud import require_points
from .run import bytes_per_point, estimate_tiled, parse_memory
from .sizing import HaloTooWide
from .store import directory_for

_LAS = (".las", ".laz")
#: bytes per point of an in-memory k="auto" estimate (1M points measured 1.3-1.6 GB)
AUTO_BYTES_PER_POINT = 1600


def add_arguments(parser) -> None:
    """The tiled options of ``estimate``."""
    g = parser.add_argument_group("scans larger than memory (tiles on Dask)")
    g.add_argument("--tile-points", type=int, default=None, metavar="N",
                   help="estimate in tiles of about N points (default: by memory, when needed)")
    g.add_argument("--workers", type=int, default=None, metavar="N",
                   help="Dask worker processes (default: one per core; 0: in this process)")
    g.add_argument("--memory", default=None, metavar="SIZE",
                   help="memory budget per worker, e.g. 2GB (default 1.5GB for tiles; above half the "
                        "available memory for the whole cloud, tiles are used)")
    g.add_argument("--scheduler", default=None, metavar="ADDRESS", help="use an existing Dask scheduler")
    g.add_argument("--work-dir", default=None, metavar="DIR",
                   help="a folder for the tiles: they are kept in DIR/.OUTPUT.tiles, and nothing else in DIR is "
                        "touched (default: .OUTPUT.tiles next to the output)")


def wanted(args) -> bool:
    """Whether this estimate runs here (tiles, or a LAS/LAZ output) rather than in memory."""
    if args.tile_points is not None or args.workers is not None or args.scheduler is not None:
        return True
    if str(args.output).lower().endswith(_LAS):
        return True
    return _too_big(args)


def _too_big(args) -> bool:
    if not str(args.input).lower().endswith(_LAS):
        return False
    count = open_las(args.input).count
    return count * _bytes(args.k) > _in_memory_budget(args.memory)


def _bytes(k) -> int:
    return AUTO_BYTES_PER_POINT if k == "auto" else bytes_per_point(k)


def _in_memory_budget(memory) -> int:
    if memory is not None:
        return parse_memory(memory)
    return available_memory() // 2


def _work_dir(args):
    """The run's own folder inside ``--work-dir`` (None: the default, next to the output)."""
    if args.work_dir is None:
        return None
    return pathlib.Path(args.work_dir) / directory_for(args.output).name


def run(args) -> int:
    """Run the estimate of ``args`` in tiles (or, for k="auto" within memory and no tile
    option, whole, into LAS/LAZ: the same answer without the tiles' halos)."""
    refuse_input_as_output([args.input], args.output)  # before any work, on every path below
    orientation = args.viewpoint if args.viewpoint is not None else args.orientation
    asked = args.tile_points is not None or args.workers is not None or args.scheduler is not None
    if args.k == "auto" and not asked and not _too_big(args):
        return _whole_to_las(args, orientation)  # fits in memory: no tiles needed, the same answer
    bar = _Bar(not args.quiet and (sys.stderr.isatty() or args.progress))
    try:
        with _told_plainly(args.quiet):
            res = estimate_tiled(
                args.input, args.output, k=args.k, method=args.method, passes=args.passes, orientation=orientation,
                options=dict(args.option or []) or None, tile_points=args.tile_points, workers=args.workers,
                memory=args.memory or "1.5GB", scheduler=args.scheduler, workdir=_work_dir(args),
                ignore_normals=args.ignore_normals, drop_nonfinite=args.drop_nonfinite, progress=bar,
            )
    finally:
        bar.close()
    if not args.quiet:
        print(f"{_label(args)}: {res.n_points} points in {res.n_tiles} tiles ({res.tiles_skipped} finished "
              f"before), method {args.method}, k {args.k}, {res.seconds:.2f} s")
        if res.params:
            print("whole cloud: " + ", ".join(f"{name} {value:.6g}" for name, value in res.params.items()))
        print(f"orientation agreement over tile overlaps: {100 * res.agreement:.2f} %")
        print(f"wrote {res.output}")
    return 0


def _whole_to_las(args, orientation) -> int:
    """k="auto" on a cloud that fits in memory, written as LAS/LAZ."""
    import core
    from ..io import las_open
    from ..io.atomic import atomic_write
    from ..io.las_stream import LasResultWriter, quantisation, result_columns
    cloud = core.io.read_cloud(args.input, drop_nonfinite=args.drop_nonfinite)
    require_points(_label(args), len(cloud))
    normals = None if args.ignore_normals else cloud.normals
    res = core.estimate(cloud.points, normals, k=args.k, method=args.method, passes=args.passes,
                        orientation=core.interop.facing(cloud, normals, orientation), options=dict(args.option or []))
    like = records = None
    if str(args.input).lower().endswith(_LAS):  # keep the input's quantisation and fields: the same points
        info = open_las(args.input)
        scales, offsets = info.scales, info.offsets
        las = las_open.read(args.input)
        records, like = las.points, las.header
    else:
        scales, offsets = quantisation(res.points.min(axis=0), res.points.max(axis=0))
    cols = result_columns(res)
    with atomic_write(args.output) as f, LasResultWriter(f, scales=scales, offsets=offsets, like=like,
                                                         laz=str(args.output).lower().endswith(".laz")) as w:
        w.write(res.points, cols, records)
    if not args.quiet:
        print(f"{_label(args)}: {len(res)} points, method {res.method}, k {res.k}\nwrote {args.output}")
    return 0


@contextlib.contextmanager
def _told_plainly(quiet: bool):
    """The tile sizing's :class:`~core.tiled.sizing.HaloTooWide` as one line on stderr
    ("note: ..."), not a Python warning with its source line."""
    shown = warnings.showwarning

    def show(message, category, *args, **kwargs):
        if not issubclass(category, HaloTooWide):
            return shown(message, category, *args, **kwargs)
        if not quiet:
            sys.stderr.write(f"\nnote: {message}\n")

    with warnings.catch_warnings():
        warnings.simplefilter("always", HaloTooWide)
        warnings.showwarning = show
        yield


def _label(args) -> str:
    """The input as the summary names it ("stdin" for the temporary copy of standard input)."""
    return getattr(args, "label", None) or str(args.input)


class _Bar:
    """One progress line on stderr with the stage (which carries the ETA)."""

    def __init__(self, enabled: bool):
        self.enabled = enabled

    def __call__(self, fraction, stage):
        if self.enabled and stage.startswith("dask dashboard"):
            sys.stderr.write(f"\r{stage}\n")  # a link to keep: its own line
        elif self.enabled:
            pct = int(fraction * 100)
            sys.stderr.write(f"\r[{'#' * (pct // 4):<25}] {pct:3d}% {stage:<40}")
            sys.stderr.flush()

    def close(self):
        if self.enabled:
            sys.stderr.write("\n")

