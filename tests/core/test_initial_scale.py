"""k="auto" measures the noise and grows the neighbourhood of its initial normals with it."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import scale, shapes
from core.normals import jet_normals, pca_normals


@pytest.mark.parametrize("sigma", [0.01, 0.03])
def test_jet_height_is_the_noise_along_the_normal(sigma):
    """On a plane with Gaussian heights the RMS residual of the 2-jet, corrected for its 6
    fitted terms, is the noise's standard deviation."""
    pts = core.shapes.plane(4000, size=4.0).points
    pts[:, 2] = np.random.default_rng(1).normal(scale=sigma, size=len(pts))
    idx, dist = core.build_neighbours(pts, 15).take(15)
    nrm, ok = pca_normals(pts, idx, dist)
    _, height = jet_normals(pts, nrm, ok, idx, dist)
    assert np.nanmedian(height) == pytest.approx(sigma, rel=0.1)


def test_jet_height_vanishes_on_a_clean_curved_surface():
    s = core.shapes.sphere(3000, seed=2)
    idx, dist = core.build_neighbours(s.points, 15).take(15)
    nrm, ok = pca_normals(s.points, idx, dist)
    _, height = jet_normals(s.points, nrm, ok, idx, dist)
    spacing = core.noise.mean_spacing(s.points)
    assert np.nanmedian(height) < 0.005 * spacing


def test_take_without_skips_flagged_neighbours_but_keeps_the_point_itself():
    pts = core.shapes.plane(500, size=4.0).points
    nb = core.build_neighbours(pts, 30)
    drop = np.zeros(len(pts), dtype=bool)
    drop[::7] = True
    idx, dist = nb.take_without(15, drop)
    full_idx, full_dist = nb.take(30)
    assert np.array_equal(idx[:, 0], full_idx[:, 0])  # each point first, flagged or not
    assert not drop[idx[:, 1:]].any()
    for r in (0, 1, 250):  # the nearest unflagged ones, in order
        keep = full_idx[r, 1:][~drop[full_idx[r, 1:]]][:14]
        assert np.array_equal(idx[r, 1:], keep)
    assert (np.diff(dist, axis=1) >= 0).all()


def test_auto_measures_the_noise_and_grows_the_initial_neighbourhood_as_its_root():
    s = core.shapes.torus(5000, seed=5)
    got = {}
    for sigma in (0.0, 0.1, 0.4):
        r = core.estimate(core.noise.add_noise(s.points, sigma, seed=6))
        got[sigma] = (r.params["noise"], r.params["initial_k"])
    # noise in units of the radius of 15 neighbours (~4.2 mean spacings)
    assert got[0.0][0] < 0.005 and got[0.0][1] == 15
    assert got[0.1][0] == pytest.approx(0.1 / 4.2, rel=0.15)
    assert got[0.4][0] == pytest.approx(4 * got[0.1][0], rel=0.1)
    assert got[0.4][1] == pytest.approx(2 * got[0.1][1], abs=2)  # k ∝ sqrt(noise)
    assert core.estimate(s.points, k=15).params["initial_k"] is None  # the paper's pipeline


def test_noise_adapted_initial_normals_beat_the_fixed_15(monkeypatch):
    """Saddle surface at 0.2 spacing of noise: 15 neighbours leave the initial normals noisy,
    and what the wide cubic fit inherits shows in e1 (measured 1.44 -> 0.97 degrees)."""
    s = core.shapes.saddle(5000, seed=3)
    p = core.noise.add_noise(s.points, 0.2, seed=4)
    adapted = core.metrics.summary(core.estimate(p), s)
    monkeypatch.setattr(scale, "INITIAL_K0", 0.0)  # always 15
    fixed = core.metrics.summary(core.estimate(p), s)
    assert adapted["direction_deg"] < 0.85 * fixed["direction_deg"]
    assert adapted["mean"] < fixed["mean"]


@pytest.mark.parametrize("n", [100, 150])
def test_coarse_small_cloud_keeps_its_initial_neighbourhood_local(n):
    """A coarse sample reads as noise (the 2-jets' residual is the bend between samples): a
    150-point torus took 42-45 initial neighbours, its tube's far side among them, and
    k="auto" faced inward at 99 % of the points (seed 1). The initial neighbourhood holds at
    most a tenth of the cloud (tuning.INITIAL_SHARE)."""
    for seed in range(4):
        s = shapes.torus(n, seed=seed)
        r = core.estimate(s.points)
        assert r.params["initial_k"] <= max(15, n // 10)
        outward = np.einsum("ij,ij->i", r.normals[r.valid], s.normals[r.valid]) > 0
        # measured 0.95-1.0 (a few lone points of 100); 0.90 on seed 2 since the own-sheet rows
        # (core.one_sheet): the tube is a spacing across and its far side reads as another sheet
        assert outward.mean() > 0.88, (seed, outward.mean())
