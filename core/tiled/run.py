"""``estimate_tiled``: the whole-cloud estimate, computed tile by tile in bounded memory."""

from __future__ import annotations

import contextlib
import os
import pathlib
import time
import dataclasses
import functools
from dataclasses import dataclass, field

import numba
import numpy as np

from .._progress import Progress
from .._validate import check_int, word
from ..methods import check_options, get_method
from ..planning import PER_POINT, orientation_mode
from ..io.atomic import refuse_input_as_output
from ..tuning import DRIFT_POOL, DRIFT_SHARE, MAX_PASSES
from . import assemble, binning, creases, engine, signs
from .sizing import choose_tile_points
from .source import open_source
from .store import TileStore, directory_for
from . import wholecloud, wholechecks
from .auto import PassView, pass_choice, run_auto_tile
from .task import TileSpec, auto_plan

#: memory of an in-memory estimate per point at integer k: ~250 bytes of arrays per point
#: plus the cached neighbours (int32 index + float64 distance = 12 bytes per neighbour,
#: twice while they are sorted); 3M points at k = 15 measured 1.75 GB (580 B/point)
BASE_BYTES, BYTES_PER_NEIGHBOUR = 250, 24
#: what a halo adds to a tile of ~1M points at k = 15 (measured 5-15 %), with room to spare: the
#: size :func:`default_tile_points` gives without seeing the cloud (a run measures its halos on
#: the cloud's sample, :mod:`core.tiled.sizing`)
HALO_ALLOWANCE = 1.5
#: what a worker process holds before any tile: Python, numpy, scipy, numba's compiled
#: kernels, Dask (measured 210 MB after a first estimate), with room to spare
RUNTIME_BYTES = 300_000_000
#: share of the budget a tile is sized to fill: Dask's nanny pauses a worker at 80 % of its
#: memory limit and kills it at 95 %; a 1.31M-point tile sized to fill all of 1.5GB peaked
#: at 1.40 GB (k = 15, 2026-11-30), so tiles aim at 75 %
FILL = 0.75
DEFAULT_MEMORY = "1.5GB"
#: k="auto" holds more than NR at its largest candidate (the jets, the scale choice, every
#: pass's result of its own points until the whole cloud chooses one): counted as this many
#: more neighbours (24 bytes each) per pass. Measured: one tile of 300k points with the
#: candidates (20,) of a large cloud peaked at 0.52 GB over the runtime, 1730 bytes a
#: point = 250 + 24 x (20 + 4 x 11) with the 4 default passes. 15 since the tiles also keep
#: pass 1 stepped back where pass 2 drifts (core.drift: 144 bytes of rows a point) and three
#: passes' fits (~310 bytes): ~4 neighbours a pass more, estimated, not measured
AUTO_PASS_NEIGHBOURS = 15
_VERSION = 6  # bumped when the work directory's layout changes: old ones are cleared


@dataclass(frozen=True)
class TiledRun:
    """What a tiled run did: the output, its size, and how the tiles went."""

    output: pathlib.Path
    n_points: int
    n_tiles: int
    tiles_skipped: int
    agreement: float  # share of halo points whose orientations agree across tiles
    seconds: float
    #: the whole cloud's crease_typical; with k="auto" also its noise, fold_typical, passes_run
    params: dict = field(default_factory=dict)
    #: CPU seconds of this process per stage (plan, bin, tiles: the scheduler and the
    #: waiting, signs, assemble) and "tile tasks": of the tasks, summed over the workers
    cpu: dict = field(default_factory=dict)


def bytes_per_point(k: int) -> int:
    """Estimated peak memory of an in-memory estimate per point at integer ``k``."""
    return BASE_BYTES + BYTES_PER_NEIGHBOUR * int(k)


#: the largest memory budget taken: a byte count that fits an int64, as Dask and numpy hold
#: it (about 9200 PB; a larger value is a typo such as 1e300 or a unit given twice)
MAX_MEMORY = 2**63 - 1


def parse_memory(memory) -> int:
    """Bytes from 2_000_000_000, "2GB", "1.5 GiB", "500MB" (at most :data:`MAX_MEMORY`)."""
    from dask.utils import parse_bytes

    try:
        value = int(memory) if isinstance(memory, (int, np.integer)) else parse_bytes(str(memory))
    except (ValueError, TypeError, OverflowError):  # OverflowError: "1e400GB" is int(inf) in Dask
        value = None
    if value is None or value > MAX_MEMORY:
        raise ValueError(f"memory {memory!r} is invalid; give bytes or a size such as '2GB' or '1.5GiB', "
                         "at most 2**63 - 1 bytes (about 9200PB)")
    if value <= 0:
        raise ValueError(f"memory {memory!r} is invalid; it must be positive")
    return value


