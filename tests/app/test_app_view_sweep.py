"""Viewer defects from the view sweep (/work/sweep_view/FINDINGS.md, findings 2-7), each
driven through the real window (or, for the command line, the real parser and process)."""

from __future__ import annotations

import numpy as np
import pytest
from app_testutils import on_next_preview, run_app_cli, wait_result
from PySide6.QtWidgets import QMessageBox
from scipy.spatial import cKDTree

from app.source import CloudSource, make_shape



def _glyph_centres(window, kind: str) -> np.ndarray:
    """The points the glyphs of one kind stand on: the centres of the ± segments; a normal's
    segment rises from its point's sprite top, ``overlay_lift`` along it (app.scene.set_glyphs)."""
    mesh = window.plotter.actors[f"glyph-{kind}"].mapper.dataset
    v = np.asarray(mesh.points)
    if kind == "normals":
        d = v[1::2] - v[0::2]
        return v[0::2] - window.scene.overlay_lift() * d / np.linalg.norm(d, axis=1, keepdims=True)
    return 0.5 * (v[0::2] + v[1::2])


# -- 2: glyphs within a budget -----------------------------------------------------------
def test_glyphs_are_drawn_at_a_budget_of_evenly_spread_positions(make_window, qtbot, monkeypatch):
    import app.glyphs
    from app.lod import STILL_POINTS

    assert 0 < app.glyphs.GLYPH_POINTS <= STILL_POINTS  # no more glyph positions than a still frame's points
    monkeypatch.setattr(app.glyphs, "GLYPH_POINTS", 400)  # a 3000-point cloud stands for a big one
    torus = make_shape("torus", 3000)
    window = make_window(torus, k_auto=False, k=12)
    window.state.set(show_e1=True, show_e2=True, show_normals=True, glyph_density=1.0)
    for kind in ("e1", "e2", "normals"):
        n_cells = window.plotter.actors[f"glyph-{kind}"].mapper.dataset.n_cells
        assert n_cells == 400, kind  # the slider's 100 % is the budget, not every point
    # each normal stands on a chosen point
    tree = cKDTree(torus.points)
    dist, full = tree.query(_glyph_centres(window, "normals"))
    assert dist.max() < 1e-9 and len(set(full)) == 400
    window.state.set(glyph_density=0.25)  # a fraction of the budgeted positions, all among them
    part = tree.query(_glyph_centres(window, "normals"))[1]
    assert len(part) == 100 and set(part) <= set(full)
    # spread evenly: every point of the cloud is nearer a glyph than with the first or random rows
    for m, chosen in ((400, full), (100, part)):
        cover = cKDTree(torus.points[chosen]).query(torus.points)[0].max()
        first = cKDTree(torus.points[:m]).query(torus.points)[0].max()
        random = cKDTree(torus.points[np.random.default_rng(1).choice(3000, m, replace=False)]).query(
            torus.points)[0].max()
        assert cover < 0.85 * min(first, random), (m, cover, first, random)
    # deterministic: the same cloud again draws the same glyphs
    again = make_window(make_shape("torus", 3000), k_auto=False, k=12, show_normals=True, glyph_density=0.25)
    assert np.array_equal(np.sort(tree.query(_glyph_centres(again, "normals"))[1]), np.sort(part))


# -- 3: the Field box names the field drawn ----------------------------------------------
def test_field_box_follows_a_fallback_to_mean_curvature(make_window, qtbot, torus):
    window = make_window(torus, field="err_mean")
    assert window.shown["field"] == "err_mean" == window.field_panel.combo.currentData()
    plain = CloudSource(name="plain torus", points=np.array(torus.points))  # no truth, no normals
    with wait_result(qtbot, window, 30_000):
        window.set_source(plain)
    qtbot.wait(50)
    assert window.shown["field"] == "mean"
    assert window.field_panel.combo.currentData() == "mean" == window.state.field
    assert window.field_panel.combo.currentText() == "Mean curvature H"
    note = window.notifier.last
    assert note.level == "warning" and "Error of H is not available for plain torus" in note.message
    assert "Mean curvature H" in note.message
    # choosing a field the cloud has still works, and no notice is repeated
    count = len(window.notifier.history)
    window.field_panel.combo.setCurrentIndex(window.field_panel.combo.findData("gaussian"))
    assert window.shown["field"] == "gaussian" == window.state.field
    assert len(window.notifier.history) == count


def test_a_preview_draws_the_field_the_box_names(make_window, qtbot, previewing):
    window = make_window(previewing, field="err_mean", k_auto=False, k=12)
    seen = on_next_preview(window, lambda out: (dict(window.shown), window.field_panel.combo.currentData()))
    with wait_result(qtbot, window, 60_000):
        window.state.set(noise=20.0)
    qtbot.waitUntil(lambda: bool(seen), timeout=10_000)
    shown, boxed = seen[0]
    assert shown.get("preview") and shown["field"] == "err_mean" == boxed  # errors of the preview itself
    assert window.shown["field"] == "err_mean" == window.field_panel.combo.currentData()
    assert not [n for n in window.notifier.history if n.level == "warning"]


def test_cli_field_on_a_plain_file_says_it_fell_back(tmp_path):
    import core.io

    plain = tmp_path / "plain.xyz"
    core.io.write_cloud(plain, make_shape("torus", 1000).points)
    out = tmp_path / "shot.png"
    proc = run_app_cli(str(plain), "--field", "err_mean", "--screenshot", str(out))
    assert proc.returncode == 0, proc.stderr
    assert "Error of H is not available for plain.xyz" in proc.stderr and "Mean curvature H" in proc.stderr
    assert out.exists()


