"""Orientation across thin parts (core.orientation) on the shapes of core.shapes_thin."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import build_neighbours, orientation, shapes_thin
from core.normals import pca_normals


def _noisy(s, sigma_spacings, seed=1):
    """Noise of ``sigma_spacings`` x the shape's spacing. (It was passed to add_noise as a
    relative sigma, which multiplied it by the mean spacing once more: ~1e-5 spacing, so
    the "noisy" cases here ran noise-free.)"""
    return shapes_thin.noisy(s, sigma_spacings, seed)


@pytest.fixture(scope="module", params=sorted(shapes_thin.THIN_SHAPES))
def thin(request):
    return shapes_thin.THIN_SHAPES[request.param](20000, seed=0)


def _clear_agreement(normals, s):
    """Agreement (per part for open sheets) over the points whose normal is not across the
    truth (|n . truth| > 0.5): a crease point's blended normal has no right side."""
    d = np.abs(np.einsum("ij,ij->i", np.nan_to_num(normals), s.normals))
    clear = d > 0.5
    parts = s.params.get("parts")
    return shapes_thin.orientation_agreement(normals[clear], s.normals[clear],
                                              None if parts is None else parts[clear])


@pytest.mark.parametrize("sigma", [0.0, 0.2])
def test_thin_parts_oriented_outward(thin, sigma):
    """measured (seed 0/1, 20k points, NF): >= 0.9975 of the clear points at sigma 0.2
    spacing, >= 0.9997 noise-free; Hoppe's propagation gave 0.51 on the plate and 0.54 on
    the shell. Over all points, judged by the outward side of the normal cone at sharp
    edges (shapes_thin.cone_normals): >= 0.9966 at 0.2 spacing."""
    r = core.estimate(_noisy(thin, sigma), k=15, method="nf")
    assert _clear_agreement(r.normals, thin) >= 0.995, thin.name
    assert shapes_thin.orientation_agreement(r.normals, shapes_thin.cone_normals(thin),
                                             thin.params.get("parts")) >= 0.995, thin.name


@pytest.mark.parametrize("seed", [1, 2])
def test_shell_inner_side_not_flipped_by_the_gap(seed):
    """A bowl 3 spacings thick at noise 0.2 spacing: the few neighbours across the gap
    inflated an RMS spread that gated the chord test, and the whole inner side flipped
    (54 % agreement at seeds 1 and 2); with the median offset >= 99.3 %."""
    s = shapes_thin.thin_shell(20000, seed=seed)
    pts = _noisy(s, 0.2, seed=seed + 1)
    idx, dist = build_neighbours(pts, 15).take(15)
    nrm, ok = pca_normals(pts, idx, dist)
    o = orientation.orient(pts, nrm, idx, "outward", ok=ok)
    inner = s.params["faces"] == 1
    assert shapes_thin.orientation_agreement(o.normals[inner], s.normals[inner]) > 0.99
    assert shapes_thin.orientation_agreement(o.normals, shapes_thin.cone_normals(s)) > 0.99


def test_cone_normals_are_the_truth_on_faces_and_outward_on_edges():
    plate = shapes_thin.thin_plate(5000, seed=0)
    cone = shapes_thin.cone_normals(plate)
    np.testing.assert_allclose(np.linalg.norm(cone, axis=1), 1.0)
    faces = plate.interior
    on_face = np.einsum("ij,ij->i", cone[faces], plate.normals[faces])
    assert np.all(on_face > 0.7) and np.mean(on_face > 0.999) > 0.95  # 2 spacings in: a few see the rim
    edge = ~faces
    assert np.all(np.einsum("ij,ij->i", cone[edge], plate.points[edge]) > 0)  # outward (centre at 0)
    assert np.mean(np.einsum("ij,ij->i", cone[edge], plate.normals[edge]) < 0.99) > 0.3  # blended there


def test_plate_beats_hoppe_where_it_fails():
    """The noisy thin plate is where Hoppe's cost 1 - |n_i . n_j| joins the two sides."""
    s = shapes_thin.thin_plate(20000, seed=0)
    pts = _noisy(s, 0.2)
    nb = build_neighbours(pts, 15)
    idx, dist = nb.take(15)
    nrm, ok = pca_normals(pts, idx, dist)
    o = orientation.orient(pts, nrm, idx, "outward", ok=ok)
    assert _clear_agreement(o.normals, s) > 0.995
    assert o.confidence.shape == (len(pts),)
    assert np.all((o.confidence >= 0) & (o.confidence <= 1))
    wrong = np.einsum("ij,ij->i", o.normals, s.normals) < 0
    assert np.median(o.confidence[~wrong]) > 0.99
    assert np.median(o.confidence[wrong]) < np.median(o.confidence[~wrong])


