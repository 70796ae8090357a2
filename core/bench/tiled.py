"""``python -m core bench tiled``: tiled estimation on synthetic aerial scans of growing size.

For each size a LAZ scan of a rolling terrain (uniform density, noise 0.2 spacing) is
generated in chunks, then estimated (a) in tiles on a local Dask cluster into LAZ and,
up to ``--memory-max`` points, (b) in memory in a separate process (read, estimate, write
the same LAZ). Printed per size: tiles, wall time and CPU time per point of each (the CPU
time of every process involved, Dask workers included: on a shared machine the wall time
measures the neighbours' load, the CPU time much less so), their ratios (target: tiled
<= 1.3x the in-memory time per point, and a time per point that does not grow with the
size), the peak memory of each tile worker (target <= 1.5 GB) and of the in-memory run,
and the largest difference between the two answers (target <= 1e-9) with the share of
points whose normal signs agree (target >= 99.9 %). ``--log`` prints each stage of the
tiled runs with its time (for long runs).
"""

from __future__ import annotations

import argparse
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

from ._args import positive
from ._common import Sampler
from ._table import fmt, text_table

_CHUNK = 1_000_000
_SPACING = 0.1


def write_scan(path, n: int, seed: int = 0) -> None:
    """A LAZ aerial scan of ``n`` points on a rolling terrain, written chunk by chunk."""
    import laspy

    side = np.sqrt(n) * _SPACING
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-4), np.zeros(3)
    rng = np.random.default_rng(seed)
    with laspy.open(path, mode="w", header=header) as w:
        for start in range(0, n, _CHUNK):
            m = min(_CHUNK, n - start)
            x, y = rng.uniform(0, side, m), rng.uniform(0, side, m)
            z = 2.0 * np.sin(x / 7.0) * np.cos(y / 11.0) + 0.5 * np.sin(x / 2.3 + y / 3.1)
            rec = laspy.ScaleAwarePointRecord.zeros(m, header=header)
            rec.x, rec.y, rec.z = x, y, z + rng.normal(0, 0.2 * _SPACING, m)
            w.write_points(rec)


class _WorkerPeaks(Sampler):
    """Peak RSS of every child process (the Dask workers), sampled in a thread."""

    def __init__(self):
        import psutil

        self.me = psutil.Process()
        self.peaks = {}
        self.cpu = {}  # pid -> CPU seconds last seen (a cross-check of RUSAGE_CHILDREN)
        self.own = 0

    def sample(self) -> None:
        self.own = max(self.own, self.me.memory_info().rss)
        for child in self.me.children(recursive=True):
            try:
                self.peaks[child.pid] = max(self.peaks.get(child.pid, 0), child.memory_info().rss)
                t = child.cpu_times()
                self.cpu[child.pid] = t.user + t.system
            except Exception:  # the process ended between listing and reading  # noqa: BLE001
                pass


_IN_MEMORY = """
import resource, sys, time, numpy as np, core
from core.io.atomic import atomic_write
from core.io.las_stream import LasResultWriter, open_las, result_columns
t0 = time.perf_counter()
cloud = core.io.read_cloud(sys.argv[1])
t1 = time.perf_counter()
res = core.estimate(cloud.points, k=int(sys.argv[2]))
t2 = time.perf_counter()
info = open_las(sys.argv[1])
with atomic_write(sys.argv[3] + ".laz") as f, LasResultWriter(f, scales=info.scales, offsets=info.offsets,
                                                             laz=True) as w:
    w.write(res.points, result_columns(res))  # every column, the lazy flags included: the CLI's in-memory path
t3 = time.perf_counter()
np.savez(sys.argv[3], n=res.normals, k1=res.k1, k2=res.k2, e1=res.e1, valid=res.valid)
print(t2 - t1, t3 - t0, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024)
"""


def _in_memory(scan, k, out):
    """(estimate seconds, read + estimate + LAZ write seconds, peak RSS bytes) in a fresh process."""
    proc = subprocess.run([sys.executable, "-c", _IN_MEMORY, str(scan), str(k), str(out)], check=True,
                          capture_output=True, text=True, cwd=os.getcwd())
    est, total, rss = proc.stdout.split()[-3:]
    return float(est), float(total), int(rss)


def _agreement(tiled_path, ref_path):
    import laspy

    las = laspy.read(tiled_path)
    ref = np.load(ref_path)
    n = np.column_stack([las.nx, las.ny, las.nz])
    same = np.einsum("ij,ij->i", n, ref["n"]) > 0
    k1 = np.where(same, las.k1, -np.asarray(las.k2))
    v = ref["valid"]
    diff = max(np.abs(n * np.where(same, 1, -1)[:, None] - ref["n"])[v].max(), np.abs(k1 - ref["k1"])[v].max())
    return float(diff), float(same[v].mean())


