"""E57 scans read by :func:`core.io.read_cloud`: every scan in world coordinates, the
scanner position of each point's scan as its viewpoint, and hostile files refused."""

from __future__ import annotations

import random
import struct
import sys

import numpy as np
import pytest

from core.io import describe, read_cloud
from core.io.e57 import _dtype
from core.tiled.source import open_source
from io_testutils import refused

pye57 = pytest.importorskip("pye57")

C45 = np.cos(np.pi / 4)
TURN_Z = np.array([C45, 0.0, 0.0, C45])  # 90 degrees about z: (x, y, z) -> (-y, x, z)
IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
#: 24 points whose coordinates float32 (pye57 writes them so) holds exactly
GRID = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0), np.arange(2.0) / 2), axis=-1).reshape(-1, 3)


def _columns(points, **extra):
    return {"cartesianX": points[:, 0], "cartesianY": points[:, 1], "cartesianZ": points[:, 2], **extra}


def _write(path, *scans):
    """An E57 file of ``scans``: (columns, translation, rotation) each."""
    e57 = pye57.E57(str(path), mode="w")
    for data, translation, rotation in scans:
        e57.write_scan_raw(data, translation=np.asarray(translation, float), rotation=np.asarray(rotation, float))
    e57.close()
    return path


def _crc32c(data: bytes) -> int:
    crc = 0xFFFFFFFF
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0x82F63B78 if crc & 1 else crc >> 1
    return crc ^ 0xFFFFFFFF


def _logical(raw: bytes) -> bytearray:
    """The file's bytes without the CRC-32C ending each 1024-byte page."""
    return bytearray(b"".join(raw[i:i + 1020] for i in range(0, len(raw), 1024)))


