"""``python -m core bench scanlines``: its clouds carry their exact geometry, and its table
scores an estimate against it."""

import json

import numpy as np
import pytest

from core.bench import scan_clouds, scanlines


@pytest.mark.parametrize("make", [
    lambda: scan_clouds.sphere_parallels(12, 0.0),
    lambda: scan_clouds.cylinder_rings(8, 0.0),
    lambda: scan_clouds.torus_parallels(8, 0.0),
    lambda: scan_clouds.sphere_seen(0.0),
])
def test_clouds_lie_on_their_surfaces_with_unit_normals(make):
    c = make()
    assert c.points.shape == c.normals.shape and len(c.mean) == len(c.points) and c.use.any()
    np.testing.assert_allclose(np.linalg.norm(c.normals, axis=1), 1.0, atol=1e-12)


def test_sphere_truth_and_score_of_the_truth():
    c = scan_clouds.sphere_parallels(8, 0.0)
    np.testing.assert_allclose(np.linalg.norm(c.points, axis=1), 1.0, atol=1e-12)

    class Exact:  # the truth scores zero error, everything valid and (from outside) facing the scanner
        normals, mean, valid = c.normals, c.mean, np.ones(len(c.points), dtype=bool)

    row = scanlines.score(c._replace(view=(0.0, 0.0, 0.0)), Exact)
    assert row["h_error"] == 0.0 and row["normal_p90"] < 1e-5 and row["valid"] == 1.0
    assert row["facing"] == 0.0  # the normals point away from a scanner at the centre


def test_run_prints_a_row_per_cloud_and_writes_json(tmp_path, capsys):
    path = tmp_path / "rows.json"
    assert scanlines.main(["--only", "sphere parallels 12x, noise 0.05", "--json", str(path)]) == 0
    rows = json.loads(path.read_text())
    assert list(rows) == ["sphere parallels 12x, noise 0.05"]
    row = rows["sphere parallels 12x, noise 0.05"]
    assert row["valid"] > 0.95 and row["h_error"] < 0.02 and row["normal_p50"] < 0.2  # 2026-12-05: 0.0042, 0.031
    assert "sphere parallels 12x" in capsys.readouterr().out


def test_unknown_cloud_names_the_choices():
    with pytest.raises(SystemExit, match="LiDAR ground"):
        scanlines.main(["--only", "nothing like it"])
