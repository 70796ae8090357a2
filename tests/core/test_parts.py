"""k="auto" within the part a point lies on (core.parts): a cloud of many small objects far
apart was capped by the size of the whole cloud (27 spheres of 113 points took 40-59 initial
neighbours where one alone takes 15, and spheres of 50 points chose fits reaching into the next
sphere): 3-10x the |H| error of one object alone."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from core import estimate, shapes
from core.bench.scan_clouds import sphere_rings
from core.parts import chosen_cap, part_sizes


class _Rows:
    """The k nearest of every point (itself first), as the pipeline's neighbour graphs."""

    def __init__(self, pts, width=40):
        from scipy.spatial import cKDTree
        self.dist, self.idx = cKDTree(pts).query(pts, width)
        self.width = width

    def take(self, k):
        return self.idx[:, :k], self.dist[:, :k]


def _objects(kind, count, per, seed, noise):
    """``count`` unit objects of ``per`` points, each turned at random, in a grid 8 sizes apart,
    with Gaussian noise of ``noise`` x their spacing; returns (points, true normals, true H,
    each point's object)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(count ** (1 / 3)))
    pts, nrm, mean = [], [], []
    for i in range(count):
        s = shapes.sphere(per, seed=seed * 100 + i) if kind == "sphere" else shapes.ellipsoid(per, seed=seed * 100 + i)
        turn = Rotation.random(random_state=seed * 100 + i).as_matrix()
        centre = 8.0 * np.array(np.unravel_index(i, (side,) * 3), float) + rng.uniform(-1, 1, 3)
        pts.append(s.points @ turn.T + centre)
        nrm.append(s.normals @ turn.T)
        mean.append(0.5 * (s.k1 + s.k2))
    pts = np.concatenate(pts)
    spacing = np.sqrt(4 * np.pi / per)
    noisy = pts + rng.normal(0.0, noise * spacing, pts.shape)
    return noisy, np.concatenate(nrm), np.concatenate(mean), np.repeat(np.arange(count), per)


def _errors(res, truth, mean, scale):
    """(|cos| to the true normals, |H| error) at the valid points."""
    cos = np.einsum("ij,ij->i", res.normals, truth)
    sign = np.where(cos < 0, -1.0, 1.0)
    return np.abs(cos[res.valid]), np.abs(sign * res.mean * scale - mean)[res.valid]


@pytest.mark.parametrize("kind, count, per, noise, scale, seed", [
    ("sphere", 27, 113, 0.2, 1.0, 0), ("sphere", 27, 113, 0.1, 1e3, 1), ("ellipsoid", 27, 150, 0.2, 1e-2, 2),
    ("sphere", 27, 50, 0.0, 1.0, 3), ("sphere", 27, 50, 0.2, 10.0, 4), ("ellipsoid", 20, 250, 0.3, 1.0, 5)])
def test_small_objects_are_estimated_as_if_alone(kind, count, per, noise, scale, seed):
    """Normals and |H| as good as each object's estimated on its own (the whole cloud's median
    |H| error was 4x that at 113 points and 0.2 spacing of noise, 5-6x at 50 points), and no fit
    wider than half its object."""
    pts, truth, mean, part = _objects(kind, count, per, seed, noise)
    res = estimate(scale * pts)
    cos, err = _errors(res, truth, mean, scale)
    alone = [_errors(estimate(scale * pts[part == i]), truth[part == i], mean[part == i], scale) for i in range(count)]
    cos_alone, err_alone = (np.concatenate(a) for a in zip(*alone))
    assert res.valid.mean() > 0.99
    assert np.median(cos) > np.median(cos_alone) - 0.005
    assert np.median(err) < 1.25 * np.median(err_alone) + 0.01
    assert res.k_point.max() <= per // 2


def test_parts_are_cut_at_gaps_and_a_single_surface_has_none():
    """Two objects far apart are two parts; a torus with a few scattered outliers (specks of
    fewer than MIN_PART points) is one: the rule does not fire and the estimate is unchanged."""
    pts = _objects("sphere", 2, 113, 0, 0.1)[0]
    sizes = part_sizes(pts, _Rows(pts), 15)
    assert sizes is not None and (sizes == 113).all()
    torus = shapes.torus(3000, seed=0).points
    rng = np.random.default_rng(0)
    noisy = np.vstack([torus + rng.normal(0, 0.01, torus.shape), rng.uniform(-4, 4, (30, 3))])
    assert part_sizes(noisy, _Rows(noisy), 15) is None


@pytest.mark.parametrize("noise", [0.0, 0.002, 0.005])
def test_scan_rings_farther_apart_than_the_graph_reaches_are_no_objects(noise):
    """A sphere scanned in rings: the end rings are parts of their own, but curves (noisy: flat
    as a whole), one surface with the others (the rule made its H error 0.004 -> 0.055)."""
    pts = sphere_rings(noise).points
    assert part_sizes(pts, _Rows(pts), 15) is None


def test_chosen_cap_is_the_largest_candidate_within_half_a_part():
    ks = (15, 20, 28, 40, 56, 80)
    assert chosen_cap(np.array([10, 50, 113, 160, 10_000]), ks).tolist() == [15, 20, 56, 80, 80]
