"""darboux-cli: estimate writes a result file, bad input is one clear line and exit code 2."""

import numpy as np
import pytest

import core
from core.cli import main


@pytest.fixture(scope="module")
def cloud_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli") / "sphere.xyz"
    pts = core.shapes.sphere(800, radius=2.0, seed=3).points
    np.savetxt(path, pts)
    return path


@pytest.mark.parametrize("k_args, k_expected", [([], "auto"), (["--k", "15"], 15)])
def test_estimate_writes_curvatures(cloud_file, tmp_path, capsys, k_args, k_expected):
    out = tmp_path / "out.csv"
    before = cloud_file.read_bytes()
    assert main(["estimate", str(cloud_file), "-o", str(out), *k_args]) == 0
    assert cloud_file.read_bytes() == before  # the input is never modified
    assert f"k {k_expected}," in capsys.readouterr().out
    table = np.genfromtxt(out, delimiter=",", names=True)
    assert len(table) == 800
    assert abs(np.median(table["mean"]) - 0.5) < 0.02  # outward sphere of radius 2: H = 1/R


def test_bad_k_is_rejected_by_the_parser(cloud_file, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["estimate", str(cloud_file), "-o", str(tmp_path / "o.ply"), "--k", "many"])
    assert exc.value.code == 2
    assert "k 'many' must be an integer or auto" in capsys.readouterr().err


def test_bad_value_is_one_line_and_exit_2(cloud_file, tmp_path, capsys):
    code = main(["estimate", str(cloud_file), "-o", str(tmp_path / "o.ply"), "--k", "auto", "--method", "ct"])
    assert code == 2
    err = capsys.readouterr().err
    assert err.startswith("darboux-cli: error: ") and err.count("\n") == 1
    assert not (tmp_path / "o.ply").exists()


def test_estimate_counts_duplicate_points(tmp_path, capsys):
    from core import shapes

    pts = shapes.sphere(800, radius=2.0, seed=2).points
    src, out = tmp_path / "twice.xyz", tmp_path / "out.csv"
    np.savetxt(src, np.concatenate([pts, pts[:100]]))
    assert main(["estimate", str(src), "-o", str(out), "--k", "15"]) == 0
    assert "duplicate points: 100 (each estimated at its place, once)" in capsys.readouterr().out
    table = np.genfromtxt(out, delimiter=",", names=True)
    assert len(table) == 900 and np.isfinite(table["mean"]).all()
