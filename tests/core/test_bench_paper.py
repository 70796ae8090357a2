"""The paper benchmark (core.bench.paper) at --quick size: files, table columns, one ordering."""

import numpy as np
import pytest

from core.bench import paper
from core.bench._table import fmt, markdown_table, text_table

COLUMNS = ["QP", "QN", "CF", "CN", "CT", "NF", "NR"]


@pytest.fixture(scope="module")
def quick_out(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench_paper")
    code = paper.main(["--quick", "--out", str(out)])
    return code, out


def test_quick_run_writes_table_and_plots(quick_out, capsys):
    code, out = quick_out
    assert code == 0
    for surface in ("torus", "saddle"):
        for fig in ("fig2_4", "fig5"):
            png = out / f"paper_{fig}_{surface}.png"
            assert png.is_file() and png.stat().st_size > 10_000
            assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    md = (out / "paper.md").read_text(encoding="utf-8")
    header = "| σ/spacing | " + " | ".join(COLUMNS) + " |"
    assert md.count(header) == 6  # K, H, e1 on two surfaces
    assert paper.EXACT_ROW in md and "fraction of the mean point spacing" in md
    assert "## Reading of these numbers" in md and "NR is best at high noise" in md
    assert "paper_fig5_torus.png" in md


def test_stdout_tables(tmp_path, capsys):
    assert paper.main(["--quick", "--surface", "torus", "--out", str(tmp_path)]) == 0
    text = capsys.readouterr().out
    assert "mean absolute error of Gaussian curvature K" in text
    assert "principal direction e1" in text
    lines = [ln.split() for ln in text.splitlines()]
    assert ["σ/spacing", *COLUMNS] in lines
    assert not (tmp_path / "paper_fig5_saddle.png").exists()


def test_nr_beats_ct_on_H_at_highest_quick_noise():
    # NR/CT on H at 1000 points, sigma = 0.4 spacing: 0.33-0.44 over 25 seeds on each surface
    res = paper.run(**paper.QUICK, seed=3)
    for name, tab in res.tables.items():
        assert tab.levels == (0.0, 0.4)
        nr, ct = tab.value("mean", "nr"), tab.value("mean", "ct")
        assert np.isfinite(nr) and nr < ct, (name, nr, ct)


def test_run_shapes_and_validation():
    res = paper.run(points=400, levels=(0.1,), repeats=2, surfaces=("torus",), methods=("ct", "nr"))
    tab = res.tables["torus"]
    assert tab.mean["gaussian"].shape == (1, 2) and tab.exact_mean["direction_deg"].shape == (2,)
    assert np.all(tab.mean["mean"] > 0) and np.all(tab.invalid >= 0)
    with pytest.raises(ValueError):
        paper.run(levels=(-0.1,))
    with pytest.raises(ValueError):
        paper.run(surfaces=("klein",))
    with pytest.raises(SystemExit):
        paper.main(["--levels", "a,b"])


def test_table_helpers():
    assert fmt(0.012345) == "0.0123" and fmt(1234.5) == "1234" and fmt(float("nan")) == "nan"
    assert fmt(2.5e-7) == "2.50e-07"
    t = text_table(["a", "B"], [["x", "1.0"]], title="T").splitlines()
    assert t[0] == "T" and t[1].split() == ["a", "B"]
    assert markdown_table(["a", "B"], [["x", "1"]]).splitlines()[1] == "|:---|---:|"