def _warm_up(tmp, args):
    """Compile (or load) numba's kernels once, so that no timed run pays for it."""
    from core.tiled import estimate_tiled

    write_scan(tmp / "warm.laz", 20_000)
    estimate_tiled(tmp / "warm.laz", tmp / "warm_out.laz", k=args.k, tile_points=10_000, workers=0)
    _in_memory(tmp / "warm.laz", args.k, tmp / "warm_ref.npz")


def _cpu() -> float:
    """CPU seconds of this process and of its finished children (Dask workers, subprocesses)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


class _StageLog:
    """Progress callback printing each new stage of a run with the seconds since its start."""

    def __init__(self, n):
        self.n, self.t0, self.last = n, time.perf_counter(), None

    def __call__(self, fraction, stage):
        name = stage.split(",")[0]
        if name != self.last:
            self.last = name
            print(f"  {self.n:,} points: {time.perf_counter() - self.t0:8.1f} s  {100 * fraction:5.1f} %  {stage}",
                  file=sys.stderr, flush=True)


def run_size(n, args, tmp):
    from core.tiled import estimate_tiled

    scan = tmp / f"scan_{n}.laz"
    write_scan(scan, n)
    cpu = _cpu()
    with _WorkerPeaks() as peaks:
        run = estimate_tiled(scan, tmp / f"out_{n}.laz", k=args.k, tile_points=args.tile_points,
                             workers=args.workers, memory=args.memory, progress=_StageLog(n) if args.log else None)
    row = dict(n=n, tiles=run.n_tiles, t_tiled=run.seconds, cpu_tiled=_cpu() - cpu, cpu_seen=sum(peaks.cpu.values()),
               worker_gb=max(peaks.peaks.values(), default=0) / 1e9, main_gb=peaks.own / 1e9,
               **{f"cpu {stage}": round(sec, 2) for stage, sec in run.cpu.items()})
    if n <= args.memory_max:
        cpu = _cpu()
        row["t_est"], row["t_mem"], rss = _in_memory(scan, args.k, tmp / f"ref_{n}.npz")
        row["cpu_mem"], row["mem_gb"] = _cpu() - cpu, rss / 1e9
        row["diff"], row["agree"] = _agreement(tmp / f"out_{n}.laz", tmp / f"ref_{n}.npz")
    for f in tmp.glob(f"*_{n}.*"):
        f.unlink()
    row["load"] = round(os.getloadavg()[0], 1)  # the machine's load: the wall times' context
    return row


def _table(rows, k) -> str:
    def per_point(r, key):
        return fmt(1e6 * r[key] / r["n"]) if key in r else "-"

    def ratio(r, a, b):
        return fmt(r[a] / r[b]) if b in r else "-"

    table = [[f"{r['n']:,}", str(r["tiles"]), fmt(r["t_tiled"]), per_point(r, "t_tiled"), per_point(r, "cpu_tiled"),
              fmt(r.get("t_mem")), per_point(r, "t_mem"), per_point(r, "cpu_mem"), ratio(r, "t_tiled", "t_mem"),
              ratio(r, "cpu_tiled", "cpu_mem"), fmt(r["worker_gb"]), fmt(r["main_gb"]), fmt(r.get("mem_gb")),
              fmt(r.get("diff")), fmt(100 * r["agree"]) if "agree" in r else "-"] for r in rows]
    return text_table(["points", "tiles", "tiled s", "us/pt", "cpu us/pt", "mem s", "us/pt", "cpu us/pt",
                       "wall ratio", "cpu ratio", "worker GB", "main GB", "in-mem GB", "max diff", "signs %"], table,
                      title=f"tiled vs in-memory, NR k = {k}; both read the LAZ and write a LAZ result; cpu: "
                            "all processes (Dask workers included)")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m core bench tiled", description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="250000,1000000,2000000", help="points per scan, comma-separated")
    p.add_argument("--k", type=positive, default=15)
    p.add_argument("--tile-points", type=positive, default=None, help="default: from --memory")
    p.add_argument("--workers", type=int, default=None, help="default: one per core")
    p.add_argument("--memory", default="1.5GB", help="budget per worker")
    p.add_argument("--memory-max", type=int, default=2_000_000, help="largest size also run in memory (0: none)")
    p.add_argument("--dir", default=None, help="where scans and results are written (default: a temporary "
                   "directory; 50M points need ~15 GB)")
    p.add_argument("--log", action="store_true", help="print every stage of the tiled runs with its time")
    args = p.parse_args(argv)
    sizes = [int(float(s)) for s in args.sizes.split(",") if s.strip()]
    rows = []
    with tempfile.TemporaryDirectory(prefix="darboux-bench-", dir=args.dir) as tmp:
        _warm_up(pathlib.Path(tmp), args)
        for n in sizes:
            r = run_size(n, args, pathlib.Path(tmp))
            print(r, flush=True)
            rows.append(r)
    print(_table(rows, args.k))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
