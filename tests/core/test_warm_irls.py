"""k="auto"'s refinement passes start their robust fit from the weights the same centre's
fit ended with in the pass before (core.kernels.Memo, core.tuning.IRLS_WARM)."""

import numpy as np
import pytest

import core
from core import kernels
from core.methods import get_method
from core.patch import Chunk
from core.tuning import IRLS_WARM


def _chunk(nrm=None):
    """A noisy ellipsoid whose normals are 5 % turned sideways (gross residuals), 80 neighbours."""
    s = core.shapes.ellipsoid(2000, seed=5)
    p = core.noise.add_noise(s.points, 0.2, seed=6)
    nrm = s.normals.copy() if nrm is None else nrm
    bad = np.random.default_rng(7).random(len(p)) < 0.05
    nrm[bad] = np.cross(nrm[bad], [0.0, 0.0, 1.0]) + 0.3 * nrm[bad]
    nrm[bad] /= np.linalg.norm(nrm[bad], axis=1, keepdims=True)
    idx, dist = core.build_neighbours(p, 80).take(80)
    centres = np.arange(0, 200)
    return Chunk.build(p, nrm, idx, dist[centres, -1], centres, rows=centres), bad, idx


def _fit(chunk, memo=None):
    return get_method("nf").fit(chunk, degree=3, robust="tukey", memo=memo)


def test_a_fit_leaves_its_final_weights_and_a_warm_start_keeps_them():
    chunk, bad, idx = _chunk()
    n = len(chunk.points)
    memo = kernels.Memo(np.zeros((n, 80), dtype=np.uint8), np.zeros(n, dtype=bool), 0, 1, IRLS_WARM)
    cold = _fit(chunk, memo)
    assert memo.has[chunk.centres].all() and not memo.has[200:].any()
    w = memo.wt[chunk.centres] / 255.0
    outlying = bad[idx[chunk.centres]]
    assert w[outlying].mean() < 0.1 < 0.8 < w[~outlying].mean()  # the turned normals were weighted down
    warm = _fit(chunk, memo._replace(read=1))
    # the same data: a warm start with one reweighting lands where the cold fit's two did
    np.testing.assert_allclose(warm.mu, cold.mu, atol=1e-3)  # 0.06 degrees of normal
    np.testing.assert_allclose(warm.W, cold.W, rtol=1e-2, atol=3e-3)


def test_no_memo_is_the_plain_fit():
    chunk, _, _ = _chunk()
    a, b = _fit(chunk), _fit(chunk, kernels.no_memo())
    assert np.array_equal(a.mu, b.mu) and np.array_equal(a.W, b.W)


def test_only_auto_passes_keep_weights():
    """k="auto" (robust) fits with a memo, written by the first fit and read by the passes; k = 15 without."""
    from core.refinement import _fitters
    from core.stages import _Fitter

    n = 100
    for k, kept in ((15, False), ("auto", True)):
        plan = core.plan(10_000, k=k)
        f = _Fitter(np.zeros((n, 3)), np.zeros((n, 20), dtype=np.int32), np.full(n, 20), np.ones(n), plan.method,
                    dict(plan.options))
        first, later = _fitters(f, plan)
        if not kept:
            assert "memo" not in first.options and "memo" not in later.options
            continue
        a, b = first.options["memo"], later.options["memo"]
        assert (a.read, a.write, b.read, b.write, b.rounds) == (0, 1, 1, 1, IRLS_WARM)
        assert a.wt is b.wt and a.has is b.has and a.wt.shape == (n, 20)
