"""Given normals worse than the estimator's own (k="auto"): crude PCA normals of a tool, tilted
normals, are only signs, the own initial normals start the fits; exact normals still start
them (core.given_normals_check, core.stages.judged_given; params["normals_repaired"]["use"])."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial import cKDTree

import core
from core import shapes
from core.io import read_cloud

N = 4000
RESOURCES = Path(__file__).resolve().parents[2] / "resources"


def _noisy(s, noise, seed=3):
    """The shape's points with Gaussian noise of ``noise`` x the mean spacing along each axis."""
    spacing = np.median(cKDTree(s.points).query(s.points, 2)[0][:, 1])
    return s.points + np.random.default_rng(seed).normal(0, noise * spacing, s.points.shape)


def _crude(pts, truth, k):
    """A tool's normals: plain PCA on the ``k`` nearest, signed as ``truth``."""
    _, idx = cKDTree(pts).query(pts, k)
    q = pts[idx] - pts[idx].mean(axis=1, keepdims=True)
    nrm = np.linalg.eigh(np.einsum("nki,nkj->nij", q, q))[1][:, :, 0]
    return nrm * np.sign(np.einsum("ij,ij->i", nrm, truth))[:, None]


def _tilted(truth, degrees, seed=5):
    """``truth`` tilted each by a random angle (half-normal, scale ``degrees``) about a random axis."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=truth.shape)
    axis -= np.einsum("ij,ij->i", axis, truth)[:, None] * truth
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = np.radians(degrees) * np.abs(rng.normal(size=(len(truth), 1)))
    return truth * np.cos(angle) + axis * np.sin(angle)


def _h_error(r, s):
    return float(np.nanmedian(np.abs(r.mean - s.mean)))


def _use(r):
    return r.params["normals_repaired"]["use"]


SHAPES = {"torus": lambda: shapes.torus(N, seed=1), "sphere": lambda: shapes.sphere(N, seed=1),
          "ellipsoid": lambda: shapes.ellipsoid(N, seed=1), "saddle": lambda: shapes.saddle(N, seed=1)}


@pytest.mark.parametrize("shape", list(SHAPES))
@pytest.mark.parametrize("noise", [0.1, 0.2, 0.5])
@pytest.mark.parametrize("k_tool", [5, 8])
def test_crude_normals_are_only_signs(shape, noise, k_tool):
    """PCA normals on 5-8 neighbours cost 2-9x in |H| as the start; as signs, the result is the
    own normals' (the error of the estimate without normals), facing the given side."""
    s = SHAPES[shape]()
    pts = _noisy(s, noise)
    r = core.estimate(pts, _crude(pts, s.normals, k_tool))
    own = core.estimate(pts)
    assert _use(r) == "signs"
    assert _h_error(r, s) <= 1.1 * _h_error(own, s)
    assert np.mean(np.einsum("ij,ij->i", r.normals, s.normals)[r.valid] > 0) == 1.0


@pytest.mark.parametrize("shape", list(SHAPES))
@pytest.mark.parametrize("noise", [0.0, 0.1, 0.5])
def test_exact_normals_still_start_the_fits(shape, noise):
    """Analytic normals read R <= 2.7: they start the fits and beat the own ones under noise."""
    s = SHAPES[shape]()
    pts = _noisy(s, noise)
    r = core.estimate(pts, s.normals)
    assert _use(r) == "initial" and r.params["normals_repaired"]["roughness"] < 3.0
    if noise:
        assert _h_error(r, s) < 0.95 * _h_error(core.estimate(pts), s)


@pytest.mark.parametrize("noise, degrees, use", [(0.2, 1.0, "initial"), (0.5, 2.0, "initial"), (0.1, 3.0, "signs"),
                                                 (0.2, 5.0, "signs"), (0.05, 2.0, "signs")])
