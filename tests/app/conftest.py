"""Fixtures for the viewer tests (pytest-qt; pytest-xvfb provides the X display).

``make_window`` owns every window it makes: at teardown it closes them, checks
that their plotters were closed and left pyvista's registry, processes deferred
deletes, and fails if an estimator thread or a Python thread outlived them
(after napari's ``make_napari_viewer`` and pyvistaqt's ``ensure_closed``).
"""

from __future__ import annotations

import gc
import os
import sys
import threading
from pathlib import Path

import pytest

# `pytest` run from anywhere still imports this checkout's `app` and `core`
ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

# QtInteractor does not render on the offscreen platform: use the X server
# that pytest-xvfb starts.
if os.environ.get("QT_QPA_PLATFORM") == "offscreen":
    del os.environ["QT_QPA_PLATFORM"]

from PySide6.QtCore import QCoreApplication, QEvent, QSettings  # noqa: E402


def pytest_collection_modifyitems(config, items):
    """Warnings are errors in the app tests (third-party noise is listed explicitly)."""
    for item in items:
        if "tests/app" in str(item.fspath).replace(os.sep, "/"):
            item.add_marker(pytest.mark.filterwarnings("error"))


@pytest.fixture(scope="session")
def torus():
    """A 2000-point torus (the paper's R=2, r=1) with exact truth."""
    from app.source import make_shape

    return make_shape("torus", 2000)


@pytest.fixture
def settings(tmp_path):
    s = QSettings(str(tmp_path / "darboux-test.ini"), QSettings.Format.IniFormat)
    yield s
    s.sync()


def _process_deletes():
    for _ in range(3):
        QCoreApplication.sendPostedEvents(None, QEvent.Type.DeferredDelete)
        QCoreApplication.processEvents()


@pytest.fixture
def make_window(qtbot, settings):
    """Factory: ``make_window(source=None, show=True, wait=True, size=(1200, 800), **state_values)``.

    With a source and ``wait=True`` it returns once the first result is drawn.
    """
    import pyvista.plotting.plotter as pv_plotter

    from app_testutils import wait_result

    from app.state import ViewerState
    from app.window import MainWindow
    from app.estimator import Estimator

    before = set(threading.enumerate())
    plotters_before = set(pv_plotter._ALL_PLOTTERS)
    windows: list[MainWindow] = []

    def factory(source=None, *, show: bool = True, wait: bool = True, timeout: int = 60_000,
                size: tuple[int, int] = (1200, 800), **values):
        window = MainWindow(state=ViewerState(**values), settings=settings, dialogs=False)
        windows.append(window)
        if show:
            window.resize(*size)
            window.show()
            qtbot.waitExposed(window)
        if source is not None:
            if wait:
                with wait_result(qtbot, window, timeout):
                    window.set_source(source)
            else:
                window.set_source(source)
        return window

    yield factory

    for window in windows:
        window.close()
        assert window._closed, "closeEvent did not shut the window down"
        assert window.plotter._closed, "main plotter left open"
        if window.compare is not None:
            assert window.compare.plotter._closed, "compare plotter left open"
        window.deleteLater()
    _process_deletes()
    windows.clear()
    gc.collect()
    _process_deletes()
    # an abandoned job stops at its next cancel check (a fraction of a second)
    qtbot.waitUntil(lambda: not Estimator.running_threads(), timeout=10_000)
    assert not Estimator.running_threads(), "a job thread outlived its window"
    # threads started by Qt show up as threading._DummyThread once they ran Python code
    leaked = [t.name for t in threading.enumerate()
              if t not in before and t.is_alive() and not isinstance(t, threading._DummyThread)]
    assert not leaked, f"threads leaked: {leaked}"
    left = set(pv_plotter._ALL_PLOTTERS) - plotters_before
    assert not left, f"plotters leaked: {left}"


@pytest.fixture
def previewing(monkeypatch):
    """Previews on small clouds (as test_preview_comes_first_then_the_full_result)."""
    import app.preview
    from app.source import make_shape

    monkeypatch.setattr(app.preview, "PREVIEW_POINTS", 800)
    monkeypatch.setattr(app.preview, "PREVIEW_AUTO_MIN", 800)
    return make_shape("torus", 3000)
