"""Framing of the 3D view: the cloud fills the view above the colour bar, and the sprite
size follows the point spacing on screen (issue 13, "Pictures worth a slide")."""

from pathlib import Path

import numpy as np
import pytest
import pyvista as pv

from app import framing
from app.scene import CloudScene
from app.source import load_file, make_shape

BUNNY = Path(__file__).resolve().parents[2] / "resources" / "bunny.ply"


@pytest.fixture
def scene():
    plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
    s = CloudScene(plotter)
    yield s
    s.close()
    plotter.close()


def _show(scene, points, view):
    scene.set_cloud(points, np.linspace(-1.0, 1.0, len(points)), reset_camera=view)
    scene.set_values(np.linspace(-1.0, 1.0, len(points)), title="H", cmap="RdBu_r", clim=(-1.0, 1.0))
    _render(scene)


def _render(scene):
    scene.plotter.render_window.Render()  # an off-screen Plotter skips render() before show()


def _bar_top(scene) -> float:
    """The colour bar's top edge in display pixels, from the actor itself."""
    bar = scene._bar
    height = scene.plotter.window_size[1]
    y0 = bar.GetPositionCoordinate().GetValue()[1]
    y1 = bar.GetPosition2Coordinate().GetValue()[1]
    return (y0 + min(y1, bar.GetMaximumHeightInPixels() / height)) * height


def _sprite_bounds(scene):
    x, y = scene.display_coords(np.arange(len(scene.points)))
    r = 0.5 * scene.sprite_size
    return x.min() - r, x.max() + r, y.min() - r, y.max() + r


@pytest.mark.parametrize("name, view", [("cube", "oblique"), ("sphere", "oblique"), ("torus", "oblique"),
                                        ("bunny", "front"), ("small cube", "xz")])
def test_cloud_fills_the_view_above_the_colour_bar(scene, name, view):
    if name == "bunny":
        points = load_file(BUNNY).points
    else:
        points = make_shape(name.split()[-1], 2000).points
        if name.startswith("small"):
            points = 1e-3 * points + 50.0  # tiny and far from the origin
    _show(scene, points, view)
    width, height = scene.plotter.window_size
    x0, x1, y0, y1 = _sprite_bounds(scene)
    bar_top = _bar_top(scene)
    assert bar_top > 0.08 * height  # the bar is where the scene puts it
    assert y0 > bar_top, (y0, bar_top)  # never over the colour bar
    assert x0 >= 0 and x1 <= width and y1 <= height  # whole cloud in view
    # fills the free part: the limiting direction to within the margins
    fill = max((x1 - x0) / width, (y1 - y0) / (height - 2 * bar_top))
    assert fill > 0.85, fill


def test_fit_view_and_a_resize_keep_the_frame(scene):
    _show(scene, make_shape("cube", 2000).points, "oblique")
    cam = scene.plotter.camera
    cam.position = tuple(np.array(cam.focal_point) + 10.0 * (np.array(cam.position) - np.array(cam.focal_point)))
    scene.fit_view()
    _render(scene)
    assert _sprite_bounds(scene)[2] > _bar_top(scene)
    scene.plotter.window_size = (500, 700)  # narrower, nobody touched the camera: refitted
    _render(scene)
    x0, x1, y0, _ = _sprite_bounds(scene)
    assert x0 >= 0 and x1 <= 500 and y0 > _bar_top(scene)
    cam.azimuth = 30.0  # the user turned the camera: a resize leaves it alone
    moved = cam.position
    scene.plotter.window_size = (900, 700)
    _render(scene)
    assert cam.position == moved


def test_sprite_size_follows_the_spacing_and_the_user_factor(scene):
    sizes = {}
    for n in (300, 2000, 20000):
        _show(scene, make_shape("sphere", n).points, "oblique")
        sizes[n] = scene.sprite_size
        assert scene._actor.prop.point_size == pytest.approx(sizes[n])
    # a sphere of n points: the spacing goes as 1 / sqrt(n); sprites stay in range
    assert sizes[300] == framing.SPRITE_MAX  # very sparse: big discs, capped
    assert sizes[2000] / sizes[20000] == pytest.approx(np.sqrt(10), rel=0.15)
    assert sizes[20000] > 2.0 * framing.SPRITE_MIN
    # sprites about cover the gaps: their diameter is the spacing seen on screen (x 1.5)
    x, y = scene.display_coords(np.arange(len(scene.points)))
    seen = framing.cloud_spacing(np.c_[x, y, np.zeros_like(x)])
    assert scene.sprite_size > 1.2 * seen
    scene.set_point_size(10.0)  # the user's control: twice the default, twice the sprites
    _render(scene)
    assert scene.sprite_size == pytest.approx(2.0 * sizes[20000], rel=1e-3)
    cam = scene.plotter.camera
    cam.zoom(0.5)  # farther (a wider view angle): the points crowd together, the sprites shrink with them
    _render(scene)
    assert 0.4 * 2.0 * sizes[20000] < scene.sprite_size < 0.6 * 2.0 * sizes[20000]
    cam.zoom(4.0)  # closer than the fit: the points spread apart, the sprites keep the fitted size
    _render(scene)
    assert scene.sprite_size == pytest.approx(2.0 * sizes[20000], rel=0.01)