def test_confidence_low_where_signs_alternate():
    """A sphere with every other normal flipped is 'keep'-ed: the confidence says so."""
    s = core.shapes.sphere(3000, seed=3)
    nb = build_neighbours(s.points, 15)
    idx, _ = nb.take(15)
    flipped = s.normals * np.where(np.arange(3000) % 2 == 0, 1.0, -1.0)[:, None]
    kept = orientation.orient(s.points, flipped, idx, "keep")
    np.testing.assert_array_equal(kept.normals, flipped)
    assert np.median(kept.confidence) < 0.8
    fixed = orientation.orient(s.points, flipped, idx, "outward")
    assert np.all(np.einsum("ij,ij->i", fixed.normals, s.normals) > 0)
    assert np.min(fixed.confidence) > 0.9


def test_orient_does_not_modify_input_and_handles_missing_normals():
    s = core.shapes.sphere(2000, seed=4)
    nb = build_neighbours(s.points, 15)
    idx, _ = nb.take(15)
    given = -s.normals.copy()
    given[::50] = np.nan
    before = given.copy()
    o = orientation.orient(s.points, given, idx, "outward")
    np.testing.assert_array_equal(given, before)
    have = np.isfinite(given).all(axis=1)
    assert np.all(o.labels[~have] == -1) and np.all(o.confidence[~have] == 0)
    assert np.all(np.einsum("ij,ij->i", o.normals[have], s.normals[have]) > 0)


def test_propagate_makes_highest_point_face_up():
    s = shapes_thin.two_sheets(6000, seed=2)
    nb = build_neighbours(s.points, 15)
    idx, _ = nb.take(15)
    o = orientation.orient(s.points, s.normals, idx, "propagate")
    for part in (0, 1):
        rows = np.flatnonzero(s.params["parts"] == part)
        top = rows[np.argmax(s.points[rows, 2])]
        assert o.normals[top, 2] >= 0
        d = np.einsum("ij,ij->i", o.normals[rows], s.normals[rows])
        assert np.all(d > 0) or np.all(d < 0)


def test_thin_shapes_are_what_they_say():
    """Thickness in spacings, unit outward normals, curvature signs of a solid's surface."""
    tube = shapes_thin.thin_tube(20000)
    assert tube.params["r"] == pytest.approx(2 * tube.params["spacing"])
    plate = shapes_thin.thin_plate(20000)
    thick = np.ptp(plate.points[:, 2])
    assert thick == pytest.approx(3 * plate.params["spacing"], rel=1e-6)
    shell = shapes_thin.thin_shell(20000)
    parts = shell.params["faces"]
    assert np.all(shell.mean[parts == 1] < 0) and np.all(shell.mean[parts == 0] > 0)
    wedge = shapes_thin.thin_wedge(20000)
    ends = wedge.params["faces"]
    for face, spacings in ((2, 2.0), (3, 5.0)):  # the x- and x+ sides: 2 and 5 spacings high
        assert np.ptp(wedge.points[ends == face, 2]) == pytest.approx(spacings * wedge.params["spacing"], rel=0.05)
    top = ends == 0
    np.testing.assert_allclose(np.einsum("ij,ij->i", wedge.points[top] - wedge.points[top][:1], wedge.normals[top]), 0,
                               atol=1e-12)  # the top is the plane of its normal
    for s in (tube, plate, shell, shapes_thin.two_sheets(20000), wedge):
        np.testing.assert_allclose(np.linalg.norm(s.normals, axis=1), 1.0)
        assert np.all(s.k1 >= s.k2)


def test_result_carries_orientation_confidence():
    s = shapes_thin.thin_plate(20000, seed=0)
    r = core.estimate(_noisy(s, 0.2), k=15, method="nf")
    c = r.orientation_confidence
    assert c.shape == (len(s.points),) and np.all((c >= 0) & (c <= 1))
    wrong = np.einsum("ij,ij->i", r.normals, s.normals) < 0
    assert np.median(c[~wrong]) > 0.99 and np.median(c[wrong]) < np.median(c[~wrong])


