"""Tiles on a Dask scheduler the run did not start (``--scheduler``): its client is not the
process's default, and waiting on its futures asked for the default one ("No clients
found"), so every run against a working scheduler failed."""

from __future__ import annotations

import pytest

import core
from core.tiled import estimate_tiled

distributed = pytest.importorskip("distributed")


def test_tiles_run_on_a_scheduler_given_by_address(tmp_path):
    pts = core.shapes.sphere(1200, seed=3).points
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=":0",
                                  silence_logs=40) as cluster:
        run = estimate_tiled(pts, tmp_path / "o.ply", k=15, tile_points=400, scheduler=cluster.scheduler_address)
    assert run.n_tiles >= 3 and run.n_points == len(pts)
    assert len(core.io.read_cloud(tmp_path / "o.ply").points) == len(pts)


def test_a_killed_worker_is_told_as_memory(monkeypatch):
    from core.tiled import engine

    class KilledWorker(Exception):
        pass

    class Failed:
        status = "error"

        def cancel(self):
            pass

        def exception(self):
            return KilledWorker("attempted to run the task on 4 different workers, all died")

    class Client:
        loop = None
        dashboard_link = ""

        def submit(self, *args, **kwargs):
            return Failed()

    monkeypatch.setattr(distributed, "as_completed", lambda futures, loop=None: iter(futures))
    clock = engine._Clock(1, None)
    with pytest.raises(ValueError, match="tile 0 failed: KilledWorker.*memory limit: lower --tile-points"):
        engine._on_dask(None, "root", [0], [1], None, clock, client=Client(), scheduler=None, workers=1,
                        memory=None, label="in.ply")
