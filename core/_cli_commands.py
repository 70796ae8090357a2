"""The commands of :mod:`core.cli`: estimate (one or many files, or stdin/stdout), info, warmup."""

from __future__ import annotations

import argparse
import contextlib
import glob
import json
import os
import pathlib
import shutil
import string
import sys
import tempfile
import time

import numpy as np

from . import io as cio
from .io.formats import READ_FORMATS, WRITE_FORMATS, resolve_format
from .tiled import cli as tiled_cli
from .io.atomic import refuse_input_as_output

STDIO = "-"
#: what -o writes: the in-memory writers' formats, and LAS/LAZ (written as a single input's
#: is, by :func:`core.tiled.cli.run`: whole, or in tiles)
OUTPUT_FORMATS = {**WRITE_FORMATS, ".las": "LAS 1.4 lidar", ".laz": "LAZ compressed lidar"}
LAS_FORMATS = ("las", "laz")
#: the options that make an estimate run in tiles (core.tiled.cli.wanted)
TILE_OPTIONS = {"tile_points": "--tile-points", "workers": "--workers", "scheduler": "--scheduler"}
#: output name in a directory, when several inputs share one -o directory
DIR_PATTERN = "{stem}_darboux.{ext}"
#: what marks -o as a pattern, filled with each input's name (one input or several)
STEM = "{stem}"
SUMMARY_FIELDS = ("mean", "gaussian", "k1", "k2")


def expand_inputs(patterns) -> list[str]:
    """Files named, plus the matches of glob patterns (for shells that do not expand them)."""
    out = []
    for pattern in patterns:
        if pattern == STDIO or os.path.exists(pattern) or not glob.has_magic(pattern):
            out.append(pattern)
            continue
        matches = sorted(glob.glob(pattern, recursive=True))
        if not matches:
            raise ValueError(f"no file matches {pattern!r}")
        out += matches
    if out.count(STDIO) > 1:
        raise ValueError("standard input (-) can be read only once")
    return out


def plan_outputs(inputs, output: str, out_format) -> list[tuple[str, str]]:
    """``[(output path or '-', format)]``, one per input, all checked before any estimate:
    the format, the folder, and that no output replaces an input."""
    if not output:  # Path("") is the current folder: ".: no file extension" named no output
        raise ValueError("-o is empty; give the output file's name (e.g. -o out.ply), a folder, or - for standard output")
    if output == STDIO:
        if len(inputs) > 1:
            raise ValueError("-o - (standard output) takes a single input")
        if str(out_format or "").lower().lstrip(".") in LAS_FORMATS:
            raise ValueError("LAS/LAZ output needs a file name ending in .las or .laz, not -o - (standard output)")
        return [(STDIO, resolve_format(pathlib.Path(STDIO), out_format or "csv", WRITE_FORMATS, "writing"))]
    paths = _output_paths(inputs, output, out_format)
    planned = []
    for dst in paths:
        refuse_input_as_output(inputs, dst)  # not an input (its name, a symlink or a hard link to it)
        fmt = resolve_format(pathlib.Path(dst), out_format, OUTPUT_FORMATS, "writing")
        if fmt in LAS_FORMATS and pathlib.Path(dst).suffix.lower() != f".{fmt}":
            raise ValueError(f"output {dst}: LAS/LAZ output needs a name ending in .{fmt}")
        folder = pathlib.Path(dst).parent
        if not folder.is_dir():
            raise ValueError(f"output {dst}: the folder {folder} does not exist")
        planned.append((dst, fmt))
    return planned


def _output_paths(inputs, output: str, out_format) -> list[str]:
    """One output path per input: a ``{stem}`` pattern filled in, ``output`` itself, or
    names in a directory."""
    if STEM in output:
        paths = [fill_pattern(output, _stem(src)) for src in inputs]
    elif len(inputs) == 1 and not os.path.isdir(output):
        return [output]
    elif os.path.isdir(output):
        ext = resolve_format(pathlib.Path("x.ply"), out_format, OUTPUT_FORMATS, "writing")
        paths = [os.path.join(output, DIR_PATTERN.format(stem=_stem(src), ext=ext)) for src in inputs]
    else:
        raise ValueError(f"with {len(inputs)} inputs, -o must be an existing directory or a pattern with {{stem}}, "
                         f"got {output!r}")
    if len(set(paths)) != len(paths):
        raise ValueError(f"the outputs {output!r} would collide (inputs with the same name); use a {{stem}} pattern")
    return paths


