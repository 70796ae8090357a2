"""A narrow neighbour graph widened row by row (core.neighbours.WidenableNeighbours) gives
k="auto" exactly what a search of every point's k_search neighbours gives (issue 15, speed)."""

from __future__ import annotations

import weakref

import numpy as np
import pytest

from core import anchors, build_neighbours, estimate, noise, plan, scale, shapes, stages, wide_rows
from core.wide_neighbours import LazyNeighbours, WidenableNeighbours, search_in_spatial_order
from core.wide_rows import rows_at_least
from core.stage_cache import StageCache

FIELDS = ("normals", "k1", "k2", "e1", "e2", "valid", "k_point", "degree_point", "outlier_score", "crease",
          "orientation_confidence", "border")


def _same(a, b):
    for f in FIELDS:
        x, y = np.asarray(getattr(a, f)), np.asarray(getattr(b, f))
        assert np.array_equal(x, y, equal_nan=True), f
    assert a.params["passes_run"] == b.params["passes_run"]
    assert a.params["initial_k"] == b.params["initial_k"]


@pytest.fixture(scope="module")
def half_noisy():
    """A torus noise-free on one half and with noise of 0.3 spacing on the other."""
    pts = shapes.torus(6000, seed=3).points
    noisy = noise.add_noise(pts, 0.3, seed=4)
    return np.where((pts[:, 0] > 0)[:, None], noisy, pts)


@pytest.fixture(scope="module")
def quantised():
    """Ties at every distance (coordinates on a grid), and some exact duplicates."""
    pts = np.round(shapes.torus(3000, seed=5).points * 12) / 12
    return np.vstack([pts, pts[:40]])


