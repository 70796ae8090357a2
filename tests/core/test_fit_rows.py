"""The NF kernel reads each centre's neighbours in place, by its row of the whole graph
(``Chunk.rows``), with the same numbers as on a copy of the chunk's rows (the copy was 0.58 of
17.4 CPU s of a noisy 100k k="auto" estimate)."""

import numpy as np
import pytest

import core
from core.methods import get_method
from core.patch import Chunk
from core.fits import Fitter


def _cloud():
    s = core.shapes.ellipsoid(2000, seed=5)
    p = core.noise.add_noise(s.points, 0.2, seed=6)
    idx, dist = core.build_neighbours(p, 60).take(60)
    return p, s.normals, np.ascontiguousarray(idx), dist


@pytest.mark.parametrize("opts", [{}, {"degree": 3, "robust": "tukey"}, {"degree": 2, "robust": "huber",
                                                                         "weights": "theta"}])
def test_rows_in_place_are_the_copy_bit_for_bit(opts):
    p, nrm, idx, dist = _cloud()
    centres = np.array([1999, 5, 3, 900, 17, 1200, 4, 640])  # scattered, unsorted
    kc = np.array([60, 40, 60, 25, 60, 33, 60, 60])
    copied = Chunk.build(p, nrm, idx[centres], dist[centres, -1], centres, kc)
    in_place = Chunk.build(p, nrm, idx, dist[centres, -1], centres, kc, rows=centres)
    a, b = (get_method("nf").fit(c, **opts) for c in (copied, in_place))
    for x, y in zip(a[:3], b[:3]):
        assert np.array_equal(x, y)
    assert np.array_equal(in_place.row_idx, copied.idx)
    assert np.array_equal(in_place.patch.u, copied.patch.u)  # the numpy methods see the same rows


def test_the_fitter_reads_a_contiguous_graph_in_place():
    p, nrm, idx, dist = _cloud()
    n = len(p)
    fitter = Fitter(p, idx, np.full(n, 60), dist[:, -1], get_method("nr"), {})
    c = np.arange(10, 20)
    [chunk] = fitter._chunks(nrm, c, True)
    assert chunk.idx is idx and np.array_equal(chunk.rows, c)
    assert fitter._chunks(nrm, c, False)[0].rows is None
    assert fitter._chunks(nrm, c[:0], True) == []


@pytest.mark.parametrize("rows", [20, 25])
def test_thinned_rows_are_the_fit_of_every_stride_th_neighbour(rows):
    """``rows`` (k="auto"'s refinement passes, core.tuning.ROWS_LATER): a centre of k >= 2 x rows
    neighbours fits every (k // rows)-th of them by distance, the same numbers as a fit of those."""
    p, nrm, idx, dist = _cloud()
    centres = np.array([7, 1500, 33, 800])
    kc = np.array([60, 41, 30, 39])  # strides 3, 2, 1, 1 at rows=20; 2, 1, 1, 1 at rows=25
    opts = {"degree": 3, "robust": "tukey"}
    h = dist[centres, -1]
    thinned = get_method("nf").fit(Chunk.build(p, nrm, idx[centres], h, centres, kc), **opts, rows=rows)
    for r, (c, k) in enumerate(zip(centres, kc)):
        stride = max(1, k // rows)
        cols = idx[c, :k:stride][None]
        one = get_method("nf").fit(Chunk.build(p, nrm, np.ascontiguousarray(cols), h[r:r + 1], c[None],
                                               np.array([cols.shape[1]])), **opts)
        for x, y in zip(thinned[:2], one[:2]):
            assert np.allclose(x[r], y[0], rtol=0, atol=1e-12)
    full = get_method("nf").fit(Chunk.build(p, nrm, idx[centres], h, centres, kc), **opts)
    for r, k in enumerate(kc):  # a centre is thinned only where it has 2 x rows neighbours
        assert np.array_equal(full.W[r], thinned.W[r]) == (k < 2 * rows)


@pytest.mark.parametrize("weights", ["uniform", "theta"])
@pytest.mark.parametrize("constraint", ["none", "project", "exact"])
def test_the_direct_linear_fit_is_the_scratch_path(weights, constraint):
    """The paper's linear fit without reweighting sums straight from the neighbours
    (``nf._fit_linear``); a robust fit with no reweighting takes the scratch path of every other
    fit. Both solve the same least squares: the same numbers to rounding, on thinned rows and
    with neighbours that have no normal (weight 0)."""
    p, nrm, idx, dist = _cloud()
    nrm = nrm.copy()
    nrm[::9] = np.nan
    centres = np.arange(0, 2000, 7)
    kc = np.where(centres % 2 == 0, 60, 31)
    opts = {"weights": weights, "constraint": constraint, "coefficients": True}
    chunk = Chunk.build(p, nrm, idx, dist[centres, -1], centres, kc, rows=centres)
    for rows in (0, 20):
        direct = get_method("nf").fit(chunk, **opts, rows=rows)
        scratch = get_method("nf").fit(chunk, **opts, rows=rows, robust="huber", reweightings=0)
        ok = direct.ok
        assert np.array_equal(ok, scratch.ok) and ok.mean() > 0.8  # centres without a normal have no frame
        np.testing.assert_allclose(direct.mu[ok], scratch.mu[ok], rtol=0, atol=1e-12)
        np.testing.assert_allclose(direct.W[ok], scratch.W[ok], rtol=0, atol=1e-10)
        for key in ("var", "rms", "spread", "coef"):
            np.testing.assert_allclose(direct.diag[key][ok], scratch.diag[key][ok], rtol=1e-9, atol=1e-14,
                                       err_msg=key)
