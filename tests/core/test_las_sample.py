"""core.io.las_sample: a bounded, evenly spread subsample of a LAS/LAZ file, whole or in a box."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.io.cloud import CloudFileError
from core.io.las_sample import sample_las

laspy = pytest.importorskip("laspy")


@pytest.fixture(scope="module", params=[3, 6])
def scan(tmp_path_factory, request):
    """5000 points with a field; point format 6 (LAS 1.4) is a layered LAZ, read in two passes."""
    rng = np.random.default_rng(1)
    pts = rng.uniform(0, 10, (5000, 3))
    pts = pts[np.argsort(pts[:, 0])]  # in "scan order": a box touches few LAZ chunks
    header = laspy.LasHeader(point_format=request.param, version="1.2" if request.param < 6 else "1.4")
    header.scales, header.offsets = np.full(3, 1e-3), np.zeros(3)
    header.add_extra_dims([laspy.ExtraBytesParams(name="k1", type=np.float64)])
    las = laspy.LasData(header)
    las.x, las.y, las.z = pts.T
    las.k1 = np.arange(5000, dtype=float)
    path = tmp_path_factory.mktemp("sample") / "scan.laz"
    las.write(str(path))
    return path, np.asarray(laspy.read(path).xyz)


def test_the_whole_file_gives_every_nth_point_within_the_budget(scan):
    path, xyz = scan
    s = sample_las(path, 600, names=["k1"], chunk=700)
    assert s.stride == 9 and s.matched == 5000 and len(s.points) == 556  # ceil(5000 / 600) = 9
    np.testing.assert_array_equal(s.rows, np.arange(0, 5000, 9))
    np.testing.assert_array_equal(s.points, xyz[s.rows])
    np.testing.assert_array_equal(s.fields["k1"], s.rows.astype(float))  # the fields of the same points


@pytest.mark.parametrize("budget", [1, 37, 400, 10_000])
def test_a_box_keeps_every_stride_th_point_inside_whatever_the_chunks(scan, budget, monkeypatch):
    monkeypatch.setattr("core.io.las_sample.BLOCK", 450)  # the second pass seeks past untouched blocks
    path, xyz = scan
    lo, hi = np.array([2.0, 1.0, 0.0]), np.array([6.0, 4.5, 10.0])
    inside = np.flatnonzero(((xyz >= lo) & (xyz <= hi)).all(axis=1))
    s = sample_las(path, budget, names=["k1"], box=(lo, hi), chunk=333)
    assert s.matched == len(inside) and len(s.points) <= budget
    np.testing.assert_array_equal(s.rows, inside[:: s.stride])  # uniform over the matches, in file order
    assert s.stride == 1 or len(inside[:: s.stride // 2]) > budget  # no thinner than it had to be
    np.testing.assert_array_equal(s.points, xyz[s.rows])
    np.testing.assert_array_equal(s.fields["k1"], s.rows.astype(float))


def test_bad_arguments_and_files_are_named(scan, tmp_path):
    path, _ = scan
    with pytest.raises(ValueError, match="no dimension 'k9'"):
        sample_las(path, 10, names=["k9"])
    with pytest.raises(ValueError, match="budget"):
        sample_las(path, 0)
    with pytest.raises(ValueError, match="box"):
        sample_las(path, 10, box=([1, 1, 1], [0, 0, 0]))
    cut = tmp_path / "cut.laz"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size * 2 // 3])
    with pytest.raises(CloudFileError, match=r"cut\.laz.*(truncated|unreadable)"):
        sample_las(cut, 10)
    cancel = lambda fraction, stage: False  # noqa: E731
    with pytest.raises(core.Cancelled, match="cancelled"):
        sample_las(path, 10, progress=cancel)