@pytest.fixture(scope="module")
def full_width(half_noisy):
    """The estimate with every point's whole list searched up front (the old pipeline)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(stages, "SEARCH_WIDTH", 10**9)
        return estimate(half_noisy)


def test_rows_widened_equal_a_full_search(quantised):
    narrow, order = search_in_spatial_order(quantised, 120, width=24)
    full, order_full = search_in_spatial_order(quantised, 120)
    assert isinstance(narrow, WidenableNeighbours) and narrow.width == 24 and narrow.k_max == 120
    assert np.array_equal(order, order_full)
    rng = np.random.default_rng(0)
    centres = np.sort(rng.choice(len(quantised), 500, replace=False))
    for k in (24, 25, 57, 120):
        idx, dist = narrow.rows(centres, k)
        assert np.array_equal(idx, full.indices[centres, :k]) and np.array_equal(dist, full.distances[centres, :k])
    idx, dist = narrow.rows(centres[::-1].copy(), 120)  # any order of rows
    assert np.array_equal(idx, full.indices[centres[::-1], :])
    drop = rng.random(len(quantised)) < 0.6  # many rows short of unflagged among the 24 held
    for got, want in zip(narrow.take_without(20, drop), full.take_without(20, drop)):
        assert np.array_equal(got, want)
    assert narrow.width == 24  # none of that widened the graph
    assert narrow.mean_spacing() == full.mean_spacing()
    idx, dist = narrow.take(80)
    assert narrow.width == 80 and np.array_equal(idx, full.indices[:, :80])
    assert np.array_equal(narrow.indices, full.indices) and np.array_equal(narrow.distances, full.distances)


def test_half_noisy_cloud_is_bit_identical_to_a_full_search(half_noisy, full_width):
    res = estimate(half_noisy)
    _same(res, full_width)
    assert set(np.unique(res.k_point)) & {226}  # the noisy half grew past the columns held
    assert (res.k_point <= 40).mean() > 0.3  # and the clean half did not


@pytest.mark.parametrize("share", [0.0, 1.0])
def test_either_way_of_widening_gives_the_same(half_noisy, share, monkeypatch):
    """share 0: every point searched wide before the jet rule; 1: only the rows that reached
    the last sizes held, rerun (the jet rule looks one ring ahead). Where the scale is not
    shared (core.anchors.shares_scale; here forced off), every noisy point runs the rule."""
    monkeypatch.setattr(anchors, "ANCHOR_ROWS", 10**6)
    with monkeypatch.context() as mp:
        mp.setattr(stages, "SEARCH_WIDTH", 10**9)
        reference = estimate(half_noisy)
    monkeypatch.setattr(scale, "WIDEN_SHARE", share)
    _same(estimate(half_noisy), reference)


def test_truncated_jet_rule_reruns_the_points_at_its_last_sizes(half_noisy, full_width, monkeypatch):
    """Without the rerun the jets at the last sizes held would differ (fold_next is True
    at the last size): the width where the noise-free half stops must be checked."""
    monkeypatch.setattr(scale, "WIDEN_SHARE", 1.0)
    monkeypatch.setattr(stages, "SEARCH_WIDTH", 40)
    _same(estimate(half_noisy), full_width)


def test_result_neighbours_are_the_full_graph_and_pass_back(half_noisy, full_width):
    res = estimate(half_noisy)
    top = plan(len(half_noisy), k="auto").k_search
    assert res.neighbours.k_max == top
    full = build_neighbours(half_noisy, top)
    _same(estimate(half_noisy, neighbours=res.neighbours), full_width)
    assert np.array_equal(res.neighbours.indices, full.indices)
    assert np.array_equal(res.neighbours.distances, full.distances)
    _same(estimate(half_noisy, neighbours=full), full_width)


def test_lazy_result_neighbours_pass_back(monkeypatch):
    """A third of the torus noisy: the rows, not the graph, are widened, and the result's
    graph in the caller's order is made when read (also by an estimate it is passed to)."""
    pts = shapes.torus(6000, seed=3).points
    pts = np.where((pts[:, 0] > 1.2)[:, None], noise.add_noise(pts, 0.3, seed=4), pts)
    monkeypatch.setattr(scale, "WIDEN_SHARE", 1.0)
    res = estimate(pts)
    assert isinstance(res.neighbours, LazyNeighbours) and res.neighbours._made is None
    with monkeypatch.context() as mp:
        mp.setattr(stages, "SEARCH_WIDTH", 10**9)
        want = estimate(pts)
    _same(res, want)
    again = estimate(pts, neighbours=res.neighbours)
    _same(again, want)
    assert again.neighbours is res.neighbours and res.neighbours._made is None  # served without the whole graph
    idx, dist = res.neighbours.take(30)
    assert np.array_equal(idx, want.neighbours.indices[:, :30]) and np.array_equal(dist, want.neighbours.distances[:, :30])
    centres = np.arange(0, len(pts), 7)
    idx, dist = res.neighbours.rows(centres, 200)
    assert np.array_equal(idx, want.neighbours.indices[centres, :200])
    assert res.neighbours.mean_spacing() == want.neighbours.mean_spacing()
    assert res.neighbours._made is None
    assert np.array_equal(res.neighbours.indices, want.neighbours.indices)
    assert np.array_equal(res.neighbours.distances, want.neighbours.distances)


def test_stage_cache_auto_then_a_larger_k(half_noisy, full_width):
    cache = StageCache()
    _same(estimate(half_noisy, cache=cache), full_width)
    fresh = estimate(half_noisy, k=200)
    again = estimate(half_noisy, k=200, cache=cache)  # served by the auto graph, widened
    assert cache.reused["neighbours"] == 1
    _same(again, fresh)
    assert np.array_equal(again.neighbours.indices[:, :200], fresh.neighbours.indices)
    _same(estimate(half_noisy, cache=cache), full_width)  # and back


def test_stage_cache_head_room_for_an_integer_k(half_noisy):
    cache = StageCache(k_max=226)
    a = estimate(half_noisy, k=15, cache=cache)  # an integer k searches the whole head room
    _same(a, estimate(half_noisy, k=15))
    _same(estimate(half_noisy, k=113, cache=cache), estimate(half_noisy, k=113))
    assert cache.computed["neighbours"] == 1


