"""Compile every numerical kernel once (``python -m core warmup``), so that numba's cache
holds them and the first estimate of a session, or the viewer's first view, starts at once."""

from __future__ import annotations

import numpy as np

from . import shapes
from .anisotropy import ANISO_K, anisotropy
from .estimate import estimate
from .methods import METHODS
from .noise import add_noise

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
            runs += 3
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
