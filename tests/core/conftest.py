"""Shared fixtures and known-answer helpers for the core tests.

Everything expensive (samples, the noisy torus and its estimates) is session-scoped so the
whole tests/core run stays well under a minute and a half on two cores. Helpers are exposed
as fixtures (there is no ``__init__.py``, so test modules cannot import this file).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

import core
from core import noise, shapes

# On CI the property tests draw the same examples every run (a red CI must be reproducible,
# and must not depend on the luck of the draw); on a developer's machine they explore.
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    settings.load_profile("ci")

# ----------------------------------------------------------------------------- helpers


def graph_truth(fx, fy, fxx, fxy, fyy):
    """Exact frame of a graph z = f(x, y) with the upward normal, independent of core.

    dn in the basis (r_x, r_y) is -I^-1 II (I, II the fundamental forms, II = Hess f / g),
    which gives k = +1/R on the cap z = -(x^2 + y^2)/(2R) (SPEC convention).
    Returns (normals, k1, k2, e1, e2) with k1 >= k2.
    """
    n = len(fx)
    g = np.sqrt(1.0 + fx**2 + fy**2)
    nrm = np.column_stack([-fx, -fy, np.ones(n)]) / g[:, None]
    first = np.empty((n, 2, 2))
    first[:, 0, 0] = 1 + fx**2
    first[:, 0, 1] = first[:, 1, 0] = fx * fy
    first[:, 1, 1] = 1 + fy**2
    second = np.empty((n, 2, 2))
    second[:, 0, 0] = fxx
    second[:, 0, 1] = second[:, 1, 0] = fxy
    second[:, 1, 1] = fyy
    second /= g[:, None, None]
    S = -np.linalg.solve(first, second)
    ev, evec = np.linalg.eig(S)
    ev, evec = ev.real, evec.real
    order = np.argsort(-ev, axis=1)
    ev = np.take_along_axis(ev, order, 1)
    evec = np.take_along_axis(evec, order[:, None, :], 2)
    rx = np.column_stack([np.ones(n), np.zeros(n), fx])
    ry = np.column_stack([np.zeros(n), np.ones(n), fy])
    e = evec[:, 0, :, None] * rx[:, None, :] + evec[:, 1, :, None] * ry[:, None, :]
    e /= np.linalg.norm(e, axis=2, keepdims=True)
    return nrm, ev[:, 0], ev[:, 1], e[:, 0], e[:, 1]


def hyperbolic_paraboloid(n=4000, *, a=0.5, seed=0):
    """z = a (x^2 - y^2) on [-1, 1]^2: a genuine saddle (K < 0 everywhere), exact truth."""
    rng = np.random.default_rng(seed)
    xy = (rng.random((n, 2)) - 0.5) * 2.0
    x, y = xy.T
    pts = np.column_stack([x, y, a * (x * x - y * y)])
    ones = np.ones(n)
    nrm, k1, k2, e1, e2 = graph_truth(2 * a * x, -2 * a * y, 2 * a * ones, 0 * ones, -2 * a * ones)
    interior = (np.abs(xy) < 0.8).all(axis=1)
    return shapes.Sample("hyperbolic_paraboloid", pts, nrm, k1, k2, e1, e2, interior, {"a": a})


def random_orthogonal(seed, proper=True):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if (np.linalg.det(q) > 0) != proper:
        q[:, 0] *= -1
    return q


def abs_cos(a, b):
    """|cos| of the angle between row vectors (sign-free, for principal directions)."""
    return np.abs(np.einsum("ij,ij->i", a, b)) / (
        np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1)
    )


def check_result_invariants(r, *, atol=1e-9):
    """The contract of every CurvatureResult, whatever the input.

    valid rows: k1, k2, e1, e2, normals finite; k1 >= k2; normal, e1, e2 unit and mutually
    orthogonal. invalid rows: k1, k2 NaN. n_invalid counts the invalid rows.
    """
    v = np.asarray(r.valid, dtype=bool)
    assert v.shape == (len(r.points),)
    assert r.n_invalid == int((~v).sum())
    for name in ("k1", "k2"):
        arr = getattr(r, name)
        assert np.isfinite(arr[v]).all(), f"{name} not finite on valid rows"
        assert np.isnan(arr[~v]).all(), f"{name} not NaN on invalid rows"
    for name in ("e1", "e2", "normals"):
        arr = getattr(r, name)
        assert arr.shape == (len(v), 3)
        assert np.isfinite(arr[v]).all(), f"{name} not finite on valid rows"
    if v.any():
        assert (r.k1[v] >= r.k2[v]).all()
        for name in ("e1", "e2", "normals"):
            np.testing.assert_allclose(np.linalg.norm(getattr(r, name)[v], axis=1), 1.0, atol=atol)
        n, e1, e2 = r.normals[v], r.e1[v], r.e2[v]
        for a, b in ((e1, e2), (e1, n), (e2, n)):
            assert np.abs(np.einsum("ij,ij->i", a, b)).max() < atol


_CHILD_READ = """
import json, resource, sys
import core
def vmsize():
    return next(int(l.split()[1]) * 1024 for l in open('/proc/self/status') if l.startswith('VmSize'))
