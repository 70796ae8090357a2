"""float32 coordinates: fine where float32 resolves the spacing, all-invalid with the reason
(core.degenerate) where its step at the coordinates' magnitude is a large share of it."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core import degenerate, shapes
from core.cli import main

UTM = np.array([500000.0, 4200000.0, 300.0])


@pytest.fixture(scope="module")
def sphere():
    return shapes.sphere(3000, seed=0)


@pytest.mark.parametrize("k", [15, "auto"])
def test_float32_sphere_at_the_origin_is_estimated(sphere, k):
    r = core.estimate(sphere.points.astype(np.float32), k=k)
    ref = core.estimate(sphere.points, k=k)
    assert "degenerate" not in r.params and r.valid.mean() > 0.99
    assert np.median(r.k1[r.valid]) == pytest.approx(np.median(ref.k1), abs=1e-3)


@pytest.mark.parametrize("k", [15, "auto"])
def test_float32_sphere_at_utm_is_flagged(sphere, k):
    r = core.estimate((sphere.points + UTM).astype(np.float32), k=k)
    assert len(r) == 3000 and not r.valid.any() and np.isnan(r.k1).all()
    why = r.params["degenerate"]
    assert "float32" in why and "step 0.5" in why and "re-centre" in why


def test_float64_at_utm_and_whole_number_grids_are_not_flagged(sphere):
    r = core.estimate(sphere.points + UTM, k=15)
    assert "degenerate" not in r.params and r.valid.all()
    # whole-number coordinates are float32 values too, but float32 did not round them
    ij = np.stack(np.meshgrid(np.arange(60.0), np.arange(60.0)), -1).reshape(-1, 2)
    grid = np.column_stack([ij, (ij[:, 0] % 3)]) + UTM
    assert degenerate.reason(grid, 3) is None
    assert degenerate.reason(grid.astype(np.float32).astype(np.float64), 3) is None


def test_float32_fine_for_its_spacing_is_not_flagged(sphere):
    """A 100 m sphere 1 km from the origin: float32's step (6e-5) is far below the spacing."""
    pts = (sphere.points * 100 + [1000.0, 2000.0, 50.0]).astype(np.float32)
    assert degenerate.reason(pts.astype(np.float64), 3) is None
    # at 1e5, float32's step 0.0078 is ~1/5 of the unit sphere's spacing: rounding the fits take as noise
    near = (sphere.points + [1e5, 0, 0]).astype(np.float32).astype(np.float64)
    assert degenerate.reason(near, 3) is None
    # at 4e6 it is 0.5, 8x the spacing: the sphere is sliced into planes
    far = (sphere.points + [4e6, 0, 0]).astype(np.float32).astype(np.float64)
    assert "float32" in degenerate.reason(far, 3)


@pytest.mark.parametrize("offset", [0.0, 1e6, 9e6, 1.2e7, 2e7])
def test_a_whole_millimetre_cloud_is_estimated_wherever_it_lies(offset):
    """Whole numbers in [2^23, 2^24) are float32 values with float32's step 1, so a cloud in
    whole millimetres 9-17 km from the origin was refused as float32-rounded (the same cloud
    1-8 km out was estimated): a grid of its own is never nearer than its step."""
    torus = shapes.torus(6000, seed=0)
    mm = np.round(torus.points * 40.0) + offset  # R = 80 mm, spacing ~3 mm, whole millimetres
    res = core.estimate(mm, k=15)
    assert "degenerate" not in res.params and res.valid.mean() > 0.99


def test_arguments_are_still_checked_first(sphere):
    pts = (sphere.points + UTM).astype(np.float32)
    with pytest.raises(ValueError, match="k must be an integer"):
        core.estimate(pts, k="big")
    with pytest.raises(ValueError, match="method"):
        core.estimate(pts, k=15, method="nope")


def test_binary_float_ply_at_utm_is_flagged_by_the_cli(sphere, tmp_path, capsys):
    """A binary PLY with `property float x/y/z` holds float32: read as float64, the values
    are still on float32's grid, and the CLI says why nothing was estimated."""
    pts = (sphere.points + UTM).astype("<f4")
    path = tmp_path / "utm.ply"
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(pts)}\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n")
    path.write_bytes(header.encode() + pts.tobytes())
    assert main(["estimate", str(path), "-o", str(tmp_path / "out.ply"), "--k", "15"]) == 0
    text = capsys.readouterr().out
    assert "invalid points: 3000" in text and "no estimate: the coordinates are float32 values" in text


def test_a_cloud_rounded_onto_a_few_places_in_every_axis_is_flagged(sphere):
    """Far from the origin in every axis float32's step (1 at 1e7) is coarser than the whole
    unit sphere: its places are a step apart, as a whole-number grid's are, and only the
    copies (3000 points on a few dozen places) tell that rounding made them."""
    pts = (sphere.points + 1e7).astype(np.float32).astype(np.float64)
    assert "float32" in degenerate.reason(pts, 3)