def _paged(data: bytearray) -> bytes:
    """Logical bytes (their header's file length set) in pages, each with its checksum, as libE57 writes them."""
    data = data + bytes(-len(data) % 1020)
    struct.pack_into("<Q", data, 16, len(data) // 1020 * 1024)
    pages = [bytes(data[i:i + 1020]) for i in range(0, len(data), 1020)]
    return b"".join(page + struct.pack(">I", _crc32c(page)) for page in pages)


def _edit(path, old: bytes, new: bytes):
    """Replace ``old`` by ``new`` in the file's logical bytes: in the XML, at the end, by any
    length, or in the binary data by as many bytes; the checksums and lengths rewritten."""
    raw = path.read_bytes()
    xml_at, xml_length = struct.unpack_from("<QQ", raw, 24)
    xml_start = xml_at // 1024 * 1020 + xml_at % 1024
    data = _logical(raw)[:xml_start + xml_length]
    assert old in data
    data = bytearray(data.replace(old, new))
    struct.pack_into("<Q", data, 32, len(data) - xml_start)
    path.write_bytes(_paged(data))
    return path


def test_scans_in_world_coordinates_with_their_scanner_as_viewpoint(tmp_path):
    near, far = GRID, GRID[:10] * 2
    t0, t1 = np.array([1.0, 2.0, 3.0]), np.array([-5.0, 0.5, 1.0])
    path = _write(tmp_path / "two.e57", (_columns(near), t0, TURN_Z), (_columns(far), t1, IDENTITY))
    cloud = read_cloud(path)
    turned = np.column_stack([-near[:, 1], near[:, 0], near[:, 2]])
    np.testing.assert_allclose(cloud.points, np.vstack([turned + t0, far + t1]), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(cloud.viewpoints, np.vstack([np.tile(t0, (len(near), 1)), np.tile(t1, (10, 1))]))
    assert cloud.fields["scan"].dtype == np.int32
    np.testing.assert_array_equal(cloud.fields["scan"], [0] * len(near) + [1] * 10)
    assert cloud.format == "e57" and cloud.normals is None and set(cloud.fields) == {"scan"}


def test_a_scan_without_pose_is_seen_from_the_origin_and_a_non_unit_quaternion_rotates_as_its_unit_one(tmp_path):
    path = _write(tmp_path / "q.e57", (_columns(GRID), [0.0, 0.0, 0.0], 3 * TURN_Z))
    _edit(path, b"pose", b"posX")  # no pose
    assert read_cloud(path).viewpoints.tolist() == [[0.0, 0.0, 0.0]] * len(GRID)
    np.testing.assert_array_equal(read_cloud(path).points, GRID)
    turned = read_cloud(_write(tmp_path / "q3.e57", (_columns(GRID), [0.0, 0.0, 0.0], 3 * TURN_Z))).points
    np.testing.assert_allclose(turned, np.column_stack([-GRID[:, 1], GRID[:, 0], GRID[:, 2]]), rtol=0, atol=1e-12)


def test_intensity_and_colours_kept_when_every_scan_has_them(tmp_path):
    rng = np.random.default_rng(0)
    n = len(GRID)
    colours = {c: rng.integers(0, 256, n).astype(np.uint8) for c in ("colorRed", "colorGreen", "colorBlue")}
    intensity = rng.random(n).astype(np.float32)
    both = _write(tmp_path / "both.e57", (_columns(GRID, intensity=intensity, **colours), [0, 0, 0], IDENTITY),
                  (_columns(GRID, intensity=intensity[::-1].copy(), **colours), [1, 0, 0], IDENTITY))
    cloud = read_cloud(both)
    for name, stored in (("red", "colorRed"), ("green", "colorGreen"), ("blue", "colorBlue")):
        assert cloud.fields[name].dtype == np.uint8  # the names and type of PLY's colours
        np.testing.assert_array_equal(cloud.fields[name], np.tile(colours[stored], 2))
    assert cloud.fields["intensity"].dtype == np.float32
    np.testing.assert_array_equal(cloud.fields["intensity"], np.concatenate([intensity, intensity[::-1]]))
    one = _write(tmp_path / "one.e57", (_columns(GRID, intensity=intensity, **colours), [0, 0, 0], IDENTITY),
                 (_columns(GRID, intensity=intensity), [1, 0, 0], IDENTITY))
    assert set(read_cloud(one).fields) == {"intensity", "scan"}  # the second scan has no colours


def test_integer_fields_kept_in_the_smallest_type_of_their_declared_range(tmp_path):
    libe57 = pye57.libe57  # the writer stores colours as 0..255; scanners also store 16-bit ones
    image = libe57.ImageFile(str(tmp_path / "w.e57"), "w")
    try:
        for (low, high), dtype in {(0, 255): "u1", (0, 65535): "u2", (-1, 1): "i1", (0, 70000): "i8"}.items():
            assert _dtype(libe57.IntegerNode(image, low, low, high), libe57) == dtype
        assert _dtype(libe57.FloatNode(image, 0.5), libe57) == "f8"
        scan = libe57.StructureNode(image)
        scan.set("intensity", libe57.IntegerNode(image, 0, 0, 4095))  # a 12-bit intensity: a float as elsewhere
        assert _dtype(scan["intensity"], libe57) == "f4"
    finally:
        image.cancel()


def test_invalid_points_dropped_with_their_viewpoints_and_scan_index(tmp_path):
    state = np.zeros(len(GRID), dtype=np.int8)
    state[[0, 5, 7]] = [1, 2, 1]  # direction only, invalid
    path = _write(tmp_path / "inv.e57", (_columns(GRID), [0, 0, 9], IDENTITY),
                  (_columns(GRID, cartesianInvalidState=state), [0, 0, -9], IDENTITY))
    cloud = read_cloud(path)
    kept = np.flatnonzero(state == 0)
    np.testing.assert_array_equal(cloud.points, np.vstack([GRID + [0, 0, 9], GRID[kept] + [0, 0, -9]]))
    assert cloud.viewpoints[len(GRID):].tolist() == [[0, 0, -9]] * len(kept)
    assert (cloud.fields["scan"] == 1).sum() == len(kept)
    info = describe(path)
    assert info["n_points"] == len(GRID) + len(kept) and info["format"] == "e57" and "scan" in info["fields"]


def test_spherical_scan_converted_then_placed_by_its_pose(tmp_path):
    rae = np.column_stack([np.linspace(1, 5, 12), np.linspace(-3, 3, 12), np.linspace(-1.5, 1.5, 12)])
    rae = rae.astype(np.float32).astype(np.float64)  # as stored
    state = np.zeros(12, dtype=np.int8)
    state[3] = 2
    path = _write(tmp_path / "sph.e57", (_columns(rae, cartesianInvalidState=state), [0, 0, 2], TURN_Z))
    for old, new in ((b"cartesianX", b"sphericalRange"), (b"cartesianY", b"sphericalAzimuth"),
                     (b"cartesianZ", b"sphericalElevation"), (b"cartesianInvalidState", b"sphericalInvalidState")):
        _edit(path, old, new)
    r, azimuth, elevation = rae[state == 0].T
    local = np.column_stack([r * np.cos(elevation) * np.cos(azimuth), r * np.cos(elevation) * np.sin(azimuth),
                             r * np.sin(elevation)])
    world = np.column_stack([-local[:, 1], local[:, 0], local[:, 2] + 2])
    np.testing.assert_allclose(read_cloud(path).points, world, rtol=0, atol=1e-12)


def test_tiled_source_reads_the_same_points_and_viewpoints(tmp_path):
    state = np.zeros(len(GRID), dtype=np.int8)
    state[2] = 2
    path = _write(tmp_path / "tiles.e57", (_columns(GRID, cartesianInvalidState=state), [1, 2, 3], TURN_Z),
                  (_columns(GRID), [0, 0, 0], IDENTITY))
    cloud, source = read_cloud(path), open_source(path)
    chunks = list(source.chunks(chunk=7))
    assert source.has_views and source.count == 2 * len(GRID)  # declared, the invalid point too
    assert [start for start, *_ in chunks] == list(np.cumsum([0] + [len(c[1]) for c in chunks[:-1]]))
    np.testing.assert_array_equal(np.vstack([c[1] for c in chunks]), cloud.points)
    np.testing.assert_array_equal(np.vstack([c[3] for c in chunks]), cloud.viewpoints)


def _scan(path, points=GRID, rotation=IDENTITY, **extra):
    return _write(path, (_columns(points, **extra), [1.0, 2.0, 3.0], rotation))


def _patched_coordinate(path, value: float):
    """A scan whose point 4 has x = ``value`` (a float32 the writer refuses, patched in)."""
    points = GRID.copy()
    points[4, 0] = 12345.5
    return _edit(_scan(path, points), struct.pack("<f", 12345.5), struct.pack("<f", value))


def _flipped(path):
    raw = bytearray(_scan(path).read_bytes())
    raw[len(raw) // 2] ^= 0x10
    path.write_bytes(raw)
    return path


def _all_invalid(path):
    """A scan's states 0 and 1 (all the writer takes: it bounds the valid points) read as 1 and 2."""
    state = np.ones(len(GRID), dtype=np.int8)
    state[0] = 0
    return _edit(_scan(path, cartesianInvalidState=state), b'InvalidState type="Integer" minimum="0" maximum="1"/>',
                 b'InvalidState type="Integer" minimum="1" maximum="2">1</cartesianInvalidState>')


def _no_scans(path):
    pye57.E57(str(path), mode="w").close()
    return path


HOSTILE = {
    "ply bytes": (lambda p: p.write_bytes(b"ply\nformat ascii 1.0\n" + b"0 0 0\n" * 500) and p,
                  "its content is a .ply file, not .e57: rename it to .ply"),
    "four bytes": (lambda p: p.write_bytes(b"ASTM") and p, "is not an E57 file"),
    "truncated": (lambda p: p.write_bytes(_scan(p).read_bytes()[:3000]) and p, "is not a readable E57 file"),
    "flipped byte": (_flipped, "checksum mismatch"),
    "no scans": (_no_scans, "contains no points (the file holds no scans)"),
    "all invalid": (_all_invalid, "contains no points: all 24 are marked invalid"),
    "nan": (lambda p: _patched_coordinate(p, np.nan), "1 of 24 points have non-finite coordinates", "at point 4"),
    "inf": (lambda p: _patched_coordinate(p, -np.inf), "1 of 24 points have non-finite coordinates"),
    "count beyond memory": (lambda p: _edit(_scan(p), b'recordCount="24"', b'recordCount="100000000000000"'),
                            "declares 100000000000000 points in 1 scan:", "memory available"),
    "no coordinates": (lambda p: _edit(_scan(p), b"cartesianX", b"cartesianQ"),
                       "scan 0 has neither cartesian (cartesianX/Y/Z) nor spherical", "cartesianQ, cartesianY"),
    "zero quaternion": (lambda p: _scan(p, rotation=np.zeros(4)),
                        "scan 0's pose has the rotation quaternion (0, 0, 0, 0)"),
    "negative count": (lambda p: _edit(_scan(p), b'recordCount="24"', b'recordCount="-24"'),
                       "scan 0 declares a negative number of points (-24)"),
    "text translation": (lambda p: _edit(_scan(p), b'<x type="Float">1</x>', b'<x type="String">one</x>'),
                         "scan 0's pose translation is not 3 finite numbers"),
}


@pytest.mark.parametrize("case", list(HOSTILE))
def test_hostile_file_refused_naming_it_and_the_problem(tmp_path, case):
    make, *parts = HOSTILE[case]
    refused(make(tmp_path / "hostile.e57"), *parts)


def test_count_beyond_the_data_refused_not_waited_for(tmp_path, helpers):
    """libE57 then returns no more records: read in a child process, which a loop waiting for
    them would keep past the helper's timeout."""
    path = _edit(_scan(tmp_path / "more.e57"), b'recordCount="24"', b'recordCount="240"')
    answer = helpers.read_in_child([path])[str(path)]
    assert "more.e57: scan 0 declares 240 points but its data ends after 24" in answer, answer


def test_non_finite_points_dropped_on_request_with_their_viewpoints(tmp_path):
    path = _patched_coordinate(tmp_path / "nan.e57", np.nan)
    with pytest.warns(UserWarning, match="dropped 1 of 24"):
        cloud = read_cloud(path, drop_nonfinite=True)
    np.testing.assert_array_equal(cloud.points, np.delete(GRID, 4, axis=0) + [1, 2, 3])
    assert cloud.viewpoints.shape == (23, 3) and len(cloud.fields["scan"]) == 23


def test_without_pye57_the_message_names_the_extra(tmp_path, monkeypatch):
    path = _scan(tmp_path / "a.e57")
    monkeypatch.setitem(sys.modules, "pye57", None)
    refused(path, "needs the Python package 'pye57'", "pip install 'darboux[big]'")


def test_damaged_files_read_or_refused_naming_them_never_crash(tmp_path, helpers):
    """One byte of 80 copies changed, the checksums rewritten (libE57 refuses a page whose
    checksum fails before parsing it), for its XML parser and decoders to meet the damage;
    read in a child process, where a crash fails this test, not the run."""
    points = np.random.default_rng(0).normal(size=(800, 3))
    raw = _scan(tmp_path / "base.e57", points, TURN_Z, intensity=np.arange(800, dtype=np.float32),
                cartesianInvalidState=(np.arange(800) % 5 == 0).astype(np.int8)).read_bytes()
    rng, paths = random.Random(0), []
    for i in range(80):
        data = _logical(raw)
        data[rng.randrange(48, len(data))] ^= rng.randrange(1, 256)  # past the file header
        paths.append(tmp_path / f"damaged{i}.e57")
        paths[-1].write_bytes(_paged(data))
    answers = helpers.read_in_child(paths)
    answers = [answers[str(path)] for path in paths]
    messages = [answer for answer in answers if isinstance(answer, str)]
    assert all(path.name in answer for path, answer in zip(paths, answers) if isinstance(answer, str)), messages
    assert len(messages) >= 5 and len(answers) - len(messages) >= 5, messages


def test_an_e57_cloud_faces_its_scanners_in_estimate_and_the_cli(tmp_path):
    """Two scans of a sphere, one from outside over its top, one from its centre of its
    bottom, each stored in its scanner's frame: core.estimate of the read cloud, and
    darboux-cli on the file, face each point toward the scanner that saw it (what
    orientation=views does): out on the top, in on the bottom, not all outward."""
    import core
    from core.cli import main

    s = core.shapes.sphere(4000, radius=1.0, seed=2)
    views = np.array([[0.0, 0.0, 5.0], [0.0, 0.0, 0.0]])
    seen = (s.points[:, 2] > 0.25, s.points[:, 2] < -0.25)  # the outer scanner's horizon is at z = 0.2
    path = _write(tmp_path / "sphere.e57", *((_columns(s.points[seen[i]] - views[i]), views[i], IDENTITY)
                                              for i in (0, 1)))
    cloud = read_cloud(path)
    res = core.estimate(cloud, k=15)
    assert res.params["orientation"] == "viewpoints"
    np.testing.assert_array_equal(res.normals, core.estimate(cloud.points, k=15, orientation=cloud.viewpoints).normals)
    assert (np.einsum("ij,ij->i", res.normals, cloud.viewpoints - cloud.points) > 0).mean() > 0.99
    assert (res.mean[cloud.fields["scan"] == 1] < 0).mean() > 0.99  # the inside: H = -1/R
    out = tmp_path / "out.csv"
    assert main(["estimate", str(path), "-o", str(out), "--k", "15", "--quiet"]) == 0
    written = core.io.read_cloud(out)
    np.testing.assert_allclose(written.normals, res.normals, atol=1e-6)