limit = vmsize() + (1 << 30)  # as a small machine: a bad allocation is std::bad_alloc
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
for path in sys.argv[1:]:
    print(json.dumps(path), flush=True)
    try:
        print(json.dumps(core.io.read_cloud(path).points.tolist()), flush=True)
    except ValueError as error:
        print(json.dumps(str(error)), flush=True)
"""


def read_in_child(paths):
    """{path: points (a list) or the error message}, each file read by ``core.io.read_cloud``
    in one subprocess whose address space is limited (as on a small machine), so that a file
    that aborts the process (std::bad_alloc, a segmentation fault) fails the caller's test
    instead of ending the test run; a path missing its answer is the one that killed it."""
    run = subprocess.run([sys.executable, "-c", _CHILD_READ, *map(str, paths)], capture_output=True, text=True,
                         timeout=300, cwd=Path(core.__file__).resolve().parents[1])
    lines = [json.loads(line) for line in run.stdout.splitlines()]
    answers = dict(zip(lines[::2], lines[1::2]))
    died = [p for p in map(str, paths) if p not in answers]
    assert not died, f"reading {died[0]} ended the process (code {run.returncode}): {run.stderr[-2000:]}"
    return answers


# ----------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="session")
def helpers():
    """Namespace of the helper functions above."""

    class H:
        pass

    for f in (graph_truth, hyperbolic_paraboloid, random_orthogonal, abs_cos, check_result_invariants, read_in_child):
        setattr(H, f.__name__, staticmethod(f))
    return H


@pytest.fixture(scope="session")
def torus():
    """The paper's torus: R = 2, r = 1, 5000 area-uniform points."""
    return shapes.torus(5000, seed=0)


@pytest.fixture(scope="session")
def torus_small():
    return shapes.torus(3000, seed=11)


@pytest.fixture(scope="session")
def noisy_torus(torus):
    """(sample, noisy points, neighbours): isotropic noise of 0.2 x mean spacing, fixed seed."""
    pts = noise.add_noise(torus.points, 0.2, seed=100)
    return torus, pts, core.build_neighbours(pts, 15)


@pytest.fixture(scope="session")
def noisy_torus_results(noisy_torus):
    """NR, NF and CT with estimated normals on the noisy torus (the paper's experiment)."""
    _, pts, nb = noisy_torus
    return {m: core.estimate(pts, k=15, method=m, neighbours=nb) for m in ("nr", "nf", "ct")}


@pytest.fixture(scope="session")
def cylinder():
    return shapes.cylinder(3000, radius=0.7, height=2.8, seed=2)


@pytest.fixture(scope="session")
def ellipsoid():
    return shapes.ellipsoid(4000, seed=3)


@pytest.fixture(scope="session")
def saddle_shape():
    return shapes.saddle(4000, seed=4)


@pytest.fixture(scope="session")
def hypar():
    return hyperbolic_paraboloid(4000, seed=0)