def fill_pattern(output: str, stem: str) -> str:
    """``output`` with ``{stem}`` replaced by ``stem``; a pattern that str.format cannot fill
    (an unclosed brace, another placeholder) is refused naming -o and the pattern."""
    try:
        fields = {name for _, name, _, _ in string.Formatter().parse(output) if name is not None}
        if fields - {"stem"}:
            raise ValueError(f"{{{sorted(fields - {'stem'})[0]}}} is not a placeholder; only {{stem}} is")
        return output.format(stem=stem)
    except (ValueError, IndexError, KeyError) as exc:  # {stem!z}, {stem:d}, {stem:{}}
        raise ValueError(f"-o {output!r} is not a valid output pattern: {exc}; write {{stem}} for the input's name "
                         "and {{ or }} for a literal brace") from None


def _stem(src: str) -> str:
    return "stdin" if src == STDIO else pathlib.Path(src).stem


def read_input(src: str, input_format: str, drop_nonfinite: bool):
    """The cloud of a file, or of standard input (stored in a temporary file to be parsed)."""
    if src != STDIO:
        return cio.read_cloud(src, drop_nonfinite=drop_nonfinite)
    with stdin_file(input_format) as path:
        return cio.read_cloud(path, drop_nonfinite=drop_nonfinite)


@contextlib.contextmanager
def stdin_file(input_format: str):
    """Standard input stored in a temporary file named for ``input_format`` (removed after);
    a refusal of that file names it "stdin", as the user knows it (not /tmp/darboux-stdin-.../stdin.xyz)."""
    fmt = resolve_format(pathlib.Path("-"), input_format, READ_FORMATS, "reading")
    with tempfile.TemporaryDirectory(prefix="darboux-stdin-") as tmp:
        path = pathlib.Path(tmp) / f"stdin.{fmt}"
        with open(path, "wb") as f:
            shutil.copyfileobj(sys.stdin.buffer, f)
        try:
            yield path
        except cio.CloudFileError as exc:
            if exc.path != str(path):
                raise
            raise cio.CloudFileError("stdin", exc.problem) from None


class ProgressBar:
    """A tqdm bar with the stage and an ETA on stderr (when it is a terminal or forced)."""

    def __init__(self, enabled: bool, label: str):
        self._bar = None
        if enabled:
            try:
                from tqdm import tqdm
            except ImportError:  # the library works without it: no bar
                return
            self._bar = tqdm(total=1000, desc=label, leave=False, file=sys.stderr, dynamic_ncols=True,
                             bar_format="{desc} {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]")

    def __call__(self, fraction, stage):
        if self._bar is not None:
            self._bar.set_postfix_str(stage, refresh=False)
            self._bar.update(int(fraction * 1000) - self._bar.n)

    def close(self):
        if self._bar is not None:
            self._bar.close()


def cmd_estimate(args) -> int:
    """Each input as it would be alone: in memory, or (LAS/LAZ output, a tile option, a
    LAS/LAZ input larger than the memory) by :func:`core.tiled.cli.run`."""
    check_execution_options(args)
    inputs = expand_inputs(args.inputs)
    plan = plan_outputs(inputs, args.output, args.out_format)  # refuse bad outputs before any work
    options = dict(args.option or [])
    failed = 0
    for src, (dst, fmt) in zip(inputs, plan):
        try:
            _estimate_one(args, src, dst, fmt, options)
        except ValueError as exc:  # this file is bad: say so and go on with the others
            if len(inputs) == 1:
                raise
            print(f"darboux-cli: error: {exc}", file=sys.stderr)
            failed += 1
    return 2 if failed else 0


def check_execution_options(args) -> None:
    """Options checked whichever path an input takes (--memory also decides whether a
    LAS/LAZ input fits in memory); tiles cannot write to standard output."""
    if args.memory is not None:
        with contextlib.suppress(ImportError):  # without Dask (the [big] extra) there are no tiles to size
            tiled_cli.parse_memory(args.memory)
    asked = [flag for name, flag in TILE_OPTIONS.items() if getattr(args, name) is not None]
    if asked and args.output == STDIO:
        raise ValueError(f"tiles ({', '.join(asked)}) write a file, not -o - (standard output); without them "
                         "the estimate runs in memory")


