"""The accuracy race (core.bench.accuracy, issue 4) at --quick size, and the APSS wrapper.

pymeshlab is optional: everything but the APSS-specific tests runs without it.
"""

import builtins
import sys

import numpy as np
import pytest

from core import metrics, shapes
from core.bench import accuracy, apss


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    """One --quick run (APSS included when pymeshlab is installed): exit code, out dir, stdout."""
    out = tmp_path_factory.mktemp("bench_accuracy")
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = accuracy.main(["--quick", "--shapes", "torus,saddle", "--out", str(out)])
    return code, out, buf.getvalue()


def test_quick_run_writes_markdown_and_plots(quick_run):
    code, out, _ = quick_run
    assert code == 0
    for shape in ("torus", "saddle"):
        png = out / f"accuracy_{shape}.png"
        assert png.is_file() and png.stat().st_size > 10_000
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not (out / "accuracy_ellipsoid.png").exists()
    md = (out / "accuracy.md").read_text(encoding="utf-8")
    assert "## Reading" in md and "## Targets of issue 4" in md
    assert md.count("mean absolute error**") == 6  # K, H, e1 on two shapes
    assert "NR k=15" in md and "NR best k" in md and "jet3 best k" in md
    assert "## Robustness: outliers" in md and "## NR options" in md
    assert "accuracy_torus.png" in md
    if apss.available():
        assert "APSS best" in md and "k1 + k2 = 2H" in md
    else:
        assert "APSS skipped" in md and "pip install pymeshlab" in md


def test_stdout_tables(quick_run):
    _, _, text = quick_run
    assert "mean absolute error of Gaussian curvature K" in text
    assert "principal direction e1" in text
    assert "Robustness: 3% outliers" in text and "NR options on the torus, k=15" in text
    header = [ln.split() for ln in text.splitlines() if ln.startswith("σ/spacing") and "NR" in ln][0]
    assert header[:3] == ["σ/spacing", "NR", "k=15"]


def test_runs_and_skips_apss_without_pymeshlab(tmp_path, monkeypatch, capsys):
    """Hide pymeshlab: the bench must still run, say so, and drop the APSS column."""
    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name == "pymeshlab" or name.startswith("pymeshlab."):
            raise ImportError("No module named 'pymeshlab' (hidden by the test)")
        return real_import(name, *args, **kwargs)

    monkeypatch.delitem(sys.modules, "pymeshlab", raising=False)
    monkeypatch.setattr(builtins, "__import__", fake_import)
    assert not apss.available()
    with pytest.raises(apss.ApssUnavailable, match="pip install pymeshlab"):
        apss.apss_curvature(np.zeros((5, 3)), np.tile([0.0, 0.0, 1.0], (5, 1)))
    res = accuracy.run(points=600, levels=(0.1,), seeds=1, shapes_=("torus",), k_grid=(15, 30), evaluate=300,
                       options_shapes=(), robust_levels=())
    tab = res.tables["torus"]
    assert accuracy.APSS not in tab.columns and accuracy.NR15 in tab.columns
    assert any("pymeshlab is not installed" in n for n in res.notes)
    assert np.isfinite(tab.value(accuracy.NR15, "mean", 0.1))


def test_oracle_picks_the_smallest_error_and_nr_beats_k15_at_its_best():
    res = accuracy.run(points=800, levels=(0.2,), seeds=1, shapes_=("torus",), k_grid=(15, 30, 45), evaluate=500,
                       use_apss=False, options_shapes=(), robust_levels=())
    tab = res.tables["torus"]
    for q, _, _ in accuracy.QUANTITIES:
        sweep = tab.sweeps[accuracy.NRBEST][0]
        assert tab.err[accuracy.NRBEST][q][0] == min(e[q] for e in sweep.values())
        # the grid includes k=15 with the same points and neighbours: the oracle can only be better
        assert tab.err[accuracy.NRBEST][q][0] <= tab.err[accuracy.NR15][q][0] + 1e-12
    assert tab.ref[accuracy.NFE]["mean"] < tab.err[accuracy.NR15]["mean"][0]


def test_sweep_stops_after_two_worse_candidates():
    errs = {1: 3.0, 2: 2.0, 3: 2.5, 4: 2.6, 5: 0.1}
    seen = []

    def f(c):
        seen.append(c)
        return {q: errs[c] for q, _, _ in accuracy.QUANTITIES}

    out = accuracy._sweep([1, 2, 3, 4, 5], f)
    assert seen == [1, 2, 3, 4] and list(out) == [1, 2, 3, 4]


def test_argument_validation(capsys):
    with pytest.raises(SystemExit):
        accuracy.main(["--levels", "0,-1"])
    with pytest.raises(SystemExit):
        accuracy.main(["--shapes", "cube"])
    with pytest.raises(ValueError):
        accuracy.run(levels=(0.1,), seeds=0)


# ----------------------------------------------------------------------------- APSS (pymeshlab)
def test_apss_conventions_on_sphere_and_torus():
    """Sign: k = +1/R on an outward sphere (and no crash on an exact sphere); Mean = 2H is
    halved; PD1/PD2 paired right on both sides of H = 0; errors reuse core.metrics."""
    pytest.importorskip("pymeshlab")
    s = shapes.sphere(1500, radius=2.0, seed=4)
    r = apss.apss_curvature(s.points, s.normals, scale=4.0)
    assert r.valid.all()
    np.testing.assert_allclose(np.median(r.k1), 0.5, atol=1e-3)
    np.testing.assert_allclose(np.median(r.mean), 0.5, atol=1e-3)
    r_in = apss.apss_curvature(s.points, -s.normals, scale=4.0)
    np.testing.assert_allclose(np.median(r_in.mean), -0.5, atol=1e-3)
    assert metrics.summary(r_in, s)["mean"] < 1e-3  # aligned() undoes the flipped normals

    tor = shapes.torus(4000, R=1.5, r=1.0, seed=5)
    ev = np.zeros(len(tor.points), dtype=bool)
    ev[::2] = True
    r = apss.apss_curvature(tor.points, tor.normals, scale=6.0, evaluate=ev)
    assert (r.valid == ev).all() and np.isnan(r.k1[~ev]).all()
    assert (r.k1[ev] >= r.k2[ev]).all()
    pe = metrics.point_errors(r, tor)
    for side in (tor.mean > 0.1, tor.mean < -0.1):
        d = pe["direction_deg"][side & ev]
        assert np.nanmedian(d) < 10, "PD1/PD2 paired the wrong way"
    m = metrics.summary(r, tor, mask=ev)
    assert m["mean"] < 0.05 and m["gaussian"] < 0.05 and m["invalid_fraction"] == 0


def test_apss_input_validation():
    pytest.importorskip("pymeshlab")
    pts = shapes.sphere(200, seed=0).points
    with pytest.raises(ValueError):
        apss.apss_curvature(pts, pts[:10])
    with pytest.raises(ValueError):
        apss.apss_curvature(pts, pts, scale=0)
