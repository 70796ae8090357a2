"""``python -m core warmup`` compiles what the viewer and a re-estimate run next.

numba compiles a kernel once per type signature, and a read-only array is a type of its
own: the stages a StageCache keeps are read-only, and so are the points of a
``build_neighbours`` graph. Judged by the dispatchers' in-memory signatures (not by
compile events, which a warm disk cache would hide): after ``warm_up()`` these calls
must add none."""

import numpy as np
from numba.core.registry import CPUDispatcher

import core.kernels
from core import METHODS, build_neighbours, estimate, plan, shapes
from core.noise import add_noise
from core.stage_cache import StageCache
from core.warmup import warm_up


def _kernels():
    """Every numba dispatcher of the kernel modules."""
    found = []
    for mod in list(vars(core.kernels).values()) + [core.kernels]:
        for obj in vars(mod).values() if hasattr(mod, "__dict__") else ():
            if isinstance(obj, CPUDispatcher) and obj not in found:
                found.append(obj)
    return found


def _signatures():
    return {f: set(map(str, f.signatures)) for f in _kernels()}


def test_warm_up_covers_cached_stages_and_given_neighbours():
    warm_up()
    before = _signatures()
    assert len(before) > 20  # the kernels were found
    cloud = shapes.sphere(700, seed=3)
    noisy = add_noise(cloud.points, 0.3, seed=4)
    for method in METHODS:
        auto = method in ("nf", "nr")
        calls = (("auto", None), ("auto", 3), (15, None), (20, 2)) if auto else ((15, None), (20, None))
        for points, normals in ((cloud.points, None), (cloud.points, cloud.normals), (noisy, None)):
            cache = StageCache(k_max=40)
            for k, passes in calls:
                estimate(points, normals, k=k, method=method, passes=passes if auto else None, cache=cache)
        for k in (15, "auto") if auto else (15,):
            pts = np.array(cloud.points)
            estimate(pts, k=k, method=method, neighbours=build_neighbours(pts, plan(len(pts), k=k).k_search))
    estimate(shapes.torus(20_000, seed=5).points, method="nr")  # data-dependent types of a larger cloud
    for n, level in ((60_000, 0.2), (30_000, 0.5)):  # ... and of larger noisy ones with strays (anchors, outliers)
        pts = add_noise(shapes.torus(n, seed=6).points, level, seed=7)
        estimate(np.vstack([pts, 1.3 * pts[:20]]), method="nr")
    rng = np.random.default_rng(8)  # clouds that are not a smooth surface: a volume (foliage), a long strip (a road)
    estimate(rng.normal(size=(8000, 3)), method="nr")
    estimate(np.c_[rng.uniform(0, 2000, 8000), rng.uniform(0, 1, 8000), rng.normal(0, 0.01, 8000)], method="nr")
    after = _signatures()
    added = {f.py_func.__qualname__: sorted(after[f] - before.get(f, set()))
             for f in after if after[f] - before.get(f, set())}
    assert not added, f"compiled after warm_up (first use would compile on the viewer's job thread): {added}"
