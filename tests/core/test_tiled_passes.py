"""The tiled run's overheads: one pass over the input file, a quiet local Dask cluster,
and the CPU accounting of a run (core.tiled.binning, core.tiled.engine, TiledRun.cpu)."""

from __future__ import annotations

import laspy
import numpy as np

from core import noise, shapes
from core.tiled import binning, engine, estimate_tiled
from core.tiled.source import open_source
from core.tiled.store import TileStore


def _scan(path, n=6000):
    pts = noise.add_noise(shapes.torus(n, seed=2).points, 0.05, seed=1)
    header = laspy.LasHeader(point_format=3, version="1.2")
    header.scales, header.offsets = np.full(3, 1e-4), np.floor(pts.min(axis=0))
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
    las.write(str(path))


def _bins(store, n_tiles):
    return [store.bin_path(t).read_bytes() for t in range(n_tiles)]


def test_a_file_is_decompressed_once_and_binned_as_from_the_file(tmp_path, monkeypatch):
    _scan(tmp_path / "scan.laz")
    src = open_source(tmp_path / "scan.laz")
    store = TileStore(tmp_path / "work")
    store.open({"run": 1})
    plan = binning.plan_tiles(src, store, 1000, lambda *a: None)
    assert store.spill_path.stat().st_size == src.count * 32  # xyz + row, every point

    reads = []
    chunks = type(src).chunks
    monkeypatch.setattr(type(src), "chunks", lambda self, *a: reads.append(1) or chunks(self, *a))
    counts = binning.bin_points(src, store, plan, lambda *a: None)
    assert reads == [] and not store.spill_path.exists()  # binned from the spill, which is then removed
    spilled = _bins(store, plan.n_tiles)

    (store.root / "bins" / "done.json").unlink()  # a resumed run without the spill reads the file again
    again = binning.bin_points(src, store, plan, lambda *a: None)
    assert reads == [1] and again == counts and sum(counts) == src.count
    assert _bins(store, plan.n_tiles) == spilled
    rows = np.concatenate([store.read_bin(t)["index"] for t in range(plan.n_tiles)])
    np.testing.assert_array_equal(np.sort(rows), np.arange(src.count))


def test_an_array_source_is_not_spilled(tmp_path):
    src = open_source(shapes.torus(3000, seed=1).points)
    store = TileStore(tmp_path / "work")
    store.open({"run": 2})
    plan = binning.plan_tiles(src, store, 1000, lambda *a: None)
    assert not store.spill_path.exists()
    assert sum(binning.bin_points(src, store, plan, lambda *a: None)) == 3000


def test_the_local_cluster_runs_quiet_workers_and_times_each_task(tmp_path):
    def probe(root, tile, spec):
        config = __import__("dask").config
        return {"tile": tile, "points": 1, "profile": config.get("distributed.worker.profile.enabled"),
                "tick": config.get("distributed.admin.tick.interval")}

    out = engine.run_tasks(tmp_path, [0, 1], [1, 1], None, workers=1, memory="1GB", fn=probe)
    assert sorted(s["tile"] for s in out) == [0, 1]
    for s in out:
        assert s["profile"] is False and s["tick"] == engine.DASK_CONFIG["distributed.admin.tick.interval"]
        assert s["cpu"] >= 0.0
    assert __import__("dask").config.get("distributed.worker.profile.enabled") is True  # this process: untouched


def test_a_run_accounts_for_its_cpu_by_stage(tmp_path):
    _scan(tmp_path / "scan.laz", 4000)
    run = estimate_tiled(tmp_path / "scan.laz", tmp_path / "out.laz", k=12, tile_points=1000, workers=0)
    assert set(run.cpu) == {"plan", "bin", "tiles", "signs", "assemble", "tile tasks"}
    assert all(v >= 0 for v in run.cpu.values())
    assert 0 < run.cpu["tile tasks"] <= run.cpu["tiles"] + 0.05  # in this process the tasks are the stage