def default_tile_points(k: int, memory) -> int:
    """Points per tile so that a worker, a tile, its halo and the estimate fit in ``memory``."""
    return max(10_000, int(_room(memory) / (bytes_per_point(k) * HALO_ALLOWANCE)))


def _room(memory) -> float:
    """Bytes a worker with ``memory`` has for a tile and its halo (refused below twice the runtime)."""
    budget = parse_memory(memory)
    if budget < 2 * RUNTIME_BYTES:
        raise ValueError(f"memory {memory!r} is too small for a tile worker; give at least "
                         f"{2 * RUNTIME_BYTES // 1_000_000}MB (a worker alone holds about {RUNTIME_BYTES // 1_000_000}MB)")
    return FILL * budget - RUNTIME_BYTES


def _prepare(source, normals, k, *, method, passes, orientation, options, tile_points, workers, memory,
             ignore_normals, drop_nonfinite=False):
    """Validate the arguments (cheap checks before the file is opened) and resolve defaults."""
    budget = parse_memory(memory)
    if tile_points is not None:
        tile_points = check_int(tile_points, name="tile_points", low=100, high=10**10)
    if workers is not None:
        check_int(workers, name="workers", low=0, high=4096)
    src = open_source(source, normals, use_normals=not ignore_normals, drop_nonfinite=drop_nonfinite)
    spec, rule = _spec(k, method, passes, orientation, options, src.has_normals, in_process=workers == 0,
                       views=src.has_views)
    if spec.k == "auto":
        spec = dataclasses.replace(spec, n_points=max(src.count, 3))
        spec = dataclasses.replace(spec, passes=auto_plan(spec).passes)  # checks method and options first
    return src, spec, rule, budget, tile_points or _sizer(spec, memory, src.count, workers)


def _auto_rules(spec):
    """What else k="auto"'s tiles depend on (the candidates, the options it resolved): a
    work directory left by other rules (another version of the library) is not resumed."""
    if spec.k != "auto":
        return None
    plan = auto_plan(spec)
    return repr((plan.candidates, plan.k_initial, sorted(plan.options.items()), plan.passes, plan.initial,
                 DRIFT_SHARE, DRIFT_POOL))


def _memory_k(spec) -> int:
    """The k whose neighbours a tile caches: k, or k="auto"'s largest candidate (plus the
    passes' results it keeps: AUTO_PASS_NEIGHBOURS neighbours' worth of bytes per pass)."""
    if spec.k != "auto":
        return spec.k
    plan = auto_plan(spec)
    return plan.k_search + AUTO_PASS_NEIGHBOURS * plan.passes


