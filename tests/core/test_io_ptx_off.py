"""Leica PTX scans and Geomview OFF meshes read by :func:`core.io.read_cloud`: PTX scans
placed in world coordinates by their transforms, each point seen from its scanner, missing
returns left out; OFF's keyword variants; hostile files of both refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.io import describe, read_cloud
from core.tiled import estimate_tiled
from io_testutils import refused


def _turn(axis, angle):
    c, s = np.cos(angle), np.sin(angle)
    i, j = {"x": (1, 2), "z": (0, 1)}[axis]
    r = np.eye(3)
    r[i, i], r[i, j], r[j, i], r[j, j] = c, -s, s, c
    return r


def _line(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _scan(world, rotation, scanner, extra=None, *, applied=False, grid=None) -> str:
    """A PTX scan of ``world`` points seen by a scanner at ``scanner`` turned by ``rotation``:
    stored in its own coordinates with the transform (rows multiply row vectors), or already
    placed (``applied``) with an identity transform. ``extra`` rows follow x y z."""
    local = world if applied else (world - scanner) @ rotation
    transform = np.eye(4)
    if not applied:
        transform[:3, :3], transform[3, :3] = rotation.T, scanner
    columns, rows = grid or (len(world), 1)
    head = [str(columns), str(rows), _line(scanner), *map(_line, rotation.T), *map(_line, transform)]
    extra = np.zeros((len(world), 0)) if extra is None else extra
    body = [_line(p) + "".join(f" {v:g}" for v in e) for p, e in zip(local, extra)]
    return "\n".join(head + body) + "\n"


def _sphere_scans():
    """A unit sphere seen from outside over its top and from its centre over its bottom."""
    s = core.shapes.sphere(4000, radius=1.0, seed=2)
    views = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 0.0]])
    seen = (s.points[:, 2] > 0.25, s.points[:, 2] < -0.25)
    return [s.points[m] for m in seen], views, (_turn("z", 0.7) @ _turn("x", 0.3), _turn("z", -1.2))


def test_scans_placed_by_their_transforms_seen_from_their_scanners_and_missing_points_left_out(tmp_path):
    parts, views, turns = _sphere_scans()
    text = ""
    for i, (world, view, turn) in enumerate(zip(parts, views, turns)):
        colour = np.tile([0.5, 10 * i, 20, 30], (len(world), 1))
        world = np.vstack([world[:7], view, world[7:]])  # a missing return: 0 0 0 in the scanner's frame
        text += _scan(world, turn, view, np.vstack([colour[:7], [0.5, 0, 0, 0], colour[7:]]))
    path = tmp_path / "sphere.ptx"
    path.write_text(text)
    cloud = read_cloud(path)
    np.testing.assert_allclose(cloud.points, np.vstack(parts), atol=1e-12)
    np.testing.assert_array_equal(cloud.fields["scan"], np.repeat([0, 1], [len(p) for p in parts]))
    np.testing.assert_array_equal(cloud.viewpoints, np.repeat(views, [len(p) for p in parts], axis=0))
    assert cloud.fields["red"].dtype == np.uint8 and set(cloud.fields["red"]) == {0, 10}
    assert set(cloud.fields["intensity"]) == {0.5} and set(cloud.fields["blue"]) == {30}
    res = core.estimate(cloud, k=15)  # the default faces each point's scanner
    assert res.params["orientation"] == "viewpoints"
    assert (np.einsum("ij,ij->i", res.normals, cloud.viewpoints - cloud.points) > 0).mean() > 0.99
    assert (res.mean[cloud.fields["scan"] == 1] < 0).mean() > 0.99  # seen from inside: H = -1/R
    info = describe(path)
    assert info["n_points"] == len(cloud) and info["n_viewpoints"] == 2 and "scan" in info["fields"]


def test_viewpoint_is_the_registered_position_also_when_the_transform_was_already_applied(tmp_path):
    parts, views, turns = _sphere_scans()
    path = tmp_path / "applied.ptx"
    path.write_text(_scan(parts[0], turns[0], views[0], applied=True))
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, parts[0])
    np.testing.assert_array_equal(cloud.viewpoints, np.broadcast_to(views[0], parts[0].shape))
    assert set(cloud.fields) == {"scan"}  # x y z only


def test_fields_kept_only_where_every_scan_has_them_and_blank_lines_between_scans_read(tmp_path):
    parts, views, turns = _sphere_scans()
    full = np.tile([0.25, 1, 2, 3], (len(parts[0]), 1))
    path = tmp_path / "mixed.ptx"
    path.write_text(_scan(parts[0], turns[0], views[0], full) + "\n\n"
                    + _scan(parts[1], turns[1], views[1], np.full((len(parts[1]), 1), 0.75)) + "\n")
    cloud = read_cloud(path)
    assert set(cloud.fields) == {"intensity", "scan"} and len(cloud) == sum(map(len, parts))


def test_tiled_run_faces_each_scanner_as_in_memory(tmp_path):
    pts = core.shapes.torus(6000, seed=0).points
    views = (np.array([0.0, 0.0, 6.0]), np.array([0.0, 0.0, -6.0]))
    path = tmp_path / "two.ptx"
    path.write_text(_scan(pts[:3000], _turn("z", 0.4), views[0]) + _scan(pts[3000:], np.eye(3), views[1]))
    estimate_tiled(path, tmp_path / "out.ply", k=15, tile_points=700, workers=0)
    out = read_cloud(tmp_path / "out.ply")
    np.testing.assert_allclose(out.points, pts, atol=1e-6)
    for rows, view in ((slice(0, 3000), views[0]), (slice(3000, None), views[1])):
        mem = core.estimate(out.points, k=15, orientation=view)
        np.testing.assert_allclose(out.normals[rows], mem.normals[rows], atol=1e-9)


_HEAD = "2\n2\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
_FOUR = "1 0 0 0.5\n0 1 0 0.5\n0 0 1 0.5\n1 1 1 0.5\n"


@pytest.mark.parametrize("text, parts", [
    (_HEAD + _FOUR[:-10], ("declares 4 points", "only 3 point lines")),
    (_HEAD.replace("2\n2\n", "-2\n2\n", 1) + _FOUR, ("-2 columns",)),
    (_HEAD.replace("2\n2\n", "2.5\n2\n", 1) + _FOUR, ("line 1 (columns)", "integer")),
    (_HEAD.replace("1 0 0 0\n0 1 0 0\n", "1 0 0 0\n1 0 0 0\n") + _FOUR, ("singular",)),
    (_HEAD.replace("0 0 0\n", "0 nan 0\n", 1) + _FOUR, ("line 3 (scanner position)", "finite")),
    (_HEAD + _FOUR.replace(" 0.5\n", " 0.5 7\n"), ("5 numbers",)),
    (_HEAD + _FOUR.replace(" 0.5\n", " 0.5 7 8 300\n"), ("blue value is 300", "0-255")),
    (_HEAD.replace("2\n2\n", "99999\n99999\n", 1) + _FOUR, ("99999 x 99999", "hold at most")),
    (_HEAD + "0 0 0 0.5\n" * 4, ("no points", "missing (0 0 0)")),
    (_HEAD[:28], ("ends inside a scan's header",)),
    (_HEAD + _FOUR.replace("1 1 1", "1 x 1"), ("scan 0's points (from line 11)", "'x'")),
])
def test_hostile_ptx_refused_naming_the_file_and_the_problem(tmp_path, text, parts):
    path = tmp_path / "bad.ptx"
    path.write_text(text)
    refused(path, *parts)


def test_a_good_ptx_of_the_hostile_cases_reads(tmp_path):
    path = tmp_path / "good.ptx"
    path.write_text(_HEAD + _FOUR + _HEAD + _FOUR)
    cloud = read_cloud(path)
    assert len(cloud) == 8 and list(cloud.fields["scan"]) == [0] * 4 + [1] * 4


_OFF_GRID = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"


@pytest.mark.parametrize("text", [
    "OFF\n# a comment\n4 1 0\n" + _OFF_GRID + "3 0 1 2\n",
    "OFF 4 1 0\n" + _OFF_GRID,
    "OFF4 1 0\n" + _OFF_GRID,  # ModelNet's keyword run into the counts
    "\ufeffOFF\n\n4 0 0  # counts\n" + _OFF_GRID,
    "nOFF 3\n4 0 0\n" + _OFF_GRID,
    "off\r\n4 0 0\r\n" + _OFF_GRID.replace("\n", "\r\n"),
    "4OFF\n4 0 0\n0 0 0 1\n2 0 0 2\n0 3 0 3\n0 0 0.5 0.5\n",
])
def test_off_variants_give_the_vertices(tmp_path, text):
    path = tmp_path / "m.off"
    path.write_text(text, encoding="utf-8")
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]))
    assert cloud.normals is None and cloud.fields == {}


def test_off_normals_and_colours_as_integers_or_fractions(tmp_path):
    path = tmp_path / "n.off"
    path.write_text("CNOFF\n2 0 0\n0 0 0 0 0 1 255 0 0 255\n1 0 0 0 1 0 0 128 0 255\n")
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.normals, [[0, 0, 1], [0, 1, 0]])
    assert cloud.fields["red"].dtype == np.uint8 and list(cloud.fields["green"]) == [0, 128]
    path.write_text("COFF\n2 0 0\n0 0 0 1 0 0 1\n1 0 0 0 0.5 0 1\n")
    assert list(read_cloud(path).fields["green"]) == [0, 128]
    path.write_text("COFF\n2 0 0\n0 0 0 1 0 0\n1 0 0 0 900 0\n")
    with pytest.warns(UserWarning, match="colours ignored"):
        assert read_cloud(path).fields == {}


@pytest.mark.parametrize("text, parts", [
    ("OFF BINARY\n", ("binary OFF",)),
    ("PLY\n", ("not an OFF file", "'PLY'")),
    ("OFF\n-4 0 0\n" + _OFF_GRID, ("none negative", "-4 0 0")),
    ("OFF\na b c\n", ("counts", "integers", "'a b c'")),
    ("OFF\n", ("3 integers",)),
    ("nOFF\n4\n1 0 0\n0 0 0 0\n", ("dimension 4",)),
    ("OFF\n5 0 0\n" + _OFF_GRID, ("declares 5 vertices", "only 4 vertex lines")),
    ("OFF\n99999999 0 0\n" + _OFF_GRID, ("declares 99999999 vertices", "hold at most")),
    ("OFF\n4 0 0\n0 0 x\n" + _OFF_GRID[6:], ("malformed vertex lines", "'x'")),
    ("NOFF\n4 0 0\n" + _OFF_GRID, ("hold 3 numbers", "at least 6")),
    ("OFF\n0 0 0\n", ("no points",)),
])
def test_hostile_off_refused_naming_the_file_and_the_problem(tmp_path, text, parts):
    path = tmp_path / "bad.off"
    path.write_text(text)
    refused(path, *parts)
