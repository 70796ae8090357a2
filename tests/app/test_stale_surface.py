"""A closed window leaves no GL surface wrapper mapped (app._refguard.forget_surface): PySide
is not told when Qt deletes a QSurface, and an object Qt later made at its address came back
as that wrapper (``QTableWidget.verticalHeader()`` returned a ``QSurface`` in a suite run)."""

from __future__ import annotations

import gc

import shiboken6
from PySide6.QtGui import QSurface


def _mapped_surfaces(plotters) -> list:
    held = [getattr(p, "_surface", None) for p in plotters]
    return [s for s in held if s is not None and shiboken6.isValid(s)]


def test_closing_the_window_unmaps_its_surfaces(make_window, qtbot, torus):
    window = make_window(torus)
    plotters = [window.plotter] + ([window.compare.plotter] if window.compare is not None else [])
    assert any(isinstance(getattr(p, "_surface", None), QSurface) for p in plotters), "no surface captured"
    window.close()
    gc.collect()
    assert _mapped_surfaces(plotters) == []
