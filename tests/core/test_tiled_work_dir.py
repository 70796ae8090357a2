"""A tiled run's work directory holds the run's own files and nothing it does not own is
ever deleted: ``--work-dir DIR`` once removed DIR with everything in it (the input too)."""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

import core
from core import cli
from core.tiled import estimate_tiled
from core.tiled.store import TileStore


def _digest(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _folder_with_input(tmp_path):
    data = tmp_path / "mydata"
    data.mkdir()
    np.savetxt(data / "scan.xyz", core.shapes.sphere(1500, seed=2).points)
    (data / "notes.txt").write_text("precious")
    return data, {p.name: _digest(p) for p in data.iterdir()}


@pytest.mark.parametrize("output", ["out.ply", "out.laz"])
def test_work_dir_keeps_every_file_it_did_not_write(tmp_path, output):
    data, before = _folder_with_input(tmp_path)
    argv = ["estimate", str(data / "scan.xyz"), "-o", str(tmp_path / output), "--k", "15", "--workers", "0",
            "--tile-points", "500", "--work-dir", str(data), "-q"]
    assert cli.main(argv) == 0
    assert (tmp_path / output).exists()
    assert {p.name: _digest(p) for p in data.iterdir()} == before  # the run's own folder came and went


def test_a_work_dir_holding_other_files_is_refused_untouched(tmp_path):
    data, before = _folder_with_input(tmp_path)
    with pytest.raises(ValueError, match="holds files that are not a tiled run's"):
        estimate_tiled(core.shapes.sphere(900, seed=1).points, tmp_path / "o.ply", k=15, tile_points=300,
                       workers=0, workdir=data)
    assert {p.name: _digest(p) for p in data.iterdir()} == before and not (tmp_path / "o.ply").exists()


def test_another_runs_directory_is_cleared_of_its_own_files_only(tmp_path):
    store = TileStore(tmp_path / "work")
    assert store.open({"run": 1}) is False
    (store.root / "results" / "tile_000000.done").touch()
    (store.root / "keep.txt").write_text("mine")  # someone's file among the run's
    assert TileStore(store.root).open({"run": 2}) is False  # another run: the old one's files go
    assert (store.root / "keep.txt").read_text() == "mine" and not any(store.root.glob("results/*"))
    assert json.loads((store.root / "manifest.json").read_text()) == {"run": 2}
    TileStore(store.root).remove()
    assert [p.name for p in store.root.iterdir()] == ["keep.txt"]


def test_a_run_in_a_new_work_dir_removes_it_afterwards(tmp_path):
    work = tmp_path / "scratch" / "tiles"
    estimate_tiled(core.shapes.sphere(900, seed=1).points, tmp_path / "o.ply", k=15, tile_points=300, workers=0,
                   workdir=work)
    assert (tmp_path / "o.ply").exists() and not work.exists() and (tmp_path / "scratch").is_dir()


def test_a_full_disk_is_named_with_the_file(tmp_path, monkeypatch):
    """numpy's short write says only "20000 requested and 1920 written"."""
    from core.tiled import binning

    class Short(np.ndarray):
        def tofile(self, f):
            raise OSError("20000 requested and 1920 written")

    records = binning._records
    monkeypatch.setattr(binning, "_records", lambda *args: records(*args).view(Short))
    with pytest.raises(OSError, match=r"tile_\d+\.bin: cannot be written \(20000 requested.*may be full"):
        estimate_tiled(core.shapes.sphere(900, seed=1).points, tmp_path / "o.ply", k=15, tile_points=300,
                       workers=0, workdir=tmp_path / "work")
    assert not (tmp_path / "work").exists()


def test_tiles_drop_nonfinite_points_when_asked(tmp_path):
    """--drop-nonfinite was not passed to the tiles: a file with 3 NaN rows was refused
    ("pass drop_nonfinite=True") with the flag given."""
    pts = core.shapes.sphere(1200, seed=3).points
    pts[[5, 50, 500]] = np.nan
    np.savetxt(tmp_path / "nan.xyz", pts)
    argv = ["estimate", str(tmp_path / "nan.xyz"), "-o", str(tmp_path / "o.ply"), "--k", "15", "--workers", "0",
            "--tile-points", "400", "--drop-nonfinite", "-q"]
    with pytest.warns(UserWarning):
        assert cli.main(argv) == 0
    assert len(core.io.read_cloud(tmp_path / "o.ply").points) == 1197
    run = estimate_tiled(pts, tmp_path / "a.ply", k=15, tile_points=400, workers=0, drop_nonfinite=True)
    assert run.n_points == 1197


def test_a_missing_input_among_several_is_told_and_the_others_estimated(tmp_path, capsys):
    np.savetxt(tmp_path / "a.xyz", core.shapes.sphere(900, seed=1).points)
    np.savetxt(tmp_path / "b.xyz", core.shapes.sphere(900, seed=2).points)
    argv = ["estimate", str(tmp_path / "a.xyz"), str(tmp_path / "missing.xyz"), str(tmp_path / "b.xyz"),
            "-o", str(tmp_path / "{stem}_out.ply"), "--k", "15", "--workers", "0", "--tile-points", "300", "-q"]
    assert cli.main(argv) == 2
    assert "missing.xyz: no such file" in capsys.readouterr().err
    assert (tmp_path / "a_out.ply").exists() and (tmp_path / "b_out.ply").exists()