def _sizer(spec, memory, count, workers):
    """The tile size as the sample will tell it (:func:`core.tiled.sizing.choose_tile_points`):
    tiles whose halos fit the budget, for the fewest work on the workers."""
    bpp = bytes_per_point(_memory_k(spec))
    room = int(_room(memory))
    return functools.partial(choose_tile_points, spec=spec, workers=workers or os.cpu_count() or 1, room=room,
                             bytes_per_point=bpp, least_tiles=max(1, -(-count * bpp // room)))


def estimate_tiled(source, output, *, normals=None, k="auto", method="nr", passes=None, orientation="auto",
                   options=None, tile_points=None, workers=None, memory=DEFAULT_MEMORY, client=None,
                   scheduler=None, workdir=None, keep_workdir=False, ignore_normals=False,
                   drop_nonfinite=False, progress=None) -> TiledRun:
    """Estimate a cloud of any size in spatial tiles with halos, on Dask, into a file.

    Every point gets the answer of :func:`core.estimate` on the whole cloud (the same
    neighbours and fits; the halo holds the whole dependency chain, see
    :mod:`core.tiled.halo`); normal signs agree across tiles by their overlaps
    (:mod:`core.tiled.signs`). A cloud :func:`core.estimate` makes no fit on (too few points,
    one place, a line, ...: :mod:`core.tiled.wholechecks`) is refused with the reason.
    Resumable: finished tiles are kept in ``workdir`` (by default ``.<output name>.tiles``
    next to the output) until the output is written.

    Parameters
    ----------
    source : path of a point-cloud file (LAS/LAZ read in chunks; E57 scan by scan, the
        scanner poses orienting the normals; other formats are read whole) or an (N, 3) array.
    output : path of the result: .laz/.las (any size, written in chunks, extra-bytes
        dimensions nx ny nz k1 k2 e1_* e2_* gaussian mean valid k) or .ply/.csv (in memory).
    normals : (N, 3) array, optional, with an array ``source``.
    k, method, passes, options : as for :func:`core.estimate`. k="auto" (the default)
        gives every point the in-memory choice of k, model and fit: a pre-pass fixes the
        whole cloud's medians (:mod:`.wholecloud`), each tile runs every refinement pass
        and the pass kept is chosen for the whole cloud (:mod:`.auto`); ``params`` of the
        result reports the noise, crease_typical and passes_run used. With an integer k the
        creases are judged against the whole cloud's median residual once every tile has
        fitted (:mod:`.creases`; ``params["crease_typical"]``).
    orientation : as for :func:`core.estimate`: "auto", "outward", "propagate", "keep" or a
        (3,) viewpoint (scanner position).
    tile_points : points per tile; default from ``memory`` and k.
    workers : Dask worker processes of the local cluster (default: one per core); 0 runs
        the tiles in this process.
    memory : budget per worker, e.g. "1.5GB" (Dask's limit for the local cluster).
    client, scheduler : an existing ``distributed.Client``, or a scheduler address.
    workdir, keep_workdir : the directory the tiles are kept in (new, empty, or an earlier run's:
        one holding other files is refused; only what a run writes is ever deleted), and
        whether to keep them afterwards.
    ignore_normals : estimate normals even where the file has some.
    drop_nonfinite : drop points with NaN/inf coordinates (a file read whole, or an array), as
        :func:`core.estimate` does; the output then holds the others.
    progress : callable(fraction, stage), optional.

    Returns
    -------
    TiledRun
    """
    t0 = time.perf_counter()
    refuse_input_as_output([source], output)  # before the input is opened: never overwritten
    report = Progress(progress)
    src, spec, rule, budget, tile_points = _prepare(
        source, normals, k, method=method, passes=passes, orientation=orientation, options=options,
        tile_points=tile_points, workers=workers, memory=memory, ignore_normals=ignore_normals,
        drop_nonfinite=drop_nonfinite)
    output = _output(output)
    own_client = engine.connect(scheduler) if client is None and scheduler is not None else None
    try:  # a scheduler that cannot be reached is told before the input is binned
        store = TileStore(workdir or directory_for(output))
        same_run = {**spec.__dict__, "threads": None}  # any number of workers may resume a run
        resumed = store.open({"input": list(map(str, src.identity)), "spec": repr(same_run), "rule": rule,
                              "tile_points": tile_points if isinstance(tile_points, int) else ("sized", budget), "version": _VERSION, "auto": _auto_rules(spec)})
        cpu = _StageCPU()
        with _kept_only_to_resume(store):
            plan, sizes = _binned(src, store, tile_points, report, cpu, _min_k(spec))
            tasks = dict(client=own_client or client, scheduler=None if own_client else scheduler, workers=workers,
                         memory=budget, label=src.name)
            spec, results, params = _estimate(store, plan, sizes, spec, tasks, report.sub(0.15, 0.9))
    finally:
        if own_client is not None:
            own_client.close()
    cpu.mark("tiles")
    report(0.9, "orientation across tiles")
    tile_signs, agreement = signs.tile_signs(results, plan.n_tiles, rule)
    cpu.mark("signs")
    report(0.93, "writing")
    out = assemble.assemble(results, plan.n_tiles, plan.n_points, tile_signs, output, src)
    cpu.mark("assemble")
    if not keep_workdir:
        store.remove()
    report(1.0, "done")
    todo = params.pop("todo")
    cpu.seconds["tile tasks"] = params.pop("tile cpu")
    skipped = plan.n_tiles - todo if resumed else 0
    return TiledRun(out, plan.n_points, plan.n_tiles, skipped, agreement, time.perf_counter() - t0, params,
                    cpu.seconds)


class _StageCPU:
    """CPU seconds of this process (all its threads: Dask's scheduler too) per stage."""

    def __init__(self):
        self.seconds, self.t = {}, time.process_time()

    def mark(self, stage: str) -> None:
        now = time.process_time()
        self.seconds[stage] = self.seconds.get(stage, 0.0) + now - self.t
        self.t = now


def _estimate(store, plan, sizes, spec, tasks, report):
    """The tile tasks: with k="auto" a pre-pass fixes the whole-cloud quantities, and the
    pass every tile reports is chosen for the whole cloud (:mod:`.auto`). Returns the spec
    run, the store to read the results from, and the whole-cloud params."""
    auto = spec.k == "auto"
    n_points = wholechecks.planned_count(spec.k, plan.n_points, plan.distinct,
                                         lambda n: auto_plan(dataclasses.replace(spec, n_points=n)).k_search)
    if auto:
        spec = dataclasses.replace(spec, n_points=n_points)
        before = []
        for when, fn, span in (("before", wholecloud.run_before, (0.0, 0.05)),
                               ("initial", wholecloud.run_initial, (0.05, 0.1))):
            if spec.normals_given and when == "initial" or not wholecloud.wanted(auto_plan(spec), when):
                continue  # given normals are not estimated: no folds to test
            todo = [t for t in range(plan.n_tiles) if not wholecloud.sampled(store, t, when)]
            before += engine.run_tasks(store.root, todo, sizes, spec, fn=fn, stage="whole-cloud medians",
                                       progress=report.sub(*span), **tasks)
            fixed = wholecloud.reduce(store, plan.n_tiles, auto_plan(spec), when)
            spec = dataclasses.replace(spec, fixed=tuple(sorted({**dict(spec.fixed), **fixed}.items())))
    todo = [t for t in range(plan.n_tiles) if not store.finished(t)]
    done = engine.run_tasks(store.root, todo, sizes, spec, fn=run_auto_tile if auto else None,
                            progress=report.sub(0.1 if auto else 0.0, 1.0), **tasks)
    params = {"todo": len(todo), "tile cpu": sum(s.get("cpu", 0.0) for s in done + (before if auto else []))}
    if not auto:  # the crease threshold is the whole cloud's median residual, as in memory
        params["crease_typical"] = wholecloud.median_of(creases.samples(store, plan.n_tiles))
        creases.rejudge(store, plan.n_tiles, params["crease_typical"])
        return spec, store, params
    whole = auto_plan(spec)
    kept, back = pass_choice(store, plan.n_tiles, whole)
    params.update(dict(spec.fixed), passes_run=kept, **wholecloud.reduce(store, plan.n_tiles, whole, "after"))
    return spec, PassView(store.root, kept, back), params


def _output(output) -> pathlib.Path:
    """The output path, checked before any work: in an existing folder (and not the input:
    :func:`core.io.atomic.refuse_input_as_output`)."""
    output = pathlib.Path(os.fspath(output))
    if not output.parent.is_dir():
        raise ValueError(f"output {output}: the folder {output.parent} does not exist")
    return output


def _min_k(spec) -> int:
    """The fewest points the run's method fits (its options as the whole cloud's plan resolves them)."""
    m = get_method(spec.method)
    options = dict(auto_plan(spec).options) if spec.k == "auto" else check_options(m, spec.options)
    return m.min_k_for(options)


def _binned(src, store, tile_points, report, cpu, min_k):
    """Plan the tiles and bin the points (a cloud with fewer than ``min_k`` points, or
    none can be estimated on, is refused before)."""
    plan = binning.plan_tiles(src, store, tile_points, report.sub(0.0, 0.05), min_k)
    cpu.mark("plan")
    sizes = binning.bin_points(src, store, plan, report.sub(0.05, 0.15))
    cpu.mark("bin")
    return plan, sizes


@contextlib.contextmanager
def _kept_only_to_resume(store):
    """A failure inside (an unreadable or truncated input, a local cluster that does not
    start, a failing tile, Ctrl-C) leaves no work directory behind (the binned copy of the
    input), unless it holds finished tiles to resume."""
    try:
        yield
    except BaseException:
        if not any(store.root.glob("results/*.done")):
            store.remove()
        raise


def _spec(k, method, passes, orientation, options, normals_given, in_process, views=False):
    """The tile parameters (validated as :func:`core.estimate` does) and the sign rule."""
    m = get_method(method)
    opts = check_options(m, options)
    k, passes = _k_passes(word(k), passes, m, opts)
    tile_orient, rule = _orientation(orientation, normals_given, views)
    spec = TileSpec(k=k, method=m.name, passes=passes, orientation=tile_orient, options=options or {},
                    normals_given=normals_given,
                    threads=numba.config.NUMBA_NUM_THREADS if in_process else 1)
    return spec, rule


def _k_passes(k, passes, m, opts):
    """k ("auto", checked further by :func:`auto_plan` once the cloud's size is known, or
    an integer) and the passes (None: the default of k="auto" or of the method)."""
    if isinstance(k, str) and k == "auto":
        return k, None if passes is None else check_int(passes, name="passes", low=0, high=MAX_PASSES)
    if isinstance(k, str):
        raise ValueError(f'k must be an integer or "auto", got {k!r}')
    k = check_int(k, name="k", low=m.min_k_for(opts), high=10**6)
    return k, m.default_passes if passes is None else check_int(passes, name="passes", low=0, high=MAX_PASSES)


def _orientation(orientation, normals_given, views):
    """(how each tile orients, how the tiles' signs are then fixed: none/outward/propagate),
    from the orientation as :func:`core.planning.orientation_mode` checks and reads it."""
    mode, label = orientation_mode(orientation, normals_given)
    if mode == PER_POINT:
        raise ValueError("orientation as one viewpoint per point is not taken by tiles; an E57 source's points face "
                         "their scanners with orientation='auto'")
    if mode == "keep" or label == "viewpoint":
        return mode, "none"
    if label == "auto" and views:  # each normal faces the scanner that saw its point
        return "scanner", "none"
    return "propagate", "outward" if label in ("auto", "outward") else "propagate"
