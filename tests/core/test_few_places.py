"""Clouds of copies of fewer places than one fit needs (round-six input audit).

Three places repeated (a broken export, a frame of three targets) have no surface: with
k="auto" and on the three points themselves every k >= 1 gives the all-invalid result that
names the reason; an integer k on their copies raised a ValueError (k exceeds the distinct
positions) instead. Now the copies get the answer of their places, as with k="auto".
"""

import numpy as np
import pytest

import core


def _places(seed):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(3, 3)) * rng.uniform(0.01, 100.0)  # three places, not collinear


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("k", [4, 15, 40])
@pytest.mark.parametrize("method", ["NR", "NF"])
def test_copies_of_three_places_are_all_invalid_like_the_places(seed, k, method):
    places = _places(seed)
    rng = np.random.default_rng(seed + 10)
    copies = places[rng.integers(0, 3, 60 + 40 * seed)]
    copies[:3] = places  # every place present
    res = core.estimate(copies, k=k, method=method)
    alone = core.estimate(places, k=k, method=method)
    assert res.points.shape == copies.shape and not res.valid.any()
    assert np.isnan(res.k1).all() and np.isnan(res.mean).all()
    assert res.params["degenerate"] == alone.params["degenerate"]
    assert res.params["duplicates"] == len(copies) - 3
    assert (res.method, res.k, res.passes) == (alone.method, alone.k, alone.passes)


@pytest.mark.parametrize("seed", [0, 3])
def test_copies_of_three_places_with_given_normals(seed):
    """Given normals are kept (unit length) on the all-invalid copies, k = 15."""
    places = _places(seed)
    copies = np.repeat(places, 30, axis=0)
    normals = np.tile([0.0, 0.0, 1.0], (len(copies), 1))
    res = core.estimate(copies, normals, k=15)
    assert not res.valid.any() and "fewer than" in res.params["degenerate"]
    assert np.allclose(res.normals, normals)