def test_noise_free_cloud_searches_few_rows_wide(monkeypatch):
    pts = shapes.torus(6000, seed=0).points
    searched = []
    rows = WidenableNeighbours.rows

    def counting(self, centres, k):
        if k > self.width:
            searched.append(len(centres))
        return rows(self, centres, k)

    monkeypatch.setattr(WidenableNeighbours, "rows", counting)
    res = estimate(pts)
    assert isinstance(res.neighbours, LazyNeighbours) and res.neighbours._made is None
    # 7.4 % (446 rows) since the quiet points' quartic walks 20..113 where the cubic reached 20
    # (tuning.JET_DEGREES, 2026-12-07: tiny noise); 3 % before
    assert sum(searched) < 0.10 * len(pts)
    top = plan(len(pts), k="auto").k_search
    assert res.neighbours.k_max == top and res.neighbours.indices.shape == (len(pts), top)


def test_pickled_as_the_whole_graph(quantised):
    import pickle

    narrow, _ = search_in_spatial_order(quantised, 60, width=20)
    back = pickle.loads(pickle.dumps(narrow))
    assert type(back).__name__ == "Neighbours" and np.array_equal(back.indices, narrow.indices)
    res = estimate(shapes.torus(3000, seed=0).points)
    assert isinstance(res.neighbours, LazyNeighbours)
    back = pickle.loads(pickle.dumps(res))
    assert np.array_equal(back.neighbours.distances, res.neighbours.distances)


@pytest.mark.parametrize("cloud", ["cube", "tube"])
def test_folds_at_the_last_sizes_held(cloud, monkeypatch):
    """Rings that fold over (a cube's edges, a thin tube's far side) stop the jet rule at
    a size whose next ring is not held: the points that stopped at the next-to-last size
    held must be rerun too (the cube had 8 points wrong without it)."""
    from core import shapes_thin

    pts = shapes.cube(6000).points if cloud == "cube" else shapes_thin.thin_tube(6000).points
    monkeypatch.setattr(scale, "WIDEN_SHARE", 1.0)
    res = estimate(pts)
    monkeypatch.setattr(stages, "SEARCH_WIDTH", 10**9)
    _same(res, estimate(pts))


def test_one_point_s_neighbourhood_reads_one_row():
    """The viewer's pick and local_fit read one row; the lazy graph must not be made."""
    import core

    pts = shapes.torus(3000, seed=0).points
    res = estimate(pts)
    fit = core.local_fit(res, 7)
    assert res.neighbours._made is None
    assert np.array_equal(fit.neighbours, res.neighbours.indices[7, :res.k_point[7]])


def _memory_of(a):
    """The array that owns ``a``'s memory (a view keeps it alive, not ``a``)."""
    while isinstance(a.base, np.ndarray):
        a = a.base
    return a


@pytest.mark.parametrize("noise_level, share", [(1.0, 0.0), (0.3, 0.0)])
def test_a_widened_graph_frees_the_narrow_one(noise_level, share, monkeypatch):
    """No view of the narrow search outlives its widening (at 1M points with noise the two
    graphs side by side were 480 MB over the peak): widened in the initial normals (noise
    1 spacing) or in the jet rule (0.3), nothing holds the narrow arrays when the next
    stage starts."""
    import gc
    import importlib
    import weakref

    from core import wide_neighbours

    estimate_module = importlib.import_module("core.estimate")
    narrow, widen = [], wide_neighbours.WidenableNeighbours.widen

    def widen_and_watch(self, k=None, **kw):
        held = self._pair
        out = widen(self, k, **kw)
        if out is not held:
            narrow.extend(weakref.ref(_memory_of(a)) for a in held)
        return out

    def freed_before(fn):
        def run(*args, **kw):
            gc.collect()
            assert all(ref() is None for ref in narrow), f"the narrow graph is still held at {fn.__name__}"
            return fn(*args, **kw)
        return run

    monkeypatch.setattr(wide_neighbours.WidenableNeighbours, "widen", widen_and_watch)
    for module, name in ((estimate_module, "choose_scale"), (scale, "_jet_ici"), (estimate_module, "refine")):
        monkeypatch.setattr(module, name, freed_before(getattr(module, name)))
    monkeypatch.setattr(scale, "WIDEN_SHARE", share)
    estimate(noise.add_noise(shapes.torus(6000, seed=3).points, noise_level, seed=4))
    assert narrow  # the graph was widened


