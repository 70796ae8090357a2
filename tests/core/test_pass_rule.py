"""The pass-stop rule of k="auto" judged on a sample (core.passes): the same passes and
numbers as judging on every point, and an undone pass fitted only at the sample."""

import numpy as np
import pytest

import core
from core import fits, passes


def test_rule_sample_is_every_point_of_a_small_cloud_and_spread_over_a_large_one():
    pts = np.random.default_rng(0).random((100_000, 3))
    assert passes.rule_sample(pts[:5000], size=8000).all()
    mask = passes.rule_sample(pts, size=1000)
    assert 900 < mask.sum() < 1100  # about `size` points
    counts = np.histogram(pts[mask, 0], bins=5, range=(0, 1))[0]
    assert counts.min() > 150  # over the whole cloud, not one end of it
    # the same points whatever their order, and in any part judged against the whole
    perm = np.random.default_rng(1).permutation(len(pts))
    np.testing.assert_array_equal(passes.rule_sample(pts[perm], size=1000), mask[perm])
    np.testing.assert_array_equal(passes.rule_sample(pts[:40_000], len(pts), size=1000), mask[:40_000])


@pytest.fixture(scope="module")
def noisy():
    s = core.shapes.torus(4000, seed=3)
    return core.noise.add_noise(s.points, 0.2, seed=4)


def test_judging_on_a_sample_keeps_the_passes_and_the_numbers(noisy, monkeypatch):
    whole = core.estimate(noisy)
    assert whole.params["passes_run"] >= 2  # the rule had passes to judge
    seen = []
    real_into = fits.Fitter.into

    def into(self, out, nrm, has_normal, report, *kept):
        seen.append(int(has_normal.sum()))
        return real_into(self, out, nrm, has_normal, report, *kept)

    whole_cloud_rule = passes.rule_sample
    monkeypatch.setattr(passes, "rule_sample", lambda pts, n=None: whole_cloud_rule(pts, n, size=1000))
    monkeypatch.setattr(fits.Fitter, "into", into)
    part = core.estimate(noisy)
    assert part.params["passes_run"] == whole.params["passes_run"]
    for name in ("normals", "k1", "k2", "e1"):
        np.testing.assert_array_equal(getattr(part, name), getattr(whole, name), err_msg=name)
    kept = part.params["passes_run"] + 1
    split = [c for c in seen if c < len(noisy)]  # the passes (the crease reference fits every point)
    # each kept pass: the sample, then the rest; a pass the rule undid: the sample alone
    assert len(split) == 2 * kept + (kept <= part.params["passes"])
    assert all(split[2 * p] <= 1100 for p in range(kept)) and split[-1] <= 1100
