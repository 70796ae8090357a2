"""Compile every numerical kernel once (``python -m core warmup``), so that numba's cache
holds them and the first estimate of a session, or the viewer's first view, starts at once."""

from __future__ import annotations

import io

import numpy as np

from . import shapes
from .anisotropy import ANISO_K, anisotropy
from .estimate import estimate
from .gauss_bonnet import gauss_bonnet
from .io.write import write_result
from .methods import METHODS
from .neighbours import build_neighbours
from .noise import add_noise
from .planning import plan
from .stage_cache import StageCache

#: option sets beyond each method's defaults that select other compiled code paths
EXTRA_OPTIONS = {
    "nr": [{"degree": 1, "robust": None}, {"degree": 2}, {"weights": "uniform", "constraint": "exact"},
           {"robust": "huber"}],
    "jet": [{"degree": 2}, {"degree": 3}],
}


def warm_up(n_points: int = 400) -> int:
    """Run tiny estimates of every method at k=15 (and k="auto" for NF/NR); returns the count."""
    cloud = shapes.torus(n_points, seed=0)
    noisy = add_noise(cloud.points, 0.3, seed=1)  # NR on the noise floor (its fold cap), not the jets
    runs = 0
    for name in METHODS:
        for options in [{}, *EXTRA_OPTIONS.get(name, [])]:
            estimate(cloud.points, k=15, method=name, options=options)
            runs += 1
        if name in ("nf", "nr"):
            res = estimate(cloud.points, method=name)
            _lazy_flags(res)
            res.neighbours.rows(np.arange(4), res.neighbours.k_max)  # the search of rows past the columns held
            estimate(cloud.points, cloud.normals, method=name)
            estimate(noisy, method=name)
            runs += 3 + _data_dependent_types(name)
        runs += _read_only_inputs(cloud, noisy, name)
    res = estimate(cloud.points, k=15)
    gauss_bonnet(res)  # the viewer's Teach mode: the cells' parallel kernel
    write_result(io.BytesIO(), res, format="csv")  # the text writer's kernel (the first CSV export compiled ~4 s)
    return runs + 1


def _data_dependent_types(method) -> int:
    """k="auto" on clouds that take the paths a larger cloud takes where the type of an array
    depends on the data: a plane's jets grow past the columns searched first (rows searched
    wider, ``kdtree.query_rows``, and the jets rerun on them); on a cube the points where a
    higher degree is tried are not one run of indices (rows copied rather than viewed). Each plainly, through a StageCache and on the read-only
    points of a given graph. Without these the first k="auto" estimate of a 100k torus
    after warm-up compiled for ~8 s. A noisy cloud with points off its surface takes the
    anchors' shared fits and robust mode's neighbours without the outliers, plainly and
    through a StageCache (without it a noisy 100k torus compiled six kernels anew). Clouds
    that are no smooth surface pass arrays of other layouts: a volume of points (foliage; a
    first Gaussian blob compiled six of orientation's kernels and a pool on C-contiguous
    writable rows, ~10 s) and a strip 1000x longer than wide (``distances_at`` on read-only
    rows).
    Returns the count of runs."""
    for cloud in (shapes.plane(400, seed=0), shapes.cube(600, seed=0)):
        estimate(cloud.points, method=method)
        estimate(cloud.points, method=method, cache=StageCache())
        pts = np.array(cloud.points)
        estimate(pts, method=method, neighbours=build_neighbours(pts, plan(len(pts), k="auto").k_search))
    estimate(_parallels(), method=method)  # scan lines far apart: initial normals on wider rows
    noisy = _noisy_with_strays()
    estimate(noisy, method=method)
    estimate(noisy, method=method, cache=StageCache())
    rng = np.random.default_rng(0)
    estimate(rng.normal(size=(3000, 3)), method=method)  # no surface (foliage)
    estimate(np.c_[rng.uniform(0, 1000, 3000), rng.uniform(0, 1, 3000), rng.normal(0, 0.01, 3000)], method=method)
    return 11


def _noisy_with_strays(n: int = 6000) -> np.ndarray:
    """A torus of ``n`` points at 0.2 spacing of noise (k="auto" fits 320 neighbours there, at
    anchors) and 12 points off its surface (outliers to robust mode)."""
    pts = add_noise(shapes.torus(n, seed=1).points, 0.2, seed=2)
    return np.vstack([pts, 1.4 * pts[:12] + np.random.default_rng(0).normal(size=(12, 3)) * 0.05])


def _parallels(n_line: int = 60, lines: int = 8, ratio: float = 10.0) -> np.ndarray:
    """A sphere patch scanned along parallels ``ratio`` x the along-line spacing apart."""
    step = 1.0 / (n_line - 1)
    theta, phi = np.meshgrid(np.arange(n_line) * step - 0.5, (np.arange(lines) - (lines - 1) / 2) * step * ratio)
    return np.column_stack([np.cos(phi.ravel()) * np.cos(theta.ravel()), np.cos(phi.ravel()) * np.sin(theta.ravel()),
                            np.sin(phi.ravel())])


def _read_only_inputs(cloud, noisy, method) -> int:
    """The same kernels on read-only arrays, a type of their own for numba: the stages a
    :class:`core.stage_cache.StageCache` keeps (the viewer's every estimate after its first)
    and the points of a :func:`core.build_neighbours` graph passed as ``neighbours=``.
    Without these the viewer's first result, or a user's first re-estimate on a kept
    graph, compiled for ~10 s. Returns the count of runs."""
    runs, auto = 0, method in ("nf", "nr")
    calls = (("auto", None), ("auto", 2), (15, None)) if auto else ((15, None), (15, None))
    for points, normals in ((cloud.points, None), (cloud.points, cloud.normals), (noisy, None)):
        cache = StageCache()
        for k, passes in calls:  # computed, then re-used (read-only)
            estimate(points, normals, k=k, method=method, passes=passes, cache=cache)
            runs += 1
    for k in (15, "auto") if auto else (15,):
        pts = cloud.points.copy()
        estimate(pts, k=k, method=method, neighbours=build_neighbours(pts, plan(len(pts), k=k).k_search))
        runs += 1
    return runs


def _lazy_flags(res) -> None:
    """Compile the kernels of the result's lazy anisotropy for both array types it meets:
    neighbour arrays come back from an estimate read-only, a type of its own for numba
    (else the viewer's first result compiles them on its job thread)."""
    idx = res.neighbours.take(ANISO_K)[0]
    for writable in (True, False):
        rows = np.array(idx)  # a copy whose flag can be set either way
        rows.setflags(write=writable)
        anisotropy(res.points, res.normals, rows)
