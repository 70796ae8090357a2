"""k="auto": where the pass after the kept one repeats the kept pass's change of H, the kept
pass drifted and the point reports the curvatures of the pass before (core.drift)."""

from __future__ import annotations

import numpy as np

import core
from core import drift, metrics, noise, shapes
from core.fits import Fit


def _fit(h, normals=None, valid=None):
    n = len(h)
    nrm = np.tile([0.0, 0.0, 1.0], (n, 1)) if normals is None else normals
    ok = np.ones(n, dtype=bool) if valid is None else valid
    e1, e2 = np.tile([1.0, 0.0, 0.0], (n, 1)), np.tile([0.0, 1.0, 0.0], (n, 1))
    return Fit(nrm, h + 0.5, h - 0.5, e1, e2, ok, np.zeros(n), np.zeros(n), np.full(n, 3, dtype=np.int8))


def _ring(n, width):
    """Each point's ``width`` nearest on a ring of n points (itself first)."""
    offsets = np.array([0] + [s * d for d in range(1, width) for s in (1, -1)][:width - 1])
    return (np.arange(n)[:, None] + offsets[None, :]) % n


def test_a_change_the_next_pass_repeats_is_drift_and_noise_is_not():
    rng = np.random.default_rng(0)
    n, idx = 400, _ring(400, 40)
    h0 = np.full(n, 1.0)
    repeated = drift.drifted(_fit(h0), _fit(h0 - 0.1), _fit(h0 - 0.18), idx)  # smoothing, pass after pass
    assert repeated.all()
    h1 = h0 + rng.normal(0, 0.1, n)  # a pass that removed noise, then one that removes a little of what is left
    noisy = drift.drifted(_fit(h1), _fit(h0), _fit(h0 + rng.normal(0, 0.02, n)), idx)
    assert noisy.mean() < 0.05


def test_stepping_back_takes_the_pass_before_turned_to_the_kept_normals():
    n, idx = 50, _ring(50, 40)
    kept = _fit(np.full(n, 0.9))
    before = _fit(np.full(n, -1.0), normals=np.tile([0.0, 0.0, -1.0], (n, 1)))  # the other side: H = +1 here
    out = drift.step_back(before, kept, _fit(np.full(n, 0.82)), idx)
    np.testing.assert_allclose(out.k1, 1.5)  # -k2 of the pass before
    np.testing.assert_allclose(out.k2, 0.5)
    assert out.normals is kept.normals and out.e1 is kept.e1  # only the curvatures step back
    invalid = drift.step_back(before._replace(valid=np.zeros(n, dtype=bool)), kept, _fit(np.full(n, 0.82)), idx)
    np.testing.assert_array_equal(invalid.k1, kept.k1)


def test_the_chirps_mean_curvature_with_noise_does_not_drift():
    """The chirp's ridges tighten across the patch and the kept pass smoothed their
    curvature: mean |H| error 0.054 at 0.1 spacing with its curvatures, 0.044 stepped back."""
    sample = shapes.chirp(6000, seed=0)
    pts = noise.add_noise(sample.points, 0.1, seed=17)
    res = core.estimate(pts)
    assert res.params["passes_run"] >= 1
    assert metrics.summary(res, sample)["mean"] < 0.048
