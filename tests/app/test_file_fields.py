"""A file's own per-point data in the viewer: its colours ("rgb") and other fields ("file:NAME")."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
import vtk

import core.io
from app import file_fields
from app.fields import RGB, colouring, resolve_field
from app.source import load_file, make_shape

from app_testutils import on_next_preview, run_app_cli, wait_result

N = 600


def _sphere(n=N, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1)[:, None]


def _coloured_ply(path, *, colour_dtype=np.uint8, scale=1, n=N, nan_rows=()):
    """A sphere whose red/green/blue follow the normal, with an intensity (its height) and a
    scan index (its quadrant); rows ``nan_rows`` get a NaN coordinate."""
    points = _sphere(n)
    rgb = (np.rint((points * 0.5 + 0.5) * 255) * scale).astype(colour_dtype)
    fields = {"red": rgb[:, 0], "green": rgb[:, 1], "blue": rgb[:, 2],
              "intensity": (points[:, 1] + 2.0).astype(np.float32),
              "scan": ((points[:, 2] > 0) + 2 * (points[:, 0] > 0)).astype(np.int32)}
    points = points.copy()
    points[list(nan_rows), 0] = np.nan
    core.io.write_cloud(path, points, fields=fields)
    return points, fields


def _combo_texts(window):
    combo = window.field_panel.combo
    return [combo.itemText(i) for i in range(combo.count())]


# -- the data (numpy only) -----------------------------------------------------------------------
def test_colours_8_bit_kept_16_bit_scaled_only_beyond_255():
    eight = {"red": np.array([0, 128, 255], np.uint8), "green": np.array([1, 2, 3], np.uint8),
             "blue": np.array([9, 8, 7], np.uint8)}
    assert file_fields.colours_of(eight).tolist() == [[0, 1, 9], [128, 2, 8], [255, 3, 7]]
    low16 = {k: v.astype(np.uint16) for k, v in eight.items()}  # LAS colours that use only 0-255
    assert file_fields.colours_of(low16).tolist() == [[0, 1, 9], [128, 2, 8], [255, 3, 7]]
    full16 = {k: v.astype(np.uint16) * 257 for k, v in eight.items()}  # 0-65535: the same colours
    assert file_fields.colours_of(full16).tolist() == [[0, 1, 9], [128, 2, 8], [255, 3, 7]]
    fractions = {"Red": np.array([0.0, 0.5, 1.0]), "GREEN": np.zeros(3), "blue": np.ones(3)}  # any case
    assert file_fields.colours_of(fractions).tolist() == [[0, 0, 255], [128, 0, 255], [255, 0, 255]]
    assert file_fields.colours_of({"red": eight["red"], "green": eight["green"]}) is None


def test_only_numeric_per_point_fields_are_kept_read_only():
    n = 4
    kept = file_fields.keep({"intensity": np.arange(n, dtype=np.float32), "label": np.array(list("abcd")),
                             "pair": np.zeros((n, 2)), "short": np.zeros(n - 1), "flag": np.array([1, 0, 1, 0], bool),
                             "z": np.arange(n) * 1j}, n)
    assert list(kept) == ["intensity", "flag"]
    assert kept["flag"].dtype == np.uint8 and kept["flag"].tolist() == [1, 0, 1, 0]
    assert not any(values.flags.writeable for values in kept.values())


def test_load_file_keeps_the_fields_of_the_rows_it_keeps(tmp_path):
    points, fields = _coloured_ply(tmp_path / "c.ply", nan_rows=(3, 10))
    source = load_file(tmp_path / "c.ply")
    keep = np.ones(N, bool)
    keep[[3, 10]] = False
    assert source.n_points == N - 2
    for name in ("red", "green", "blue", "intensity", "scan"):
        assert np.array_equal(source.fields[name], fields[name][keep]), name
        assert not source.fields[name].flags.writeable
    assert list(source.field_specs) == [RGB, "file:intensity", "file:scan"]  # no red/green/blue one by one
    assert source.field_specs["file:scan"].scale == "categorical"
    assert source.field_specs["file:intensity"].scale == "linear"
    assert not make_shape("sphere", 100).fields and not make_shape("sphere", 100).field_specs


def test_file_field_names_on_the_command_line():
    assert resolve_field("RGB") == RGB
    assert resolve_field("file:Intensity") == "file:Intensity"  # matched to the file once it is read
    assert file_fields.find("file:Intensity", {"file:intensity": None, RGB: None}) == "file:intensity"
    assert file_fields.find("file:nope", {"file:intensity": None}) is None
    with pytest.raises(ValueError, match="unknown.*rgb.*file:NAME"):
        resolve_field("file:")


def test_file_fields_are_sequential_whatever_their_sign_and_small_integers_categorical():
    spec = file_fields.specs_of({"height": np.linspace(-5.0, 100.0, 50)})["file:height"]
    look = colouring(spec, np.linspace(-5.0, 100.0, 50))
    assert look.cmap == "viridis" and look.clim[0] < 0 < look.clim[1] and not look.bands
    scan = np.repeat(np.arange(4), 5)
    look = colouring(file_fields.specs_of({"scan": scan})["file:scan"], scan)
    assert look.bands == 4 and look.clim == (-0.5, 3.5) and look.cmap == "tab10"
    wide = np.arange(50)  # 50 integers: a continuous map
    assert file_fields.specs_of({"k": wide})["file:k"].scale == "linear"


def test_fields_of_one_value_are_not_listed_but_stay_drawable():
    n = 5
    fields = {"red": np.zeros(n, np.uint16), "green": np.zeros(n, np.uint16), "blue": np.zeros(n, np.uint16),
              "intensity": np.arange(n, dtype=np.float32), "synthetic": np.zeros(n, np.uint8),
              "user_data": np.full(n, 7, np.int32), "gone": np.full(n, np.nan), "one_left": np.array([np.nan] * 4 + [2.0]),
              "sparse": np.array([np.nan, 1.0, np.nan, 3.0, np.nan]), "blue_only": np.array([0, 0, 0, 0, 1], np.uint8)}
    specs = file_fields.specs_of(fields)
    assert list(file_fields.listed(specs, fields)) == ["file:intensity", "file:sparse", "file:blue_only"]
    assert file_fields.listed(specs, fields)["file:intensity"] == "File: intensity"
    assert list(file_fields.listed(specs, fields, keep="file:synthetic")) == [
        "file:intensity", "file:synthetic", "file:sparse", "file:blue_only"]  # the one shown stays
    assert RGB in specs and "file:synthetic" in specs  # still drawable by name (--field)
    fields["blue"] = np.array([0, 0, 0, 0, 65535], np.uint16)  # one colour component varying is enough
    assert RGB in file_fields.listed(specs, fields)


# -- the window -------------------------------------------------------------------------------------
def test_field_box_lists_the_files_own_fields_and_rgb_draws_the_files_colours(make_window, qtbot, tmp_path):
    _, fields = _coloured_ply(tmp_path / "c.ply", n=400)
    window = make_window()
    window.scene.lod.limit = 100  # (a stand-in for the moving camera, as a big cloud has)
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "c.ply"))
    texts = _combo_texts(window)
    assert "File colour (RGB)" in texts and "File: intensity" in texts and "File: scan" in texts
    assert not any(t in texts for t in ("File: red", "File: green", "File: blue"))
    window.field_panel.combo.setCurrentIndex(texts.index("File colour (RGB)"))  # as the user chooses it
    assert window.state.field == RGB and window.shown["field"] == RGB
    cloud, mapper = window.scene._cloud, window.scene._actor.mapper
    want = np.column_stack([fields["red"], fields["green"], fields["blue"]])
    assert np.array_equal(np.asarray(cloud.point_data["rgb"]), want[window.scene.drawn])
    assert mapper.GetColorMode() == vtk.VTK_COLOR_MODE_DIRECT_SCALARS and mapper.GetArrayName() == "rgb"
    lod = window.scene.lod
    assert np.array_equal(np.asarray(lod._mesh.point_data["rgb"]), want[lod.index])
    assert lod._actor.mapper.GetColorMode() == vtk.VTK_COLOR_MODE_DIRECT_SCALARS
    assert not window.scene._bar.GetVisibility() and "colour-note" in window.plotter.actors
    assert not window.field_panel.lo.isEnabled()  # no limits apply to colours drawn as they are
    window.state.set(field="file:intensity")  # back to a colour map: the bar, editable limits
    assert mapper.GetColorMode() == vtk.VTK_COLOR_MODE_MAP_SCALARS and mapper.GetArrayName() == "values"
    assert np.array_equal(window.scene._values, fields["intensity"].astype(float))
    assert window.scene._bar.GetVisibility() and "colour-note" not in window.plotter.actors
    assert window.field_panel.lo.isEnabled()


def test_16_bit_colours_are_drawn_in_8_bits(make_window, qtbot, tmp_path):
    _, fields = _coloured_ply(tmp_path / "c16.ply", colour_dtype=np.uint16, scale=257)
    assert fields["red"].max() > 255
    window = make_window(field=RGB)
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "c16.ply"))
    drawn = np.asarray(window.scene._cloud.point_data["rgb"])
    want = np.column_stack([fields["red"], fields["green"], fields["blue"]]) // 257
    assert drawn.dtype == np.uint8 and np.array_equal(drawn, want[window.scene.drawn])


def test_a_las_style_file_lists_only_the_fields_that_vary(make_window, qtbot, tmp_path):
    points = _sphere(300)
    zeros = np.zeros(len(points), np.uint16)  # LAS point formats carry colours many scanners leave at 0
    fields = {"red": zeros, "green": zeros, "blue": zeros, "intensity": (points[:, 2] * 100 + 500).astype(np.uint16),
              "synthetic": np.zeros(len(points), np.uint8), "scan_angle": np.full(len(points), -3, np.int8)}
    core.io.write_cloud(tmp_path / "scan.ply", points, fields=fields)
    window = make_window()
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "scan.ply"))
    assert [t for t in _combo_texts(window) if t.startswith("File")] == ["File: intensity"]
    window = make_window(field="file:synthetic")  # asked for by name, it is listed and drawn
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "scan.ply"))
    assert [t for t in _combo_texts(window) if t.startswith("File")] == ["File: intensity", "File: synthetic"]
    assert window.state.field == "file:synthetic" and window.shown["field"] == "file:synthetic"


def test_a_cloud_without_fields_lists_none(make_window, qtbot, tmp_path, torus):
    core.io.write_cloud(tmp_path / "plain.ply", _sphere())
    window = make_window()
    with wait_result(qtbot, window):
        window.set_source(_coloured_source(tmp_path))
    assert "File: intensity" in _combo_texts(window)
    for source in (load_file(tmp_path / "plain.ply"), torus):  # the previous file's fields go
        with wait_result(qtbot, window):
            window.set_source(source)
        assert not [t for t in _combo_texts(window) if t.startswith("File") or not t]


def _coloured_source(tmp_path):
    _coloured_ply(tmp_path / "coloured.ply")
    return load_file(tmp_path / "coloured.ply")


def test_a_file_field_is_drawn_before_the_estimate_and_on_the_same_points_with_noise(make_window, qtbot, tmp_path):
    _, fields = _coloured_ply(tmp_path / "c.ply")
    source = load_file(tmp_path / "c.ply")
    window = make_window(field="file:intensity", noise=30.0)
    window.set_source(source)
    assert window.output is None and window.shown["field"] == "file:intensity"  # no estimate yet
    assert np.array_equal(window.scene._values, fields["intensity"].astype(float))
    with wait_result(qtbot, window) as got:
        pass
    out = got.out
    assert out.request.noise == 30.0 and not np.array_equal(out.points, source.points)  # a noisy copy
    assert np.allclose(out.points, source.points, atol=0.2)  # of the same points, in their order
    assert np.array_equal(window.scene._values, fields["intensity"].astype(float))
    assert window.shown["field"] == "file:intensity" and window.shown["gen"] == out.gen


def test_a_preview_draws_the_file_field_of_every_point(make_window, qtbot, tmp_path, monkeypatch):
    import app.preview

    monkeypatch.setattr(app.preview, "PREVIEW_POINTS", 300)
    monkeypatch.setattr(app.preview, "PREVIEW_AUTO_MIN", 300)
    _, fields = _coloured_ply(tmp_path / "c.ply", n=1500)
    window = make_window(field="file:scan")
    seen = on_next_preview(window, lambda out: (out.preview, window.scene._values.copy(), dict(window.shown)))
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "c.ply"))
    assert seen, "no preview came"
    n_sub, values, shown = seen[0]
    assert n_sub == 300 and shown["field"] == "file:scan" and shown.get("preview")
    assert np.array_equal(values, fields["scan"].astype(float))  # every point's own, not its subsample neighbour's


def test_scan_index_is_drawn_one_colour_a_scan(make_window, qtbot, tmp_path):
    _coloured_ply(tmp_path / "c.ply")
    window = make_window(field="file:scan")
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "c.ply"))
    assert window.shown["clim"] == (-0.5, 3.5) and window.shown["cmap"] == "tab10"
    assert window.scene._lut.n_values == 4
    bar = window.scene._bar
    labels = bar.GetCustomLabels()
    assert bar.GetUseCustomLabels() and [labels.GetValue(i) for i in range(labels.GetNumberOfTuples())] == [0, 1, 2, 3]
    tab10 = matplotlib.colormaps["tab10"].colors
    for scan in range(4):  # tab10's first four colours (not its ends), the histogram's bars in the cloud's
        bar_of = next(b for b in window.histogram._bars if b.get_x() <= scan < b.get_x() + b.get_width())
        rgb = [0.0, 0.0, 0.0]
        window.scene._lut.GetColor(float(scan), rgb)
        assert np.allclose(rgb, tab10[scan], atol=0.01), scan
        assert np.allclose(bar_of.get_facecolor()[:3], rgb, atol=0.01), scan
    window.state.set(field="mean")  # a continuous map again
    assert window.scene._lut.n_values == 256 and not bar.GetUseCustomLabels()


def test_picked_point_panel_shows_the_files_values(make_window, qtbot, tmp_path):
    _, fields = _coloured_ply(tmp_path / "c.ply")
    window = make_window()
    with wait_result(qtbot, window):
        window.set_source(load_file(tmp_path / "c.ply"))
    window.state.set(picked=17)
    values = window.inspector.values
    assert values["file: red"] == str(fields["red"][17]) and values["file: scan"] == str(fields["scan"][17])
    assert float(values["file: intensity"]) == pytest.approx(float(fields["intensity"][17]), rel=1e-4)
    table = window.inspector.table
    labels = [table.item(r, 0).text() for r in range(table.rowCount())]
    assert labels[-5:] == ["file: red", "file: green", "file: blue", "file: intensity", "file: scan"]


def test_a_file_field_the_next_cloud_has_not_falls_back_to_H_with_a_notice(make_window, qtbot, tmp_path, torus):
    window = make_window(field=RGB)
    with wait_result(qtbot, window):
        window.set_source(_coloured_source(tmp_path))
    assert window.shown["field"] == RGB
    with wait_result(qtbot, window):
        window.set_source(torus)
    assert window.state.field == "mean" and window.shown["field"] == "mean"
    note = window.notifier.last
    assert note.message.startswith(f"File colour (RGB) is not available for {torus.name}: it has no such field of "
                                   "its own (its own: none); showing Mean curvature H"), note.message


# -- the command line ----------------------------------------------------------------------------------
def test_screenshot_in_the_files_colours_and_an_unknown_file_field_refused(tmp_path):
    _coloured_ply(tmp_path / "c.ply")
    proc = run_app_cli(str(tmp_path / "c.ply"), "--field", "file:nope", "--screenshot", str(tmp_path / "no.png"))
    assert proc.returncode == 2, proc.stderr
    assert "field 'file:nope' is unknown for c.ply" in proc.stderr
    assert "rgb, file:intensity, file:scan" in proc.stderr and not (tmp_path / "no.png").exists()
    proc = run_app_cli(str(tmp_path / "c.ply"), "--field", "RGB", "--view-only", "--size", "800x600",
                       "--screenshot", str(tmp_path / "rgb.png"))
    assert proc.returncode == 0 and not proc.stderr, proc.stderr
    assert (tmp_path / "rgb.png").exists()