@pytest.mark.parametrize("cap_z, flipped", [(0.9, 183), (0.6, 859)])
def test_flipped_patch_is_turned_by_its_seam(cap_z, flipped):
    """A cap of a sphere given inward normals (the rest outward): its points agree with
    each other, so the local majority, which flips a point at a time, turns only its rim
    (3 sweeps: 184 and 887 points still inward). resettle re-decides the patch whole by the
    evidence across its seam (core.kernels.patches, tuning.PATCH_MAX = 1000 points)."""
    s = core.shapes.sphere(4000, seed=3)
    idx = build_neighbours(s.points, 15).take(15)[0]
    cap = s.points[:, 2] > cap_z
    assert cap.sum() == flipped
    given = np.where(cap[:, None], -s.normals, s.normals)
    sign, confidence = orientation.resettle(s.points, given, idx, "outward")
    assert np.all(np.einsum("ij,ij->i", given * sign[:, None], s.normals) > 0)
    assert np.min(confidence) > 0.9
    kept, _ = orientation.resettle(s.points, given, idx, "keep")
    np.testing.assert_array_equal(kept, 1.0)


def _face_shares(name, k, seeds, sigma=0.2):
    """Face shares (all points) of the default method, 20k points, noise ``sigma`` spacing."""
    out = []
    for seed in seeds:
        s = shapes_thin.THIN_SHAPES[name](20000, seed=seed)
        r = core.estimate(shapes_thin.noisy(s, sigma, seed + 1), k=k)
        out.append(shapes_thin.sign_agreement(r.normals, s)[1])
    return np.array(out)


def test_rims_at_k15_ten_seeds():
    """Issue 12 at k=15, noise 0.2 spacing, seeds 0-9 (README "Real scans"): the signs
    re-decided on the refined normals weight Hoppe's term by the raw chord offsets and flip
    patches whole by their seam (core.orientation.resettle). Face share before -> after
    (min / mean): plate 99.395 / 99.512 -> 99.445 / 99.570 %; wedge 98.725 / 99.458 ->
    99.435 / 99.578 % (seed 1 kept 120 points of its thin end's top flipped); the
    L-bracket (shapes_thin.thin_bracket) 99.405 / 99.490 -> 99.410 / 99.511 %. The fits
    are the paper's (only signs change), so 99.5 % at every seed is not reached: what is
    left are rim normals more than 60 degrees off their face's, half of them across it.
    The gate's noise floor (core.orientation_evidence, which turned the thin lens outward):
    plate 99.445 / 99.584 -> 99.435 / 99.584 % (seed 8: two points), wedge 99.435 / 99.565 ->
    99.440 / 99.571 %."""
    plate = _face_shares("thin_plate", 15, range(10))
    assert plate.min() >= 0.9943 and plate.mean() >= 0.9955, plate
    wedge = _face_shares("thin_wedge", 15, range(10))
    assert wedge.min() >= 0.9940 and wedge.mean() >= 0.9955, wedge


def test_thin_rims_at_auto_ten_seeds():
    """Issue 12 at k="auto", noise 0.2 spacing: its initial normals (58 neighbours there)
    lay across the wedge's 2-spacing rim, both faces and the side between them, and no
    later scale or sign repaired them (NR's fits forced to 10 neighbours there: no gain).
    Where the PCA_K normals of the wide neighbourhood disagree (core.initial_normals.unfolded,
    tuning.FOLD_SPREAD) a point keeps its PCA_K normal. Face share min / max before ->
    after: wedge (seeds 0-9) 99.270 / 99.435 -> 99.575 / 99.660 %, plate 99.470 / 99.680
    -> 99.585 / 99.725 %, L-bracket (seeds 0-2) 99.415 / 99.520 -> 99.525 / 99.640 %."""
    for name, seeds in (("thin_wedge", range(10)), ("thin_plate", range(10)), ("thin_bracket", range(3))):
        faces = _face_shares(name, "auto", seeds)
        assert faces.min() >= 0.995, (name, faces)


def test_fold_fallback_is_the_same_when_the_noise_is_given():
    """A plan with the noise fixed (what tiles and cached stages pass) keeps the same
    normals at a thin rim's folded points as an estimate that measures the noise itself:
    the fallback is the 15-neighbour jet in both (it was the plain PCA with the noise given)."""
    s = shapes_thin.THIN_SHAPES["thin_wedge"](6000, seed=0)
    pts = shapes_thin.noisy(s, 0.2, 1)
    measured = core.estimate(pts)
    given = core.estimate(pts, plan=core.plan(len(pts), noise=measured.params["noise"]))
    np.testing.assert_array_equal(given.normals, measured.normals)
    np.testing.assert_array_equal(given.k1, measured.k1)