def test_rows_of_points_that_may_not_fit_are_searched_when_they_do(quantised):
    """k="auto"'s followers (core.anchors) read their anchors' fits: their wide rows are
    searched only if they fit after all (_Rows.ensure), the same rows and h as a full search."""
    narrow, _ = search_in_spatial_order(quantised, 120, width=24)
    full, _ = search_in_spatial_order(quantised, 120)
    n = len(quantised)
    kc = np.where(np.arange(n) % 3 == 0, 100, 20)
    fits = np.arange(n) % 4 != 1
    rows, h = rows_at_least(narrow, kc, fits)
    assert narrow.width == 24 and not isinstance(rows, np.ndarray)
    exact = fits | (kc <= 24)
    np.testing.assert_array_equal(h[exact], full.distances[exact, kc[exact] - 1])
    assert (h <= full.distances[np.arange(n), kc - 1]).all()  # the others: a lower bound until searched
    later = np.flatnonzero(~exact)
    first = rows.blocks[0][1]
    rows.ensure(later[::2][::-1], h)  # in any order
    assert rows.blocks[0][1] is first and len(rows.blocks) == 2  # a block of their own: the others not copied
    rows.ensure(later[::2], h)
    assert len(rows.blocks) == 2  # held already: not searched again
    now = exact.copy()
    now[later[::2]] = True
    np.testing.assert_array_equal(h[now], full.distances[now, kc[now] - 1])
    c = np.flatnonzero(now)
    got = rows[c]
    for i, row in zip(c, got):
        np.testing.assert_array_equal(row[:kc[i]], full.indices[i, :kc[i]])
    assert (rows[later[1::2]][:, 24:] == later[1::2, None]).all()  # not searched: the centre itself
    every = np.arange(n)
    parts = rows.parts(every)  # the fits read the rows in place: held, each block, and a copy for the rest
    in_place = [rows.held, *(block for _, block in rows.blocks)]
    assert len(parts) == 4 and all(a is b for (a, _, _), b in zip(parts, in_place))
    assert np.array_equal(np.sort(np.concatenate([at for _, _, at in parts])), every)
    for array, at_rows, at in parts:
        for i, r in zip(at, at_rows):
            want = full.indices[i, :kc[i]] if now[i] else rows[np.array([i])][0, :kc[i]]
            np.testing.assert_array_equal(array[r, :kc[i]], want)
    none, _ = rows_at_least(narrow, kc, np.zeros(n, dtype=bool))  # nothing searched yet: held, and copies
    assert len(none.blocks[0][0]) == 0 and [len(at) for _, _, at in none.parts(every)] == [(kc <= 24).sum(), (kc > 24).sum()]


def test_rows_kept_for_the_fits_are_not_searched_again(quantised, monkeypatch):
    """k="auto"'s jets search the wide rows of nearly the points whose fits read them
    (core.stages.choose_scale keeps them): rows_at_least searches only the others and gives
    the same rows and h as a full search; the graph hands them over (holds them no more)."""
    import core.wide_neighbours as wide

    narrow, _ = search_in_spatial_order(quantised, 120, width=24)
    full, _ = search_in_spatial_order(quantised, 120)
    n = len(quantised)
    kc = np.where(np.arange(n) % 3 == 0, 120, 20)
    fits = np.arange(n) % 4 != 1
    narrow.keep_rows(120)
    rng = np.random.default_rng(1)
    kept = [np.sort(rng.choice(n, 400, replace=False)), rng.permutation(n)[:300]]  # overlapping, any order
    for c in kept:
        narrow.rows(c, 120)
    narrow.rows(np.arange(50), 60)  # another width: not kept
    searched, copied = [], []
    real = wide.query_rows
    monkeypatch.setattr(wide, "query_rows", lambda p, t, r, c, *a: (searched.append(c.copy()), real(p, t, r, c, *a)))
    copy = wide_rows.copy_rows

    def copied_one_by_one(block, *args):  # each kept block is freed once copied (not all beside the new rows)
        assert all(ref() is None for ref in copied)
        copied.append(weakref.ref(block))
        return copy(block, *args)

    monkeypatch.setattr(wide_rows, "copy_rows", copied_one_by_one)
    rows, h = rows_at_least(narrow, kc, fits)
    assert len(copied) == 2
    need = np.flatnonzero(fits & (kc > 24))
    np.testing.assert_array_equal(np.sort(np.concatenate(searched)), np.setdiff1d(need, np.concatenate(kept)))
    np.testing.assert_array_equal(h[need], full.distances[need, kc[need] - 1])
    np.testing.assert_array_equal(rows[need], full.indices[need])
    assert narrow.kept_rows(120) == [] and narrow._kept is None  # handed over
    narrow.rows(need[:5], 120)
    assert narrow._kept is None  # and no longer kept


