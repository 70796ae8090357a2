"""Given normals that are zero / NaN everywhere or over a region: the rows no file normal
decides are oriented as estimated normals are, the rows with a file normal keep its sign
(core.normal_repair.repair_normals / orient_undecided, core.stages.given_normals)."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import build_neighbours, shapes
from core.cli import main
from core.normal_repair import repair_normals, split_normals


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(3000, seed=0)


def _outward(normals, s):
    return np.einsum("ij,ij->i", normals, s.normals) > 0


@pytest.mark.parametrize("fill", [0.0, np.nan])
@pytest.mark.parametrize("k", [15, "auto"])
def test_no_usable_normal_is_estimated_and_oriented_outward(sphere, fill, k):
    given = np.full_like(sphere.points, fill)
    r = core.estimate(sphere.points, given, k=k)
    ref = core.estimate(sphere.points, k=k)
    assert _outward(r.normals, sphere).mean() >= 0.999
    assert np.mean(r.mean[r.valid] > 0) >= 0.999 and np.median(r.k1[r.valid]) == pytest.approx(1.0, abs=0.05)
    assert np.nanmean(r.mean) == pytest.approx(np.nanmean(ref.mean), abs=0.02)  # as without normals
    rep = r.params["normals_repaired"]
    assert rep["unusable"] == rep["estimated"] == rep["oriented"] == len(sphere.points)


@pytest.mark.parametrize("k", [15, "auto"])
def test_a_zeroed_region_follows_the_kept_rows(sphere, k):
    """File normals inward on the lower half, zero on the upper half: the upper half is
    estimated inward too (the kept half's sign carried through the graph), not outward."""
    given = -sphere.normals.copy()
    upper = sphere.points[:, 2] > 0
    given[upper] = 0.0
    r = core.estimate(sphere.points, given, k=k)
    inward = ~_outward(r.normals, sphere)
    assert inward[upper].mean() >= 0.999 and inward[~upper].mean() >= 0.999
    assert np.mean(r.mean[r.valid] < 0) >= 0.999  # the inward sphere's H, everywhere
    # the rim's rows take their sign from the neighbours' file normals: not counted
    assert 0 < r.params["normals_repaired"]["oriented"] < np.count_nonzero(upper)


def test_rows_with_a_file_normal_keep_their_sign_exactly(sphere):
    """Random file signs (no orientation to read from them), a zeroed cap: every usable row
    is returned as the file has it (unit length), whatever the orientation of the rest."""
    rng = np.random.default_rng(3)
    given = sphere.normals * rng.choice([-2.0, 2.0], size=(len(sphere.points), 1))
    cap = sphere.points[:, 2] > 0.6
    given[cap] = 0.0
    nb = build_neighbours(sphere.points, 15)
    unit, usable, _ = split_normals(given)
    fixed, counts = repair_normals(sphere.points, given, *nb.take(15), orientation="outward")
    np.testing.assert_array_equal(fixed[usable], unit[usable])
    assert np.isfinite(fixed).all() and counts["estimated"] == np.count_nonzero(cap)
    r = core.estimate(sphere.points, given, k=15)  # orientation "auto" keeps the file's signs
    agree = np.einsum("ij,ij->i", r.normals[usable], given[usable]) > 0
    assert agree.all()


@pytest.mark.parametrize("convention", [1.0, -1.0], ids=["outward", "inward"])
def test_a_part_with_no_file_normal_follows_the_files_convention(convention):
    """Two spheres apart: one with file normals (outward, or inward), one all zero. The
    orientation joins the parts across the gap (core.part_joins: consistent = both facing
    the same way), so the zeroed sphere takes the file's convention; the file's rows keep
    theirs."""
    a, b = shapes.sphere(2000, seed=1), shapes.sphere(2000, seed=2)
    pts = np.vstack([a.points, b.points + [5.0, 0, 0]])
    given = np.vstack([convention * a.normals, np.zeros_like(b.normals)])
    r = core.estimate(pts, given, k=15)
    facing = convention * np.einsum("ij,ij->i", r.normals, np.vstack([a.normals, b.normals]))
    assert np.mean(facing[:2000] > 0) >= 0.999 and np.mean(facing[2000:] > 0) >= 0.999


@pytest.mark.parametrize("orientation", ["keep", "outward", "propagate"])
def test_other_orientations(sphere, orientation):
    """"keep" asked outright keeps the file's signs; rows that have none are oriented all the
    same (the initial normals are cached whatever the orientation, core.stage_cache);
    "outward" and "propagate" orient every row, as before."""
    given = -sphere.normals.copy()
    given[sphere.points[:, 2] > 0] = 0.0
    r = core.estimate(sphere.points, given, k=15, orientation=orientation)
    facing = _outward(r.normals, sphere)
    expected = {"keep": 0.0, "outward": 1.0}.get(orientation)
    if expected is not None:
        assert np.mean(facing == bool(expected)) >= 0.999
    else:  # the highest point faces +z: outward
        assert facing.mean() >= 0.999


def test_cached_initial_normals_serve_any_orientation(sphere):
    from core.stage_cache import StageCache

    given = np.zeros_like(sphere.points)
    cache = StageCache()
    core.estimate(sphere.points, given, k=15, orientation="keep", cache=cache)
    r = core.estimate(sphere.points, given, k=15, cache=cache)  # "auto": the same initial normals
    assert cache.reused["initial"] == 1
    assert _outward(r.normals, sphere).mean() >= 0.999


def test_cli_says_how_many_signs_were_oriented(sphere, tmp_path, capsys):
    src = tmp_path / "zeros.ply"
    core.io.write_cloud(src, sphere.points, normals=np.zeros_like(sphere.points))
    assert main(["estimate", str(src), "-o", str(tmp_path / "out.ply"), "--k", "15"]) == 0
    text = capsys.readouterr().out
    assert ("file normals: 3000 unusable (zero, NaN or inf), 3000 estimated; 3000 of them oriented as "
            "estimated normals are") in text
