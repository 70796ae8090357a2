"""The before/after comparison of core.bench.perf_identity must pass equal snapshots and
catch any flag change, any moved NaN and any float difference of 1e-12 or more."""

from __future__ import annotations

import numpy as np

from core.bench.perf_identity import compare


def _save(path, **arrays):
    np.savez(path, **arrays)
    return str(path)


def test_identity_check_passes_equal_and_tiny_differences_and_catches_the_rest(tmp_path):
    k1 = np.array([1.0, np.nan, -2.5])
    base = dict(k1=k1, k_point=np.array([15, 20, 226]), valid=np.array([True, False, True]))
    a = _save(tmp_path / "a.npz", **base)
    lines = []
    assert compare(a, _save(tmp_path / "same.npz", **base), out=lines.append) == 0
    assert compare(a, _save(tmp_path / "tiny.npz", **{**base, "k1": k1 + 1e-15}), out=lines.append) == 0
    assert "within 1e-12" in lines[-2]
    assert compare(a, _save(tmp_path / "far.npz", **{**base, "k1": k1 + 1e-9}), out=lines.append) == 1
    assert compare(a, _save(tmp_path / "nan.npz", **{**base, "k1": np.array([1.0, 0.0, -2.5])}), out=lines.append) == 1
    assert compare(a, _save(tmp_path / "k.npz", **{**base, "k_point": np.array([15, 20, 160])}), out=lines.append) == 1
    assert compare(a, _save(tmp_path / "missing.npz", k1=k1), out=lines.append) == 1
