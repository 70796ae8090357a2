"""Orientation of the estimated normals in the viewer: the Orientation choice and the CLI flags."""

from __future__ import annotations

import numpy as np
import pytest
from app_testutils import wait_result

from app.source import CloudSource, make_shape


def _bump(n_side: int = 45) -> CloudSource:
    """A plane z = 0 on [-1, 1]^2 with a smooth bump at the centre, without normals."""
    u = np.linspace(-1.0, 1.0, n_side)
    x, y = (a.ravel() for a in np.meshgrid(u, u))
    z = 0.3 * np.exp(-(x**2 + y**2) / 0.1)
    return CloudSource(name="bump", points=np.column_stack([x, y, z]))


def _choose(window, value: str) -> None:
    """The user picks the entry of ``value`` in the Orientation combo."""
    combo = window.orientation_combo
    index = combo.findData(value)
    assert combo.model().item(index).isEnabled()
    combo.setCurrentIndex(index)
    combo.activated.emit(index)  # what a click on the entry sends (also for the entry already chosen)


def _place_camera(window, position, focal=(0.0, 0.0, 1.0)) -> None:
    camera = window.plotter.renderer.GetActiveCamera()
    camera.SetFocalPoint(*focal)
    camera.SetPosition(*position)


def test_viewpoint_inside_a_sphere_turns_the_normals_inward(make_window, qtbot):
    """Outward on a unit sphere: H > 0; toward the camera at (0.0123, 0, 0), inside: every
    valid normal faces the centre and H < 0, in a new request (not a cached orientation)."""
    window = make_window(make_shape("sphere", 1500), use_input_normals=False, k_auto=False)
    first = window.output
    assert first.request.orientation == "auto"
    assert np.nanmean(first.result.mean[first.result.valid]) > 0
    assert "oriented" not in window.status_label.text()

    _place_camera(window, (0.0123456, 0.0, 0.0))
    with wait_result(qtbot, window, 60_000) as blocker:
        _choose(window, "view")
    out = blocker.args[0]
    assert out.request.orientation == pytest.approx((0.0123456, 0.0, 0.0))
    assert isinstance(out.request.orientation, tuple) and hash(out.request)
    res = out.result
    valid = res.valid
    assert valid.mean() > 0.95
    assert np.all(np.einsum("ij,ij->i", res.normals[valid], res.points[valid]) < 0)  # toward the centre
    assert np.nanmean(res.mean[valid]) < 0
    assert "orientation" not in out.reused_stages and "initial" in out.reused_stages
    assert "oriented toward (0.0123, 0, 0)" in window.status_label.text()
    assert "oriented toward (0.0123, 0, 0)" in window.scene._title_actor.GetInput()  # the caption

    with wait_result(qtbot, window, 60_000) as blocker:
        _choose(window, "auto")  # back to the default: outward again
    assert np.nanmean(blocker.args[0].result.mean[blocker.args[0].result.valid]) > 0
    assert "oriented" not in window.status_label.text()


def test_up_orients_a_plane_with_a_bump_to_plus_z(make_window, qtbot):
    """"up (+z)": every valid normal of a floor with a bump has nz > 0; a viewpoint below
    turns them all to nz < 0."""
    window = make_window(_bump(), k_auto=False)
    with wait_result(qtbot, window, 60_000) as blocker:
        _choose(window, "propagate")
    out = blocker.args[0]
    assert out.request.orientation == "propagate"
    assert np.all(out.result.normals[out.result.valid, 2] > 0)
    assert "oriented up (+z)" in window.status_label.text()

    _place_camera(window, (0.0, 0.0, -10.0), focal=(0.0, 0.0, 0.0))
    with wait_result(qtbot, window, 60_000) as blocker:
        _choose(window, "view")
    res = blocker.args[0].result
    assert blocker.args[0].request.orientation == (0.0, 0.0, -10.0)
    assert np.all(res.normals[res.valid, 2] < 0)