# -- 4: a failed open leaves the estimate of the cloud on screen alone ---------------------
def test_a_file_that_fails_to_open_leaves_the_estimate_under_way(make_window, qtbot, previewing, tmp_path):
    bad = tmp_path / "broken.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 100\nproperty float x\nend_header\n1 2\n")
    window = make_window(previewing, k_auto=False, k=12)
    kept = []

    def open_bad(out):
        window.open_file(bad)  # File > Open while the preview is on screen
        kept.append(window.presenter.preview)
        return out

    seen = on_next_preview(window, open_bad)
    with wait_result(qtbot, window, 60_000) as blocker:
        window.state.set(noise=25.0)
        qtbot.waitUntil(lambda: bool(seen) and window.loader.pending is None, timeout=30_000)
        assert kept[0] is seen[0]  # opening the file left the preview on screen
        # and its failure did too, unless the full result has replaced it since (a race: both are quick)
        assert window.presenter.preview is seen[0] or window.output.request.noise == 25.0
        assert window.notifier.last.level == "error" and "broken.ply" in window.notifier.last.message
        assert window.estimator.busy or window.output.request.noise == 25.0  # not cancelled
        assert "not estimated" not in window.status_label.text()
    assert blocker.args[0].request.noise == 25.0 and window.output is blocker.args[0]
    assert window.state.source is previewing and window.presenter.preview is None


def test_a_shape_replaces_the_cloud_and_its_estimate_only_when_it_arrives(make_window, qtbot, previewing):
    window = make_window(previewing, k_auto=False, k=12)
    seen = on_next_preview(window, lambda out: (window.load_shape("sphere", 700), window.estimator.busy)[1])
    window.state.set(noise=25.0)
    qtbot.waitUntil(lambda: bool(seen), timeout=60_000)
    assert seen[0] is True  # the torus is still being estimated while the sphere is generated
    qtbot.waitUntil(lambda: window.output is not None and window.output.request.source.n_points == 700,
                    timeout=60_000)
    assert window.state.source.name.startswith("sphere") and not window.estimator.busy


# -- 5: one error box at a time ------------------------------------------------------------
def _boxes(window):
    return [b for b in window.findChildren(QMessageBox) if b.isVisible()]


def test_repeated_errors_share_one_box(make_window, qtbot):
    two = CloudSource(name="two points", points=np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    window = make_window(k_auto=False, k=12)
    window.dialogs = True  # as the application runs

    def errors():
        return [n for n in window.notifier.history if n.level == "error"]

    window.set_source(two)
    qtbot.waitUntil(lambda: len(errors()) == 1, timeout=30_000)
    for k in (20, 30, 40):  # a user trying k values
        window.k_slider.slider.setValue(k)
        qtbot.waitUntil(lambda n=len(errors()): len(errors()) > n, timeout=30_000)
    assert len(errors()) == 4 and len({n.message for n in errors()}) == 1  # every one in the history
    boxes = _boxes(window)
    assert len(boxes) == 1
    assert errors()[0].message in boxes[0].text() and "4 times" in boxes[0].text()
    window.notifier.error("Something else went wrong")  # another error: the same box, its text
    assert _boxes(window) == boxes and boxes[0].text() == "Something else went wrong"
    boxes[0].close()
    qtbot.waitUntil(lambda: not _boxes(window), timeout=5_000)
    window.notifier.error("Something else went wrong")  # closed: the next error opens a box again
    assert len(_boxes(window)) == 1 and _boxes(window)[0].text() == "Something else went wrong"


# -- 6: a fixed k on a tiny cloud explains as automatic k does ------------------------------
def test_fixed_k_on_three_points_says_why_there_is_no_estimate(make_window, qtbot):
    three = CloudSource(name="three", points=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))
    window = make_window(three)  # automatic k
    why = window.output.result.params["degenerate"]
    assert "fewer than the 4" in why
    for k in (20, 4):
        with wait_result(qtbot, window, 30_000) as blocker:
            window.state.set(k_auto=False, k=k)
        assert blocker.args[0].result.params["degenerate"] == why
        assert f"NR k={k}" in window.status_label.text() and f"no estimate: {why}" in window.status_label.text()
    assert not [n for n in window.notifier.history if n.level == "error"]


# -- 7: command-line values out of range are refused ------------------------------------------
@pytest.mark.parametrize("args, named", [
    (["--size", "0x0"], "--size '0x0'"),
    (["--size", "10x10"], "--size '10x10'"),
    (["--size", "100000x900"], "--size '100000x900'"),
    (["--pick", "-3"], "--pick -3"),
    (["--shape", "torus", "--points", "500", "--pick", "500"], "--pick 500"),
    (["--timeout", "0"], "--timeout 0"),
    (["--timeout", "-1"], "--timeout -1"),
    (["--timeout", "nan"], "--timeout nan"),
])
def test_cli_refuses_values_out_of_range(args, named, capsys):
    from app.__main__ import _check_args, build_parser

    parser = build_parser()
    with pytest.raises(SystemExit) as exc:
        _check_args(parser.parse_args(args), parser)
    err = capsys.readouterr().err
    assert exc.value.code == 2 and named in err and "allowed:" in err, err


def test_cli_pick_past_the_last_point_of_a_file_is_refused(tmp_path):
    import core.io

    cloud = tmp_path / "small.xyz"
    core.io.write_cloud(cloud, make_shape("sphere", 300).points)
    out = tmp_path / "shot.png"
    proc = run_app_cli(str(cloud), "--pick", "99999999", "--screenshot", str(out))
    assert proc.returncode == 2, proc.stderr
    assert "--pick 99999999 is out of range for small.xyz; allowed: 0 to 299" in proc.stderr
    assert not out.exists()
