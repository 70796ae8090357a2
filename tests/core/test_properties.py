"""Property-based tests (hypothesis): on random clouds and on corrupted files, no exception
other than ValueError (CloudFileError is one) or Cancelled escapes, and every point reported
valid is finite."""

from __future__ import annotations

import struct
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import core
from core import Cancelled

FAST = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
FEW = settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ------------------------------------------------------------------------------ estimate

coords = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False, width=64)


@st.composite
def clouds(draw):
    """Random clouds: uniform, on few distinct locations (duplicates), flat, or rescaled."""
    n = draw(st.integers(3, 60))
    kind = draw(st.sampled_from(["random", "duplicates", "flat", "scaled"]))
    pts = draw(hnp.arrays(np.float64, (n, 3), elements=coords))
    if kind == "duplicates":
        pts = pts[draw(hnp.arrays(np.int64, n, elements=st.integers(0, min(n, 4) - 1)))]
    elif kind == "flat":
        pts[:, 2] = draw(coords)
    elif kind == "scaled":
        pts = pts * 10.0 ** draw(st.integers(-310, 300))
    return pts


def _check_result(res, n):
    assert len(res) == n
    v = res.valid
    for name in ("k1", "k2", "mean", "gaussian"):
        assert np.isfinite(getattr(res, name)[v]).all(), name
    for name in ("e1", "e2", "normals"):
        assert np.isfinite(getattr(res, name)[v]).all(), name
    assert (res.k1[v] >= res.k2[v]).all()


@FAST
@given(pts=clouds(), k=st.one_of(st.just("auto"), st.integers(1, 25)),
       method=st.sampled_from(sorted(core.METHODS)), with_normals=st.booleans())
def test_estimate_never_crashes_nor_invents(pts, k, method, with_normals):
    normals = None
    if with_normals:
        normals = np.random.default_rng(0).standard_normal(pts.shape) * 10.0 ** np.random.default_rng(1).integers(
            -5, 300)
    try:
        with np.errstate(all="ignore"):
            res = core.estimate(pts, normals, k=k, method=method)
    except (ValueError, Cancelled):
        return
    _check_result(res, len(pts))


@FAST
@given(pts=clouds(), cancel_at=st.floats(0.0, 1.0))
def test_cancel_anywhere_is_cancelled(pts, cancel_at):
    try:
        res = core.estimate(pts, progress=lambda f, stage: f < cancel_at)
    except (ValueError, Cancelled):
        return
    _check_result(res, len(pts))


# ------------------------------------------------------------------------------ readers

RNG = np.random.default_rng(7)
PTS = RNG.standard_normal((12, 3))
NRM = PTS / np.linalg.norm(PTS, axis=1, keepdims=True)


def _text_rows(points, sep=" "):
    return "".join(sep.join(repr(float(v)) for v in row) + "\n" for row in points)


def _pcd(data: str, body: bytes) -> bytes:
    head = (f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {len(PTS)}\nHEIGHT 1\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(PTS)}\nDATA {data}\n")
    return head.encode() + body


def _stl_binary() -> bytes:
    tri = PTS[:12].reshape(4, 3, 3).astype("<f4")
    rec = np.zeros(4, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = tri
    return b"binary".ljust(80) + struct.pack("<I", 4) + rec.tobytes()


def _via_file(ext, write) -> bytes:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"seed.{ext}"
        write(path)
        return path.read_bytes()


def _las(path):
    import laspy

    las = laspy.LasData(laspy.LasHeader(point_format=3, version="1.2"))
    las.header.scales, las.header.offsets = [0.001] * 3, [0.0] * 3
    las.x, las.y, las.z = PTS.T
    las.write(path)


def _pyvista(path, binary=True):
    import pyvista as pv

    cloud = pv.PolyData(PTS)
    cloud.point_data["Normals"] = NRM
    cloud.save(path, binary=binary)


SEEDS = {
    "ply": lambda: _via_file("ply", lambda p: core.io.write_cloud(p, PTS, normals=NRM)),
    "ply-ascii": lambda: ("ply\nformat ascii 1.0\nelement vertex 12\nproperty float x\nproperty float y\n"
                          "property float z\nproperty uchar red\nend_header\n"
                          + "".join(f"{a} {b} {c} 7\n" for a, b, c in PTS)).encode(),
    "csv": lambda: _via_file("csv", lambda p: core.io.write_cloud(p, PTS, normals=NRM)),
    "xyz": lambda: _text_rows(np.hstack([PTS, NRM])).encode(),
    "pts": lambda: (f"{len(PTS)}\n" + _text_rows(np.hstack([PTS, PTS[:, :1]]))).encode(),
    "pcd": lambda: _pcd("ascii", _text_rows(PTS).encode()),
    "pcd-binary": lambda: _pcd("binary", PTS.astype("<f4").tobytes()),
    "obj": lambda: ("".join(f"v {a} {b} {c}\n" for a, b, c in PTS) + "f 1 2 3\n").encode(),
    "stl": _stl_binary,
    "vtk": lambda: _via_file("vtk", lambda p: _pyvista(p, binary=False)),
    "vtp": lambda: _via_file("vtp", _pyvista),
    "las": lambda: _via_file("las", _las),
    "laz": lambda: _via_file("laz", _las),
}


@st.composite
def corruptions(draw, data: bytes):
    """``data`` truncated, with bytes overwritten, inserted or a block repeated."""
    data = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["truncate", "flip", "insert", "repeat", "digits"]))
        at = draw(st.integers(0, max(0, len(data) - 1)))
        if op == "truncate":
            del data[at:]
        elif op == "flip" and data:
            data[at] = draw(st.integers(0, 255))
        elif op == "insert":
            data[at:at] = draw(st.binary(min_size=1, max_size=16))
        elif op == "repeat":
            data[at:at] = data[at : at + draw(st.integers(1, 64))]
        elif op == "digits":
            data[at:at] = draw(st.sampled_from([b"9" * 20, b"-1", b"1e999", b"nan", b"300", b"1,5", b"\x00"]))
    return bytes(data)


@pytest.mark.parametrize("fmt", sorted(SEEDS))
def test_seed_files_are_read(fmt):
    cloud = _read(SEEDS[fmt](), fmt)
    assert len(cloud) >= 4


def _read(data: bytes, fmt: str):
    ext = fmt.split("-")[0]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"cloud.{ext}"
        path.write_bytes(data)
        cloud = core.io.read_cloud(path)
        assert path.read_bytes() == data  # never modified
        return cloud


@pytest.mark.parametrize("fmt", sorted(SEEDS))
def test_corrupted_files_give_a_cloud_or_a_clear_error(fmt):
    seed = SEEDS[fmt]()

    @FEW
    @given(data=corruptions(seed))
    def check(data):
        try:
            cloud = _read(data, fmt)
        except ValueError as exc:  # CloudFileError: names the file
            assert "cloud." in str(exc)
            return
        assert np.isfinite(cloud.points).all() and cloud.points.shape[1] == 3

    check()
