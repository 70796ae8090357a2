"""``python -m core bench perf``: wall time and peak memory of each stage of an NR estimate.

The reference is the neighbour search alone (``cKDTree(points)`` + ``query(k + 1)`` on all
cores: the k neighbours and the next one, which the search needs to see ties at the cut)
measured in the same run, so the printed ratio does not depend on the machine; the
reference, the end-to-end estimate and the re-estimates are each timed twice and the
faster run is kept (the machine may be shared: one re-estimate after the k="auto" runs
read 0.44-0.67 s where it takes 0.29 s). Targets: whole NR estimate (k = 15, 1 refinement pass)
<= 1.5x that search; peak memory <= 2 GB at 1M points; re-estimate with cached neighbours
on 100k points < 0.5 s; k="auto" <= 3x NR at k = 15; the ratio to the same fit (cubic,
robust, the passes auto kept) at the largest candidate k is printed too, the cost of
*choosing* k and passes (where every point may hold that k: :func:`core.neighbour_budget.whole_cap`).
Each run's peak is above the memory the process holds when it starts (freed heap returned
first). ``--noise`` adds isotropic Gaussian noise of that fraction of the mean spacing
(:func:`core.noise.add_noise`) to the torus: with noise k="auto" fits far wider.
"""

from __future__ import annotations

import argparse
import ctypes
import gc
import os
import time

import numpy as np
from scipy.spatial import cKDTree

from .. import build_neighbours, estimate, plan, shapes
from ..neighbour_budget import whole_cap
from ..noise import add_noise
from ._common import Sampler
from .perf_stages import stage_rows, summed
from ._table import fmt, text_table


class _PeakRSS(Sampler):
    """Sample the resident set size (Linux /proc) in a thread; peak above the start."""

    def __init__(self, interval=0.002):
        self.interval = interval

    @staticmethod
    def rss() -> int:
        try:
            with open("/proc/self/statm") as fh:
                return int(fh.read().split()[1]) * 4096
        except OSError:  # not Linux: memory is not reported
            return 0

    def __enter__(self):
        _release()
        self.start = self.peak = self.rss()
        return super().__enter__()

    def sample(self) -> None:
        self.peak = max(self.peak, self.rss())

    @property
    def delta_mb(self) -> float:
        return (self.peak - self.start) / 2**20

    @property
    def peak_mb(self) -> float:
        return self.peak / 2**20


def _release() -> None:
    """Return the heap's freed pages to the system (glibc), so a run's process peak is its
    own memory above the live objects, not above what earlier runs left mapped."""
    gc.collect()
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: the peak may include earlier runs' freed heap
        pass


def _timed(fn):
    """(result, wall seconds, memory sampler); the sampler also carries ``cpu``, the
    process's CPU seconds (all threads: on a shared machine the steadier figure)."""
    with _PeakRSS() as mem:
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        dt = time.perf_counter() - t0
        mem.cpu = time.process_time() - c0
    return out, dt, mem


def _best_of_two(fn):
    """The faster of two timed runs (the result of the second is dropped)."""
    first = _timed(fn)
    second = _timed(fn)
    return first if first[1] <= second[1] else second


def _torus(n, seed, noise):
    """The measured cloud: a torus of ``n`` points, with ``noise`` x the mean spacing if any."""
    pts = shapes.torus(n, seed=seed).points
    return add_noise(pts, noise, seed=seed + 1) if noise else pts