def test_cloud_spacing_of_a_grid():
    g = np.stack(np.meshgrid(np.arange(300.0), np.arange(300.0), [0.0]), axis=-1).reshape(-1, 3) * 0.01
    g[::7] += 0.001 * np.random.default_rng(1).normal(size=g[::7].shape)
    assert framing.cloud_spacing(g) == pytest.approx(0.01, rel=0.05)  # 20k queries against all points
    assert framing.cloud_spacing(g[:1]) == 0.0 and framing.cloud_spacing(np.full((5, 3), np.nan)) == 0.0


def test_a_still_frame_draws_at_most_the_budget_with_sprites_grown_to_cover(scene):
    points = make_shape("sphere", 4000).points
    values = np.linspace(-1.0, 1.0, len(points))
    _show(scene, points, "oblique")
    full_size = scene.sprite_size
    assert scene._cloud.n_points == 4000
    scene.lod.budget = 1000
    scene.set_cloud(points + 0.0, values, reset_camera="oblique")  # a new array: rebuilt with the budget
    scene.set_values(values, title="H", cmap="RdBu_r", clim=(-1.0, 1.0))
    _render(scene)
    drawn = scene.drawn
    assert scene._cloud.n_points == len(drawn) == 1000 and np.all(np.diff(drawn) > 0)
    assert np.array_equal(scene._cloud.points, points[drawn])
    assert np.array_equal(scene._cloud.point_data["values"], values[drawn])
    # a quarter of the density: sprites twice as wide (spacing ~ 1 / sqrt(density))
    assert scene.sprite_size == pytest.approx(2.0 * full_size, rel=0.15)
    # a click picks among the points drawn
    x, y = scene.display_coords(drawn[10])
    assert scene.pick(float(x[0]), float(y[0])) in set(drawn.tolist())


def test_cloud_geometry_ignores_non_finite_rows_and_nests_its_subsets():
    from app.geometry import CloudGeometry

    points = make_shape("cube", 3000).points.copy()
    points[::7] = np.nan
    g = CloudGeometry.of(points)
    finite = np.isfinite(points).all(axis=1)
    assert g.n_points == 3000 and set(g.order.tolist()) == set(np.flatnonzero(finite).tolist())
    lo, hi = points[finite].min(axis=0), points[finite].max(axis=0)
    assert np.allclose(g.centre, 0.5 * (lo + hi)) and g.radius == pytest.approx(0.5 * np.linalg.norm(hi - lo))
    assert finite[g.fit_index].all() and g.spacing > 0
    small, large = g.subset(100), g.subset(1000)
    assert len(small) == 100 and set(small) <= set(large)  # the moving stand-in is part of the still frame
    assert np.array_equal(CloudGeometry.of(points[1:6]).subset(10), np.arange(5))  # all finite: all drawn
    empty = CloudGeometry.of(np.full((4, 3), np.nan))
    assert empty.radius == 1.0 and len(empty.subset(10)) == 0


def test_visible_subset_keeps_the_frustum_and_the_earliest_in_the_drawing_order():
    from app.detail import visible_subset

    points = np.random.default_rng(1).uniform(-2.0, 2.0, size=(5000, 3))
    order = np.random.default_rng(2).permutation(5000)
    inside = np.flatnonzero((np.abs(points) <= 1.0).all(axis=1))  # identity: clip = world, w = 1
    chosen, seen = visible_subset(points, np.eye(4), order, budget=10_000)
    assert seen == len(inside) and np.array_equal(chosen, inside)
    chosen, seen = visible_subset(points, np.eye(4), order, budget=100)
    rank = np.argsort(order)
    assert seen == len(inside) and len(chosen) == 100 and set(chosen) <= set(inside)
    assert rank[chosen].max() < np.sort(rank[inside])[100]  # the first 100 of them in the order


def test_zoomed_in_the_still_budget_goes_to_the_points_in_view(scene, qtbot):
    points = make_shape("plane", 8000).points
    scene.lod.budget = 1000
    _show(scene, points, "xy")
    uniform = scene.drawn.copy()
    scene.plotter.camera.Dolly(8.0)  # an eighth of the width: a few % of the plane in view
    scene.plotter.renderer.ResetCameraClippingRange()  # as the interactor's zoom does
    _render(scene)
    before = scene.drawn
    scene.detail.request()  # what the end of a drag or zoom does
    qtbot.waitUntil(lambda: scene.drawn is not before, timeout=10_000)
    x, y = scene.display_coords(np.arange(len(points)))
    width, height = scene.plotter.window_size
    in_view = np.flatnonzero((x >= 0) & (x <= width) & (y >= 0) & (y <= height))
    assert 200 < len(in_view) < 1000 and set(scene.drawn) == set(in_view)  # every point in view is drawn
    assert len(np.intersect1d(uniform, in_view)) < 0.3 * len(in_view)  # the uniform subset drew few of them
    scene.plotter.camera.Dolly(0.125)  # back out: the same uniform subset as before
    scene.plotter.renderer.ResetCameraClippingRange()
    _render(scene)
    before = scene.drawn
    scene.detail.request()
    qtbot.waitUntil(lambda: scene.drawn is not before, timeout=10_000)
    assert np.array_equal(scene.drawn, uniform)