def _tiled(args, src, dst, fmt) -> bool:
    """Whether ``src`` is estimated by :func:`core.tiled.cli.run` (as a single input is)."""
    if dst == STDIO:
        return False
    if fmt in LAS_FORMATS or src == STDIO and any(getattr(args, name) is not None for name in TILE_OPTIONS):
        return True
    return src != STDIO and tiled_cli.wanted(_one(args, src, dst))


def _one(args, src, dst, **extra) -> argparse.Namespace:
    return argparse.Namespace(**{**vars(args), "input": src, "output": dst, **extra})


def _estimate_one(args, src, dst, fmt, options) -> None:
    import core

    if _tiled(args, src, dst, fmt):
        if src != STDIO:
            tiled_cli.run(_one(args, src, dst))
            return
        with stdin_file(args.input_format) as path:  # read from a temporary copy, named "stdin" in the summary
            tiled_cli.run(_one(args, str(path), dst, label="stdin"))
        return
    cloud = read_input(src, args.input_format, args.drop_nonfinite)
    cio.cloud.require_points("stdin" if src == STDIO else src, len(cloud))
    normals = None if args.ignore_normals else cloud.normals
    orientation = args.viewpoint if args.viewpoint is not None else args.orientation
    bar = ProgressBar(not args.quiet and (sys.stderr.isatty() or args.progress), _stem(src))
    t0 = time.perf_counter()
    try:
        res = core.estimate(cloud.points, normals, k=args.k, method=args.method, passes=args.passes,
                            orientation=core.interop.facing(cloud, normals, orientation), options=options, progress=bar)
    finally:
        bar.close()
    elapsed = time.perf_counter() - t0
    if dst == STDIO:
        cio.write_result(sys.stdout.buffer, res, format=fmt)
        sys.stdout.flush()
    else:
        cio.write_result(dst, res, format=fmt)
    if not args.quiet:
        _summary(res, "stdin" if src == STDIO else cloud.path, elapsed, dst,
                 sys.stderr if dst == STDIO else sys.stdout)


def _summary(res, name, elapsed, dst, out) -> None:
    print(f"{name}: {len(res)} points, method {res.method}, k {res.k}, passes {res.passes}, {elapsed:.2f} s",
          file=out)
    print(f"invalid points: {res.n_invalid}", file=out)
    if res.params.get("duplicates"):
        print(f"duplicate points: {res.params['duplicates']} (each estimated at its place, once)", file=out)
    if "degenerate" in res.params:
        print(f"  no estimate: {res.params['degenerate']}", file=out)
    repaired = res.params.get("normals_repaired") or {}
    if repaired.get("unusable"):
        oriented = repaired.get("oriented", 0)
        print(f"file normals: {repaired['unusable']} unusable (zero, NaN or inf), {repaired['estimated']} estimated"
              + (f"; {oriented} of them oriented as estimated normals are (no neighbour has a file normal)"
                 if oriented else ""),
              file=out)
    if repaired.get("use") == "signs":
        print(f"file normals: rougher than the estimator's own (roughness {repaired['roughness']}), "
              "used for their signs only", file=out)
    v = res.valid
    if v.any():
        for name in SUMMARY_FIELDS:
            f = res.field(name)[v]
            print(f"  {name:>9}: median {np.median(f):+.4g}  [p5 {np.percentile(f, 5):+.4g}, "
                  f"p95 {np.percentile(f, 95):+.4g}]", file=out)
    print(f"wrote {'standard output' if dst == STDIO else dst}", file=out)


def cmd_info(args) -> int:
    records, failed = [], 0
    for path in expand_inputs(args.files):
        try:
            records.append(cio.describe(path))
        except ValueError as exc:
            print(f"darboux-cli: error: {exc}", file=sys.stderr)
            failed += 1
    if args.json:
        json.dump(records, sys.stdout, indent=2)
        print()
    else:
        for info in records:
            print(info["path"])
            for key, val in info.items():
                if key != "path":
                    print(f"  {key}: {val}")
    return 2 if failed else 0


def cmd_warmup(args) -> int:
    """Run tiny estimates of every method, so numba compiles and caches each kernel."""
    from .warmup import warm_up

    t0 = time.perf_counter()
    runs = warm_up()
    if not args.quiet:
        print(f"compiled {runs} configurations in {time.perf_counter() - t0:.1f} s")
    return 0
