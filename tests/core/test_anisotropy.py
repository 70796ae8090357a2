"""Sampling anisotropy (core.anisotropy): scan stripes told apart from surface structure."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import anisotropy, build_neighbours, noise, shapes, shapes_thin


def _aniso(points, normals):
    idx, _ = build_neighbours(points, anisotropy.ANISO_K).take(anisotropy.ANISO_K)
    return anisotropy.anisotropy(points, normals, idx)


@pytest.mark.parametrize("make", [shapes.plane, shapes.sphere, shapes.cylinder])
@pytest.mark.parametrize("sigma", [0.0, 0.2])
def test_uniform_random_sampling_is_not_striped(make, sigma):
    """measured (20k points): median 0.33, 99th percentile <= 0.68, <= 0.07 % flagged"""
    s = make(10000, seed=1)
    pts = noise.add_noise(s.points, sigma, seed=2) if sigma else s.points
    a = _aniso(pts, s.normals)
    assert np.all((a >= 0) & (a <= 1))
    assert np.median(a) < 0.45 and np.percentile(a, 99) < 0.75
    assert anisotropy.striped(a).mean() < 0.005


@pytest.mark.parametrize("ratio, share", [(2.0, 0.99), (3.0, 0.99), (1.5, 0.8)])
def test_scan_lines_are_striped(ratio, share):
    s = shapes_thin.stripe_scan(10000, ratio=ratio, seed=0)
    assert anisotropy.striped(_aniso(s.points, s.normals)).mean() > share


def test_striped_at_noise_and_on_the_estimate_result():
    s = shapes_thin.stripe_scan(10000, ratio=3.0, seed=1)
    pts = noise.add_noise(s.points, 0.2, seed=3)
    r = core.estimate(pts, k=15, method="nf")
    assert r.anisotropy.shape == (len(pts),) and r.striped.mean() > 0.9
    assert np.array_equal(r.field("anisotropy"), r.anisotropy)
    uniform = core.estimate(shapes.plane(10000, seed=2).points, k=15, method="nf")
    assert uniform.striped.mean() < 0.005


def test_square_grid_and_border_are_not_read_as_stripes():
    """A grid's four nearest tie (each counts alike); a rim's neighbours lie on one side,
    but their nearest neighbours still lie all around."""
    grid = shapes_thin.stripe_scan(10000, ratio=1.0, seed=0)
    assert anisotropy.striped(_aniso(grid.points, grid.normals)).mean() < 0.1
    s = shapes.plane(10000, seed=4)
    a = _aniso(s.points, s.normals)
    rim = np.abs(s.points[:, :2]).max(axis=1) > 0.98 * np.abs(s.points[:, :2]).max()
    assert anisotropy.striped(a[rim]).mean() < 0.05


def test_structure_does_not_move_it():
    """The same random sampling density on a wavy and on a flat surface: alike."""
    s = shapes.plane(10000, seed=5)
    wavy = s.points.copy()
    wavy[:, 2] = 0.1 * np.sin(6 * wavy[:, 0])
    flat, bent = _aniso(s.points, s.normals), _aniso(wavy, core.estimate(wavy, k=15).normals)
    assert abs(np.median(flat) - np.median(bent)) < 0.05


def test_missing_normals_and_bad_neighbours():
    s = shapes.plane(500, seed=0)
    nrm = s.normals.copy()
    nrm[::7] = np.nan
    a = _aniso(s.points, nrm)
    assert np.all(np.isnan(a[::7])) and np.all(np.isfinite(np.delete(a, np.s_[::7])))
    with pytest.raises(ValueError, match="idx must hold at least 5"):
        anisotropy.anisotropy(s.points, s.normals, np.zeros((500, 3), dtype=int))


def test_stripe_scan_truth_is_consistent():
    s = shapes_thin.stripe_scan(5000, ratio=2.0)
    np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0)
    assert np.all(s.k1 >= s.k2)
    assert np.abs(np.einsum("ij,ij->i", s.e1, s.normals)).max() < 1e-12
    grid = shapes_thin.stripe_scan(20000, ratio=1.0)
    r = core.estimate(grid.points, k=20)  # the closed-form H is what an even sampling estimates
    inner = grid.interior
    assert np.median(np.abs(r.mean[inner] - grid.mean[inner])) < 0.01 * np.median(np.abs(grid.mean[inner])) + 1e-3