def run(sizes=(100_000, 1_000_000), k=15, seed=0, out=print, noise=0.0):
    warm = _torus(2000, seed, noise)  # compile every kernel variant once
    estimate(warm, k=k)
    estimate(warm)
    stage_rows(warm, k, _timed)
    summary = []
    for n in sizes:
        pts = _torus(n, seed, noise)
        _, t_ref, mem_ref = _best_of_two(lambda: cKDTree(pts).query(pts, k=k + 1, workers=-1))
        del _  # the reference's answer (256 MB at 1M points) is not part of the estimates' peaks
        res, t_all, mem_all = _best_of_two(lambda: estimate(pts, k=k, method="nr"))
        invalid = res.n_invalid
        del res  # each measurement starts without the previous result (its neighbours) alive
        res, t_auto, mem_auto = _timed(lambda: estimate(pts, k="auto", method="nr"))
        opts, passes = res.params["options"], res.params["passes_run"]  # the same fit: the passes auto kept
        del res
        k_top = plan(n, k="auto").k_search
        t_same = mem_same = None  # every point on k_top whole: past the budget k="auto" keeps (1M: 4.7 GB, 90 s)
        if k_top <= whole_cap(n, k):
            res, t_same, mem_same = _timed(lambda: estimate(pts, k=k_top, method="nr", options=opts, passes=passes))
            del res
        stages = stage_rows(pts, k, _timed)
        nb = build_neighbours(pts, k)
        _, t_re, m_re = _best_of_two(lambda: estimate(pts, k=k, method="nr", neighbours=nb))
        _, t_nf, m_nf = _best_of_two(lambda: estimate(pts, k=k, method="nf", neighbours=nb))
        rows = [(f"cKDTree build + query k={k + 1} (reference)", t_ref, mem_ref), *stages,
                *summed(stages, t_all, mem_all.cpu), ("core.estimate NR, end to end", t_all, mem_all),
                ('core.estimate NR, k="auto", end to end', t_auto, mem_auto)]
        rows += [(f"same fit at fixed k = {k_top} (no choice)", t_same, mem_same)] if t_same else []
        table = [[name, fmt(dt, 3), fmt(mem.cpu, 3), fmt(dt / t_ref, 3)]
                 + ([fmt(mem.delta_mb, 4), fmt(mem.peak_mb, 4)] if hasattr(mem, "peak_mb") else ["", ""])
                 for name, dt, mem in rows]
        table.append(["re-estimate NR, cached neighbours", fmt(t_re, 3), fmt(m_re.cpu, 3), fmt(t_re / t_ref, 3), "", ""])
        table.append(["re-estimate NF, cached neighbours", fmt(t_nf, 3), fmt(m_nf.cpu, 3), fmt(t_nf / t_ref, 3), "", ""])
        out(text_table(["stage", "seconds", "CPU s", "x search", "stage MB", "process peak MB"], table,
                       title=f"\n{n:,} points (torus{f', noise {noise} x spacing' if noise else ''}), k = {k}"))
        summary.append(dict(n=n, ratio=t_all / t_ref, peak_mb=max(mem_all.peak_mb, mem_auto.peak_mb),
                            reestimate=t_re, invalid=invalid, auto=t_auto / t_same if t_same else None,
                            auto_paper=t_auto / t_all, k_top=k_top, cpu_ratio=mem_all.cpu / mem_ref.cpu,
                            cpu_auto=mem_auto.cpu / mem_all.cpu, load=os.getloadavg()[0]))
    out("")
    for s in summary:
        out(f"{s['n']:>9,} points: NR k={k} / search = {s['ratio']:.2f} (target <= 1.5), "
            f"peak {s['peak_mb']:.0f} MB (target <= 2048 at 1M), "
            f"re-estimate {s['reestimate']:.3f} s (target < 0.5 s at 100k), "
            f"auto / NR k={k} = {s['auto_paper']:.1f} (target <= 3), "
            + (f"auto / same fit at fixed k={s['k_top']} = {s['auto']:.2f}, " if s["auto"] else "")
            + f"invalid {s['invalid']}; "
            f"in CPU time: NR / search = {s['cpu_ratio']:.2f}, auto / NR = {s['cpu_auto']:.1f}; "
            f"load average {s['load']:.1f}")
    return summary


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m core bench perf", description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="100000,1000000", help="comma-separated point counts")
    p.add_argument("--k", type=int, default=15)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--noise", type=float, default=0.0, help="noise as a fraction of the mean spacing (default 0)")
    a = p.parse_args(argv)
    run(tuple(int(s) for s in a.sizes.split(",")), k=a.k, seed=a.seed, noise=a.noise)
    return 0
