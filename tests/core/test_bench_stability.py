"""``python -m core bench stability`` measures what it says."""

from __future__ import annotations

import numpy as np

from core import shapes
from core.bench import stability
from core.cli import main


def test_measure_sphere_known_answers():
    """On a clean sphere H is 1/R everywhere: resampling and noise barely move it, and the
    file-normal agreement reads the file's signs (outward: 1, inward: 0)."""
    s = shapes.sphere(3000, radius=2.0, seed=3)
    out = stability.measure(s.points, s.normals, estimate_kw=dict(k=15, method="nf"))
    assert out["sub_dh"] < 0.15 and out["sub_flip"] == 0.0  # observed 0.092 (NF variance at 1500 points)
    assert out["noise_dh"] < 0.35  # observed 0.227
    assert out["fixed_k"] == 15 and out["noise_dh_fixed"] == out["noise_dh"]  # k=15 is already fixed
    assert out["file_agree"] == 1.0
    inward = stability.measure(s.points, -s.normals, estimate_kw=dict(k=15, method="nf"))
    assert inward["file_agree"] == 0.0


def test_cli_table_on_a_user_file(tmp_path, capsys, monkeypatch):
    s = shapes.sphere(1500, seed=1)
    path = tmp_path / "ball.xyz"
    np.savetxt(path, s.points)
    monkeypatch.setattr(stability, "BUNNY", path)  # keep the test fast: no bunny
    assert main(["bench", "stability", str(path)]) == 0
    text = capsys.readouterr().out
    assert text.count("ball.xyz") == 2 and "50% |dH|/|H|" in text and "same, fixed k" in text


def test_measure_counts_border_and_file_normal_repairs():
    s = shapes.plane(2000, seed=2)
    given = s.normals.copy()
    given[:7] = 0.0
    given[7:10] *= 3.0
    out = stability.measure(s.points, given, estimate_kw=dict(k=15, method="nf"))
    assert out["repaired"] == 10
    assert 0.02 < out["border"] < 0.5  # an open square: its rim, not its inside
    assert out["striped"] < 0.01  # a random sampling


def test_measure_reads_scan_lines_as_stripes():
    from core import shapes_thin

    s = shapes_thin.stripe_scan(3000, ratio=3.0)
    out = stability.measure(s.points, estimate_kw=dict(k=15, method="nf"))
    assert out["striped"] > 0.9
