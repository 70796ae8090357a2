"""Command line: ``darboux-cli`` / ``python -m core`` — estimate, info, warmup, bench.

The parser is built from one small function per group of options; the commands live in
:mod:`core._cli_commands`. Exit codes: 0 success, 1 a run failed (out of memory, a
compiled kernel failed), 2 bad input or arguments, 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import sys

from . import __version__, _cli_commands
from ._validate import word
from .io.formats import READ_FORMATS, WRITE_FORMATS
from .tiled import cli as tiled_cli

BENCHES = ("paper", "perf", "accuracy", "tiled", "stability", "teach", "holdout", "scanlines")
PROG = "darboux-cli"
_NONE = ("none", "null")
_BOOLS = {"true": True, "false": False}
#: where a MemoryError is Dask's communication failing, not the estimate out of memory
_DASK_MODULES = ("distributed", "tornado", "msgpack")


def _parse_value(text: str):
    """An option value: None/null, true/false, an int, a float, else the string."""
    low = text.strip().lower()
    if low in _NONE:
        return None
    if low in _BOOLS:
        return _BOOLS[low]
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _parse_option(text):
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"option {text!r} must look like key=value (e.g. robust=None, degree=3)")
    return key.strip(), _parse_value(value)


def _k(text):
    if word(text) == "auto":  # "AUTO", "Auto": keywords in any case, as the Python API takes them
        return "auto"
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


def _add_io_arguments(e) -> None:
    e.add_argument("inputs", nargs="+", metavar="input",
                   help=f"point cloud file(s) or glob patterns ({', '.join(READ_FORMATS)}); - reads standard "
                        "input (see --input-format)")
    e.add_argument("-o", "--output", required=True,
                   help=f"output file ({', '.join(WRITE_FORMATS)}, .las, .laz); - writes standard output (not LAS/LAZ); "
                        "with several inputs a directory or a pattern with {stem} (filled for one input too), "
                        "e.g. out/{stem}_k.laz")
    e.add_argument("--format", dest="out_format", default=None,
                   help=f"output format when it cannot come from the extension: {', '.join(f[1:] for f in WRITE_FORMATS)}, "
                        "or las/laz "
                        "in a directory (default: csv for -, ply in a directory)")
    e.add_argument("--input-format", default="xyz", help="format of standard input (default xyz)")
    e.add_argument("--drop-nonfinite", action="store_true", help="drop points with NaN/inf coordinates")
    e.add_argument("--ignore-normals", action="store_true", help="estimate normals even if the file has some")


def _add_method_arguments(e) -> None:
    from .methods import METHODS

    e.add_argument("--k", type=_k, default="auto",
                   help="neighbours per point, itself included, or auto (default; chosen per point, NF/NR)")
    e.add_argument("--method", type=word, default="nr", choices=list(METHODS), help="estimator (default nr)")
    e.add_argument("--passes", type=int, default=None, help="normal refinement passes (default: method's)")
    e.add_argument("--orientation", type=word, default="auto", choices=["auto", "propagate", "outward", "keep"],
                   help="normal signs: auto (default: keep the file's normals; orient estimated ones outward, or "
                        "toward the scanners of an E57/PTX file), propagate (each part's highest point faces +z), "
                        "outward, keep")
    e.add_argument("--viewpoint", type=_viewpoint, default=None, help="orient normals towards x,y,z")
    e.add_argument("--option", type=_parse_option, action="append",
                   help="method option key=value; values None, true/false, numbers (e.g. robust=None, degree=3)")


def add_execution_arguments(e) -> argparse._ArgumentGroup:
    """How the estimate runs: progress and output chatter. Tiled / parallel execution
    options (--tile-points, --workers, --memory, --scheduler) belong in this group."""
    g = e.add_argument_group("execution")
    g.add_argument("--progress", action="store_true", help="show the progress bar even when not a terminal")
    g.add_argument("-q", "--quiet", action="store_true", help="no summary and no progress bar")
    tiled_cli.add_arguments(e)
    return g


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog=PROG, description="Normals, principal curvatures and directions of point clouds (Cheng & Zhang 2009).",
    )
    p.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    e = sub.add_parser("estimate", help="estimate the Darboux frame of every point and write it "
                                        f"({', '.join(f[1:] for f in (*WRITE_FORMATS, '.las', '.laz'))})")
    _add_io_arguments(e)
    _add_method_arguments(e)
    add_execution_arguments(e)
    e.set_defaults(func=_cli_commands.cmd_estimate)

    i = sub.add_parser("info", help="describe point cloud files")
    i.add_argument("files", nargs="+", help="files or glob patterns")
    i.add_argument("--json", action="store_true", help="print a JSON list of objects")
    i.set_defaults(func=_cli_commands.cmd_info)

    w = sub.add_parser("warmup", help="compile (and cache) every numerical kernel once")
    w.add_argument("-q", "--quiet", action="store_true")
    w.set_defaults(func=_cli_commands.cmd_warmup)

    b = sub.add_parser("bench", help="benchmarks: paper (torus experiment), perf (speed/memory), accuracy, tiled, stability, teach, holdout (auto scale on unseen surfaces), scanlines (scanner-sampled clouds)")
    b.add_argument("which", choices=BENCHES)
    b.add_argument("rest", nargs=argparse.REMAINDER, help="options of the benchmark (see --help)")
    b.set_defaults(func=_cmd_bench)
    return p


def _cmd_bench(args) -> int:
    import importlib

    module = importlib.import_module(f"core.bench.{args.which}")
    return module.main(args.rest)


def _library_error(exc: BaseException) -> str | None:
    """A one-line description of an error from a compiled library, or None."""
    top = type(exc).__module__.split(".")[0]
    if top == "numba":
        return f"a compiled kernel failed ({type(exc).__name__}): {str(exc).strip().splitlines()[0]}"
    if top == "lazrs":
        return f"LAZ decompression failed: {exc}"
    return None


def _raised_in_dask(exc: BaseException) -> bool:
    """Whether ``exc`` was raised in Dask's communication rather than by the estimate."""
    tb = exc.__traceback__
    while tb is not None:
        if tb.tb_frame.f_globals.get("__name__", "").split(".")[0] in _DASK_MODULES:
            return True
        tb = tb.tb_next
    return False


def _error(message: str, code: int) -> int:
    print(f"{PROG}: error: {message}", file=sys.stderr)
    return code


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
        return args.func(args)
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # e.g. `darboux-cli estimate a.ply -o - | head`
        return 141
    except MemoryError as exc:
        if _raised_in_dask(exc):  # e.g. a reply that is not Dask's, read as the length of a message
            return _error(f"a message from the Dask scheduler could not be read ({type(exc).__name__}: {exc}); "
                          "is --scheduler the address of a Dask scheduler?", 1)
        return _error("out of memory; try fewer points, a smaller k or --k 15", 1)
    except (ValueError, OSError) as exc:  # bad input: one clear line, no traceback
        return _error(str(exc), 2)
    except Exception as exc:
        message = _library_error(exc)
        if message is None:
            raise
        return _error(message, 1)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