def test_rows_kept_at_any_width_past_the_fits_serve_them(quantised, monkeypatch):
    """The jets search rows at several widths (the degree rule's 113, the reruns' 320): every
    row kept at least as wide as the fits read serves them (its first k columns are a search's
    at k, bit for bit), once where kept at two widths; narrower ones are searched again."""
    import core.wide_neighbours as wide

    narrow, _ = search_in_spatial_order(quantised, 160, width=24)
    full, _ = search_in_spatial_order(quantised, 90)
    n = len(quantised)
    kc = np.where(np.arange(n) % 3 == 0, 90, 20)
    narrow.keep_rows(narrow.width + 1)
    rng = np.random.default_rng(2)
    at_90, at_160, at_60 = (rng.permutation(n)[:m] for m in (300, 200, 100))  # overlapping, any order
    for c, k in ((at_90, 90), (at_160, 160), (at_60, 60)):
        narrow.rows(c, k)
    searched = []
    real = wide.query_rows
    monkeypatch.setattr(wide, "query_rows", lambda p, t, r, c, *a: (searched.append(c.copy()), real(p, t, r, c, *a)))
    rows, h = rows_at_least(narrow, kc)
    need = np.flatnonzero(kc > 24)
    np.testing.assert_array_equal(np.sort(np.concatenate(searched)), np.setdiff1d(need, np.union1d(at_90, at_160)))
    np.testing.assert_array_equal(h[need], full.distances[need, kc[need] - 1])
    np.testing.assert_array_equal(rows[need], full.indices[need])
    assert narrow._kept is None


def test_a_graph_widened_where_its_rows_were_kept_reads_them(quantised, monkeypatch):
    """Where most points fit wide (tiny noise: the anchors' rows of 320 held nearly every point)
    the graph is widened whole: from the rows kept, their distances recomputed, and only the
    others searched; the same graph, bit for bit, as a search of every row."""
    import core.wide_neighbours as wide

    narrow, _ = search_in_spatial_order(quantised, 160, width=24)
    full, _ = search_in_spatial_order(quantised, 90)
    n = len(quantised)
    narrow.keep_rows(narrow.width + 1)
    every = np.random.default_rng(3).permutation(n)
    narrow.rows(every[: n // 2], 160)
    narrow.rows(every[n // 3: n - 50], 90)  # overlapping the first; 50 rows not kept
    searched, whole = [], []
    monkeypatch.setattr(wide, "_query_tree", lambda *a: whole.append(a))
    real = wide.query_rows
    monkeypatch.setattr(wide, "query_rows", lambda p, t, r, c, *a: (searched.append(c.copy()), real(p, t, r, c, *a)))
    rows, h = rows_at_least(narrow, np.full(n, 90))
    assert not whole and np.array_equal(np.sort(np.concatenate(searched)), np.sort(every[n - 50:]))
    assert narrow.width == 90
    np.testing.assert_array_equal(rows, full.indices)
    np.testing.assert_array_equal(h, full.distances[:, -1])
    np.testing.assert_array_equal(narrow.take(90)[1], full.distances)