def test_keep_needs_the_clouds_normals(make_window, qtbot, torus):
    """"keep the file's normals" is enabled only while the cloud's normals are used; a cloud
    without normals drops a kept choice back to the default."""
    window = make_window(torus, k_auto=False)
    combo = window.orientation_combo
    keep = combo.model().item(combo.findData("keep"))
    assert keep.isEnabled()
    with wait_result(qtbot, window, 60_000) as blocker:
        _choose(window, "keep")
    assert blocker.args[0].request.orientation == "keep"
    assert "file's normals kept" in window.status_label.text()

    with wait_result(qtbot, window, 60_000) as blocker:
        window.normals_check.setChecked(False)
    assert not keep.isEnabled()
    assert blocker.args[0].request.orientation == "auto"
    assert combo.currentData() == "auto"

    window.normals_check.setChecked(True)
    assert keep.isEnabled()
    with wait_result(qtbot, window, 60_000):
        _choose(window, "keep")
    with wait_result(qtbot, window, 60_000) as blocker:
        window.set_source(_bump())
    assert blocker.args[0].request.orientation == "auto"
    assert not keep.isEnabled()


def test_cli_flags_reach_the_request(make_window, qtbot):
    """``--viewpoint`` / ``--orientation`` parse (core's spelling) and reach the request."""
    from app.__main__ import _state_from_args, build_parser

    parser = build_parser()
    args = parser.parse_args(["--viewpoint=-1,2.5,3", "--k", "12"])
    state = _state_from_args(args, parser)
    assert state.orientation == (-1.0, 2.5, 3.0) and "orientation" in state.given
    values = {key: state.get(key) for key in ("orientation", "k", "k_auto")}
    window = make_window(_bump(20), **values)
    assert window.output.request.orientation == (-1.0, 2.5, 3.0)
    assert window.orientation_combo.currentData() == "view"
    assert "oriented toward (-1, 2.5, 3)" in window.status_label.text()

    for flag, expected in (("propagate", "propagate"), ("keep", "keep"), ("auto", "auto")):
        assert _state_from_args(parser.parse_args(["--orientation", flag]), parser).orientation == expected
    assert _state_from_args(parser.parse_args([]), parser).orientation == "auto"


@pytest.mark.parametrize("argv, message", [
    (["--viewpoint", "1,2"], "viewpoint '1,2' must be x,y,z"),
    (["--viewpoint", "a,b,c"], "viewpoint 'a,b,c' must be x,y,z"),
    (["--viewpoint", "1,2,inf"], "must be x,y,z"),
    (["--orientation", "outward-ish"], "invalid choice: 'outward-ish'"),
    (["--orientation", "propagate", "--viewpoint", "0,0,0"], "not allowed with argument"),
])
def test_bad_orientation_flags_are_clear_errors(argv, message, capsys):
    from app.__main__ import build_parser

    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(argv)
    assert exc.value.code == 2
    assert message in capsys.readouterr().err


def test_state_checks_the_orientation():
    from app.state import ViewerState

    state = ViewerState()
    state.set(orientation=[1, 2, 3])
    assert state.orientation == (1.0, 2.0, 3.0)
    for bad in ("outward-ish", (1, 2), (0, 0, float("nan"))):
        with pytest.raises(ValueError):
            state.set(orientation=bad)


def test_a_cloud_with_its_scanners_positions_faces_them_by_default(make_window):
    """A cloud that came with each point's scanner position (an E57 file's poses): the
    default orientation faces every point toward its own scanner, as core.estimate of the
    file's cloud does, and the status line and caption say so."""
    import core

    pts = core.shapes.torus(3000, seed=2).points
    views = np.where((pts[:, 0] > 0)[:, None], [9.0, 0.0, 1.0], [0.0, 0.0, 6.0])
    source = CloudSource(name="two scans", points=pts, viewpoints=views)
    window = make_window(source, use_input_normals=False, k_auto=False)
    res = window.output.result
    assert res.params["orientation"] == "viewpoints"
    req = window.output.request
    alone = core.estimate(pts, k=req.k, method=req.method, passes=req.passes, orientation=views)
    np.testing.assert_array_equal(res.normals, alone.normals)
    assert (np.einsum("ij,ij->i", res.normals, views - pts) > 0).mean() > 0.95
    assert "oriented toward the scanners" in window.status_label.text()
    assert "oriented toward the scanners" in window.scene._title_actor.GetInput()
    assert window.orientation_combo.currentText() == "toward the scanners (default)"
