"""Viewer bits of real scans: the file-normals checkbox follows the file."""

from __future__ import annotations

import numpy as np

from app.source import load_file


def test_normals_checkbox_disabled_without_file_normals(make_window, qtbot, torus, tmp_path):
    path = tmp_path / "bare.xyz"
    np.savetxt(path, torus.points)
    w = make_window(load_file(path))
    assert not w.normals_check.isEnabled()
    assert w.output is not None  # estimated its own normals
    w.set_source(torus)  # a shape comes with exact normals
    assert w.normals_check.isEnabled()
