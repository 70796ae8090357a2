"""The window with files a user should not lose or be stuck with (found by a sweep of the
viewer with hostile files): an export over the cloud's own file is refused and the file
kept; a file with nothing to draw or too few points to estimate is refused at load, as an
unreadable one is, and the cloud on screen stays."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from app_testutils import wait_result

import core.io
from app.source import make_shape


@pytest.fixture
def scan(tmp_path):
    s = make_shape("sphere", 1500)
    return core.io.write_cloud(tmp_path / "scan.ply", s.points, normals=s.normals)


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_an_export_over_the_clouds_own_file_is_refused(make_window, qtbot, scan, tmp_path):
    window = make_window(k_auto=False, k=12)
    with wait_result(qtbot, window, 60_000):
        window.open_file(scan)
    before = _digest(scan)
    (tmp_path / "link.ply").symlink_to(scan)
    for target in (scan, tmp_path / "." / "scan.ply", tmp_path / "link.ply"):  # what a Save dialog may return
        assert window.export_result(target) is None  # was: written over the input, its normals lost
        note = window.notifier.last
        assert note.level == "error" and "is the input file" in note.message
    assert _digest(scan) == before
    assert window.export_result(tmp_path / "out.ply") == tmp_path / "out.ply"  # another name is written


@pytest.mark.parametrize("name, rows, says", [
    ("one.xyz", np.array([[0.0, 0.0, 0.0]]), "has 1 point; an estimate needs at least 3"),
    ("two.xyz", np.eye(3)[:2], "has 2 points; an estimate needs at least 3"),
    ("huge.xyz", np.random.default_rng(0).normal(size=(50, 3)) * 1e160, "nothing can be drawn or estimated"),
])
def test_a_file_with_nothing_to_estimate_or_draw_is_refused_at_load(make_window, qtbot, tmp_path, name, rows, says):
    window = make_window(make_shape("torus", 800), k_auto=False, k=12)
    shown = window.state.source
    path = tmp_path / name
    np.savetxt(path, rows)
    window.open_file(path)  # huge.xyz raised 'Empty meshes cannot be plotted' inside a Qt slot, no estimate ran
    qtbot.waitUntil(lambda: window.loader.pending is None, timeout=30_000)
    qtbot.wait(50)
    note = window.notifier.last
    assert note.level == "error" and name in note.message and says in note.message
    assert window.state.source is shown and window.output is not None  # the cloud and its result stay


class _Panic(BaseException):
    """What pyo3 raises for a native library's panic: no ``Exception`` base."""


def test_a_reader_panic_is_a_load_failure_and_the_loader_goes_on(qtbot, monkeypatch, scan):
    """A BaseException from a reader passed the loader's ``except Exception``: it ended the
    loader's thread, the load stayed pending for ever and no later file was read."""
    from app import loader as loader_module

    real = loader_module.load_file

    def panics(path):
        raise _Panic("called `Result::unwrap()` on an `Err` value")

    loader = loader_module.CloudLoader()
    try:
        monkeypatch.setattr(loader_module, "load_file", panics)
        with qtbot.waitSignal(loader.failed, timeout=10_000) as failed:
            loader.open_file(scan)
        assert "scan.ply: _Panic: called `Result::unwrap()`" in failed.args[1]
        monkeypatch.setattr(loader_module, "load_file", real)
        with qtbot.waitSignal(loader.loaded, timeout=30_000) as loaded:
            loader.open_file(scan)
        assert loaded.args[1].n_points == 1500
    finally:
        loader.shutdown(2.0)