@pytest.mark.parametrize("shape", ["torus", "sphere"])
def test_tilted_normals_judged_by_what_they_cost(shape, noise, degrees, use):
    """Normals tilted by a few degrees are the start while they help (small tilts, more noise:
    the fits average them), signs once the own start is better: never 10 % worse than the own start."""
    s = SHAPES[shape]()
    pts = _noisy(s, noise)
    r = core.estimate(pts, _tilted(s.normals, degrees))
    assert _use(r) == use
    assert _h_error(r, s) <= 1.1 * _h_error(core.estimate(pts), s)


@pytest.mark.parametrize("fill", [0.0, np.nan])
@pytest.mark.parametrize("source", ["crude", "exact"])
def test_unusable_rows_repaired_then_judged(fill, source):
    """Zero / NaN rows are still estimated and counted; the verdict is the same as without them."""
    s = shapes.torus(N, seed=2)
    pts = _noisy(s, 0.2)
    given = _crude(pts, s.normals, 6) if source == "crude" else s.normals.copy()
    holes = np.random.default_rng(0).choice(N, N // 20, replace=False)
    given[holes] = fill
    r = core.estimate(pts, given)
    rep = r.params["normals_repaired"]
    assert rep["unusable"] == rep["estimated"] == len(holes)
    assert _use(r) == ("signs" if source == "crude" else "initial")
    assert np.all(np.einsum("ij,ij->i", r.normals, s.normals)[r.valid] > 0)


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("source", ["crude", "exact"])
def test_verdict_invariant_to_pose_and_scale(scale, source):
    s = shapes.ellipsoid(N, seed=3)
    pts = _noisy(s, 0.2)
    given = _crude(pts, s.normals, 7) if source == "crude" else s.normals
    base = core.estimate(pts, given).params["normals_repaired"]
    rot = _rotation(int(scale * 10) + 1)
    moved = core.estimate((pts - 0.3) @ rot.T * scale, given @ rot.T).params["normals_repaired"]
    assert moved["use"] == base["use"] == ("signs" if source == "crude" else "initial")
    assert moved["roughness"] == pytest.approx(base["roughness"], rel=0.05)


@pytest.mark.parametrize("source", ["crude", "exact"])
@pytest.mark.parametrize("signs", ["inward", "random"])
def test_given_sides_kept(source, signs):
    """Given normals facing inward (or each row either way) come back facing as given,
    whichever normals started the fits."""
    s = shapes.sphere(N, seed=4)
    pts = _noisy(s, 0.2)
    given = _crude(pts, s.normals, 6) if source == "crude" else s.normals.copy()
    flip = -np.ones(N) if signs == "inward" else np.random.default_rng(1).choice([-1.0, 1.0], N)
    given *= flip[:, None]
    r = core.estimate(pts, given)
    assert _use(r) == ("signs" if source == "crude" else "initial")
    assert np.mean(np.einsum("ij,ij->i", r.normals, given)[r.valid] > 0) >= 0.999
    if signs == "inward":
        assert np.mean(r.mean[r.valid] < 0) >= 0.999  # the inward sphere's H


def test_integer_k_unchanged_and_undiagnosed():
    """k=15 (the paper's pipeline) starts from the given normals as before, without a verdict."""
    s = shapes.torus(N, seed=1)
    pts = _noisy(s, 0.2)
    given = _crude(pts, s.normals, 6)
    r = core.estimate(pts, given, k=15)
    assert "use" not in r.params["normals_repaired"]
    assert _use(core.estimate(pts, given)) == "signs"


def test_bunny_file_normals_read_and_their_sides_kept():
    """The viewer's sample: its file normals (mesh normals of a scan) read rough at its low
    noise (R 6 where the bar is 2.25), so its result is the own normals', facing the file's side."""
    cloud = read_cloud(RESOURCES / "bunny.ply")
    r = core.estimate(cloud.points, cloud.normals)
    assert _use(r) == "signs"
    np.testing.assert_allclose(r.mean, core.estimate(cloud.points).mean, rtol=1e-9, atol=1e-12)
    assert np.mean(np.einsum("ij,ij->i", r.normals, cloud.normals) > 0) == 1.0
