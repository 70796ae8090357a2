"""Invalid arguments raise ValueError naming the argument and the value; degenerate
geometry never crashes nor produces silent NaNs."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import shapes


@pytest.fixture(scope="module")
def small():
    return shapes.sphere(200, seed=1)


# ----------------------------------------------------------------------------- points


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda p: p[:, :2], r"points must have shape \(N, 3\), got shape \(200, 2\)"),
        (lambda p: p[:, 0], r"points must have shape \(N, 3\), got shape \(200,\)"),
        (lambda p: p[None], r"points must have shape \(N, 3\), got shape \(1, 200, 3\)"),
        (lambda p: np.zeros((0, 3)), r"points must hold at least 3 points, got 0"),
        (lambda p: p[:2], r"points must hold at least 3 points, got 2"),
        (lambda p: p.astype(object), r"points must be a numeric array.*dtype object"),
        (lambda p: [["a", "b", "c"]] * 20, r"points must be a numeric array.*dtype <U1"),
        (lambda p: p.astype(str), r"points must be a numeric array.*dtype <U"),
    ],
    ids=["N2", "1d", "3d", "empty", "two_points", "object", "strings", "numeric_strings"],
)
def test_bad_points(make, match, small):
    with pytest.raises(ValueError, match=match):
        core.estimate(make(small.points), k=15)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nonfinite_points_raise_then_drop(bad, small):
    p = small.points.copy()
    p[[7, 30]] = [[bad, 0, 0], [0, 0, bad]]
    with pytest.raises(ValueError, match=r"points contains 2 row\(s\) with NaN or inf \(first at row 7\)"):
        core.estimate(p, k=15)
    with pytest.raises(ValueError, match="drop_nonfinite=True"):
        core.estimate(p, k=15)
    r = core.estimate(p, k=15, drop_nonfinite=True)
    assert len(r) == 198 and r.params["dropped"] == 2 and r.params["n_points"] == 198
    keep = np.ones(200, bool)
    keep[[7, 30]] = False
    np.testing.assert_array_equal(r.points, small.points[keep])
    assert r.valid.all()
    # given normals are dropped with their points
    rn = core.estimate(p, small.normals, k=15, drop_nonfinite=True)
    np.testing.assert_allclose(rn.k1, core.estimate(small.points[keep], small.normals[keep], k=15).k1, rtol=1e-12)
    # normals of dropped rows may be garbage too
    bad_n = small.normals.copy()
    bad_n[[7, 30]] = np.nan
    np.testing.assert_allclose(core.estimate(p, bad_n, k=15, drop_nonfinite=True).k1, rn.k1, rtol=1e-12)


def test_drop_nonfinite_too_few_left():
    p = np.full((20, 3), np.nan)
    p[:2] = [[0, 0, 0], [1, 0, 0]]
    with pytest.raises(ValueError, match="at least 3 points, got 2"):
        core.estimate(p, k=15, drop_nonfinite=True)


def test_input_arrays_not_modified(small):
    p = small.points.copy()
    n = small.normals.copy()
    core.estimate(p, n, k=15, orientation="outward")
    np.testing.assert_array_equal(p, small.points)
    np.testing.assert_array_equal(n, small.normals)


def test_list_and_float32_input_accepted(small):
    a = core.estimate(small.points.tolist(), k=10)
    b = core.estimate(small.points.astype(np.float32), k=10)
    assert a.points.dtype == np.float64 and a.valid.all() and b.valid.all()
    np.testing.assert_allclose(b.k1, a.k1, rtol=1e-3, atol=1e-3)


# ----------------------------------------------------------------------------- k / method / options / passes


BAD_ARGUMENTS = [
    (dict(k=0), r"k=0 is out of range; allowed: in \[4, 200\]"),
    (dict(k=-5), r"k=-5 is out of range"),
    (dict(k=201), r"k=201 is out of range; allowed: in \[4, 200\]"),
    (dict(k=2.5), r"k must be an integer, got 2.5"),
    (dict(k=15.0), r"k must be an integer, got 15.0"),
    (dict(k=True), r"k must be an integer, got True"),
    (dict(k="15"), r"k must be an integer.*got '15'"),
    (dict(k=None), r"k must be an integer, got None"),
    (dict(method="foo"), r"method 'foo' is unknown; valid methods are: nr, nf, ct, qp, qn, cf, cn, jet"),
    (dict(method=None), r"method None is unknown; valid methods are: .*nr.*jet"),
    (dict(options={"bogus": 1}),
     r"option\(s\) \['bogus'\] do not apply to method 'nr'; its options are: .*constraint.*weights"),
    (dict(method="ct", options={"weights": "theta"}),
     r"option\(s\) \['weights'\] do not apply to method 'ct'; its options are: none"),
    (dict(method="jet", options={"constraint": "none"}),
     r"\['constraint'\] do not apply to method 'jet'; its options are: degree"),
    (dict(options={"weights": "gauss"}), r"weights 'gauss' is invalid; must be one of \['uniform', 'theta'\]"),
    (dict(options={"constraint": "strict"}), r"constraint 'strict' is invalid"),
    (dict(method="jet", options={"degree": 4}), r"degree 4 is invalid; must be 2 or 3"),
    (dict(passes=-1), r"passes=-1 is out of range; allowed: in \[0, 20\]"),
    (dict(passes=1.5), r"passes must be an integer, got 1.5"),
    (dict(passes=21), r"passes=21 is out of range"),
    (dict(orientation="inward"),
     r"orientation 'inward' is invalid; must be one of \['auto', 'propagate', 'outward', 'keep'\], a \(3,\) "
     r"viewpoint or an \(N, 3\) array of one viewpoint per point"),
    (dict(orientation=[0, 0]), r"orientation as a viewpoint must be 3 finite numbers, got \[0, 0\]"),
    (dict(orientation=[0, 0, 0, 1]),
     r"orientation as a viewpoint must be 3 finite numbers, got \[0, 0, 0, 1\]"),
    (dict(orientation=(0, np.nan, 1)), r"orientation as a viewpoint must be 3 finite numbers"),
    (dict(progress=5), r"progress must be callable or None, got 5"),
    (dict(progress="yes"), r"progress must be callable or None, got 'yes'"),
    (dict(k=2), r"k=2 is out of range; allowed: in \[4, 200\]"),
    (dict(tol=-1), r"tol must be a positive number of degrees or None, got -1"),
    (dict(initial="bogus"), r"initial 'bogus' is invalid; must be one of \['auto', 'pca', 'jet'\]"),
    (dict(neighbours="x"), r"neighbours must be a core.Neighbours, got str"),
    (dict(plan=5), r"plan must be a core.EstimatePlan \(from core.plan\) or None, got int"),
    (dict(cache="x"), r"cache must be a core.stage_cache.StageCache or None, got str"),
]
_IDS = dict(ids=lambda x: repr(x) if isinstance(x, dict) else None)


@pytest.mark.parametrize("kw, match", BAD_ARGUMENTS, **_IDS)
def test_bad_arguments(kw, match, small):
    with pytest.raises(ValueError, match=match):
        core.estimate(small.points, **{"k": 15, **kw})


def _flat_clouds():
    """Clouds of 200 points (as ``small``) that no fit can be made on."""
    t = np.linspace(0.0, 1.0, 200)
    return {"line": np.outer(t, [1.0, 2.0, 3.0]) + [0.5, -1, 2], "identical": np.full((200, 3), 7.25),
            "two_places": np.repeat([[0.0, 0, 0], [1.0, 1, 1]], 100, axis=0)}


FLAT = _flat_clouds()


@pytest.mark.parametrize("cloud", list(FLAT))
@pytest.mark.parametrize("kw, match", BAD_ARGUMENTS, **_IDS)
def test_bad_arguments_refused_alike_on_degenerate_clouds(cloud, kw, match):
    """A degenerate cloud's all-invalid result used to be returned before the arguments
    were checked: passes=-1, k=201 > N, orientation="inward" ... were accepted, plan=5 an
    AttributeError. The same checks (and messages) run on every cloud."""
    with pytest.raises(ValueError, match=match):
        core.estimate(FLAT[cloud], **{"k": 15, **kw})


@pytest.mark.parametrize("kw, match", [(kw, m) for kw, m in BAD_ARGUMENTS if "k" not in kw], **_IDS)
def test_bad_arguments_refused_on_too_few_points(kw, match, small):
    """Fewer points than a fit needs leave k no allowed value: any k >= 1 gives the
    all-invalid result (test_degenerate), but every other argument is checked."""
    with pytest.raises(ValueError, match=match):
        core.estimate(small.points[:3], **{"k": 15, **kw})


def test_k_on_too_few_points_is_an_integer_from_1(small):
    with pytest.raises(ValueError, match=r"k=0 is out of range; allowed: >= 1"):
        core.estimate(small.points[:3], k=0)
    with pytest.raises(ValueError, match=r"k must be an integer, got 2.5"):
        core.estimate(small.points[:3], k=2.5)
    for k in (1, 3, 15):
        res = core.estimate(small.points[:3], k=k)
        assert not res.valid.any() and res.k == k and "fewer than" in res.params["degenerate"]


def test_k_beyond_the_points_refused_on_a_line_as_on_a_surface():
    for pts in (FLAT["line"], shapes.sphere(200, seed=1).points):
        with pytest.raises(ValueError, match=r"k=1000 is out of range; allowed: in \[4, 200\]"):
            core.estimate(pts, k=1000)


def test_fewer_points_than_k():
    p = shapes.sphere(10, seed=0).points
    with pytest.raises(ValueError, match=r"k=15 is out of range; allowed: in \[4, 10\]"):
        core.estimate(p, k=15)
    assert core.estimate(p, k=10).k == 10  # k == N is allowed


def test_method_names_case_insensitive(small):
    assert core.estimate(small.points, k=15, method="NF").method == "nf"


def test_validation_happens_before_the_search(small):
    """Bad arguments fail fast: the progress callback never runs."""
    calls = []
    with pytest.raises(ValueError):
        core.estimate(small.points, k=0, progress=lambda f, s: calls.append(f))
    with pytest.raises(ValueError):
        core.estimate(small.points, k=15, orientation="x", progress=lambda f, s: calls.append(f))
    assert calls == []


# ----------------------------------------------------------------------------- normals


BAD_NORMALS = [
    (lambda n: n[:-1], r"normals must have shape \(200, 3\) to match points, got shape \(199, 3\)"),
    (lambda n: n[:, :2], r"normals must have shape \(200, 3\) to match points, got shape \(200, 2\)"),
    (lambda n: n[:, 0], r"normals must have shape \(200, 3\) to match points, got shape \(200,\)"),
    (lambda n: n.astype(object), r"normals must be a numeric array.*dtype object"),
    (lambda n: n.astype(str), r"normals must be a numeric array.*dtype <U"),
]
BAD_NORMAL_IDS = ["short", "N2", "1d", "object", "strings"]


@pytest.mark.parametrize("make, match", BAD_NORMALS, ids=BAD_NORMAL_IDS)
def test_bad_normals(make, match, small):
    with pytest.raises(ValueError, match=match):
        core.estimate(small.points, make(small.normals), k=15)


@pytest.mark.parametrize("bad", [[0.0, 0, 0], [np.nan, 0, 1], [np.inf, 0, 0]], ids=["zero", "nan", "inf"])
def test_unusable_file_normals_repaired_not_refused(bad, small):
    """Issue 12: a scan's zero / NaN normals are estimated per row, not a reason to refuse
    the file (the message used to be "pass normals=None")."""
    given = small.normals.copy()
    given[[0, 5, 6]] = bad
    r = core.estimate(small.points, given, k=15)
    assert r.params["normals_repaired"] == {"unusable": 3, "renormalised": 0, "estimated": 3}
    assert np.all(np.einsum("ij,ij->i", r.normals[[0, 5, 6]], small.normals[[0, 5, 6]]) > 0.99)
    np.testing.assert_array_equal(given[[0, 5, 6]], [bad] * 3)  # the caller's array untouched


@pytest.mark.parametrize("cloud", list(FLAT))
@pytest.mark.parametrize("make, match", BAD_NORMALS, ids=BAD_NORMAL_IDS)
def test_bad_normals_refused_alike_on_degenerate_clouds(cloud, make, match, small):
    """Normals of the wrong length were an IndexError on a degenerate cloud."""
    with pytest.raises(ValueError, match=match):
        core.estimate(FLAT[cloud], make(small.normals), k=15)
    with pytest.raises(ValueError, match=match):
        core.estimate(FLAT[cloud], make(small.normals), k=15, drop_nonfinite=True)


@pytest.mark.parametrize("cloud", list(FLAT))
def test_unusable_normals_not_refused_on_degenerate_clouds(cloud):
    """A NaN or zero row was refused on a degenerate cloud but repaired on any other: here
    it is kept as NaN (no neighbourhood can estimate it), the others unit length."""
    given = np.tile([0.0, 0.0, 2.0], (200, 1))
    given[[0, 5, 6]] = [[np.nan, 0, 1], [0.0, 0, 0], [np.inf, 0, 0]]
    r = core.estimate(FLAT[cloud], given, k=15)
    assert not r.valid.any() and r.params["degenerate"]
    assert np.isnan(r.normals[[0, 5, 6]]).all()
    np.testing.assert_array_equal(np.delete(r.normals, [0, 5, 6], axis=0), np.tile([0.0, 0, 1], (197, 1)))
    assert r.params["normals_repaired"] == {"unusable": 3, "renormalised": 197, "estimated": 0}


def test_neighbours_checked_on_degenerate_clouds():
    """A given graph is checked as on a cloud that is estimated (and then not used)."""
    line = FLAT["line"]
    with pytest.raises(ValueError, match=r"neighbours were built with k_max=10 < k=15"):
        core.estimate(line, k=15, neighbours=core.build_neighbours(line, 10))
    with pytest.raises(ValueError, match="neighbours were built on different points"):
        core.estimate(line, k=15, neighbours=core.build_neighbours(line + 1.0, 15))
    assert not core.estimate(line, k=15, neighbours=core.build_neighbours(line, 15)).valid.any()


def test_neighbours_type_checked_on_a_cloud_of_copies(small):
    """A cloud with copies of points ignores a given graph (searched on the copies); a
    graph that is no core.Neighbours was accepted silently there."""
    with pytest.raises(ValueError, match=r"neighbours must be a core.Neighbours, got str"):
        core.estimate(np.vstack([small.points, small.points[:5]]), k=15, neighbours="x")


def test_unnormalised_normals_are_normalised(small):
    a = core.estimate(small.points, small.normals, k=10)
    b = core.estimate(small.points, small.normals * np.linspace(0.1, 10, 200)[:, None], k=10)
    np.testing.assert_allclose(b.k1, a.k1, rtol=1e-12)


def test_bad_normals_with_drop_nonfinite(small):
    with pytest.raises(ValueError, match=r"normals must have shape \(200, 3\)"):
        core.estimate(small.points, small.normals[:-1], k=15, drop_nonfinite=True)


def test_complex_points_rejected(small):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ValueError, match="points"):
            core.estimate(small.points + 1j, k=15)


# ----------------------------------------------------------------------------- build_neighbours


@pytest.mark.parametrize(
    "k_max, match",
    [(0, r"k_max=0 is out of range; allowed: in \[1, 200\]"), (201, r"k_max=201 is out of range"),
     (True, r"k_max must be an integer, got True"), (3.0, r"k_max must be an integer, got 3.0")],
)
def test_build_neighbours_bad_k(k_max, match, small):
    with pytest.raises(ValueError, match=match):
        core.build_neighbours(small.points, k_max)


def test_build_neighbours_bad_points():
    with pytest.raises(ValueError, match=r"points must have shape \(N, 3\)"):
        core.build_neighbours(np.zeros((10, 2)), 3)
    with pytest.raises(ValueError, match="NaN or inf"):
        core.build_neighbours(np.array([[0, 0, 0], [1, np.nan, 0], [0, 1, 0.0]]), 2)


# ----------------------------------------------------------------------------- degenerate geometry


def _degenerate_clouds():
    s = shapes.sphere(2000, seed=1)
    rng = np.random.default_rng(0)
    t = rng.random(500)
    rot = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    plane = shapes.plane(1000, seed=3).points
    return {
        "duplicates_on_surface": (np.vstack([s.points, np.repeat(s.points[:1], 50, axis=0)]), None),
        "duplicates_with_normals": (
            np.vstack([s.points, np.repeat(s.points[:1], 50, axis=0)]),
            np.vstack([s.normals, np.repeat(s.normals[:1], 50, axis=0)]),
        ),
        "duplicates_inside": (np.vstack([s.points, np.zeros((50, 3))]), None),
        "collinear": (np.outer(t, [1.0, 2.0, 3.0]) + [0.5, -1, 2], None),
        "collinear_with_normals": (np.outer(t, [1.0, 2.0, 3.0]), np.tile([3.0, 0, -1.0], (500, 1))),
        "coplanar_tilted": (plane @ rot.T + 5.0, None),
        "tight_cluster_1e-6": (np.vstack([s.points, s.points[0] + 1e-6 * rng.normal(size=(40, 3))]), None),
        "tight_cluster_1e-12": (np.vstack([s.points, s.points[0] + 1e-12 * rng.normal(size=(40, 3))]), None),
        "tight_cluster_1e-300": (np.vstack([s.points, s.points[0] + 1e-300 * rng.normal(size=(40, 3))]), None),
    }


DEGENERATE = _degenerate_clouds()
CLEAN = shapes.sphere(2000, seed=1)


@pytest.mark.parametrize("method", list(core.METHODS))
@pytest.mark.parametrize("name", list(DEGENERATE))
def test_degenerate_clouds_never_crash_nor_leak_nan(name, method, helpers):
    pts, nrm = DEGENERATE[name]
    r = core.estimate(pts, nrm, k=15, method=method)
    helpers.check_result_invariants(r)
    if name.startswith("collinear"):
        assert r.n_invalid == len(pts)  # a line has no normal and no curvature
        return
    if name == "coplanar_tilted":
        assert r.valid.all()
        assert np.abs(r.k1).max() < 1e-9 and np.abs(r.k2).max() < 1e-9
        return
    if name.startswith("duplicates"):  # estimated once, at their position (core.duplicates); were invalid
        assert r.params["duplicates"] == (49 if name == "duplicates_inside" else 50)
        first = 2000 if name == "duplicates_inside" else 0
        for rows in (r.k1, r.valid, r.normals):
            np.testing.assert_array_equal(rows[2000:], np.repeat(rows[first:first + 1], 50, axis=0))
    assert r.valid[1:2000].mean() > 0.995
    # away from the defect the sphere's answer is exactly the defect-free one
    clean = core.estimate(CLEAN.points, None if nrm is None else CLEAN.normals, k=15, method=method)
    # (a defect reaches ~0.35 through the PCA normals and NF, ~0.55 after an NR pass)
    far = np.linalg.norm(CLEAN.points - CLEAN.points[0], axis=1) > 0.8
    assert far.sum() > 1500
    np.testing.assert_allclose(r.k1[:2000][far], clean.k1[far], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(r.k2[:2000][far], clean.k2[far], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(r.normals[:2000][far], clean.normals[far], atol=1e-9)
