"""XML PolyData (.vtp) cells are never read: damaged cell topology (an ``offsets`` array whose
last value is 10**12 or 4 * 10**9 made VTK allocate that many connectivity entries, and the
failed allocation aborted the process with std::bad_alloc, which no ``except`` catches) and
damaged cell data leave the points readable. Each damaged file is built from a valid one VTK
wrote and read in a subprocess with its address space limited, so that a regression fails
this test instead of ending the test run."""

from __future__ import annotations

import base64
import re
import struct
import tempfile
import zlib
from pathlib import Path

import numpy as np
import pytest

import core
from core.io import CloudFileError

pytest.importorskip("vtkmodules.vtkIOXML")


def _polydata():
    pv = pytest.importorskip("pyvista")
    rng = np.random.default_rng(3)
    n = 30
    poly = pv.PolyData(rng.random((n, 3)), verts=np.column_stack([np.ones(n, int), np.arange(n)]).ravel(),
                       lines=[4, 0, 1, 2, 3], faces=[3, 4, 5, 6, 3, 7, 8, 9], strips=[5, 10, 11, 12, 13, 14])
    poly.point_data["Normals"] = rng.random((n, 3))
    poly.cell_data["cell_id"] = np.arange(poly.n_cells, dtype=np.int32)
    return poly


def _write(path, poly, mode, compressor="None"):
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    writer = vtkXMLPolyDataWriter()
    writer.SetInputData(poly)
    getattr(writer, f"SetCompressorTypeTo{compressor}")()
    {"ascii": writer.SetDataModeToAscii, "Binary": writer.SetDataModeToBinary}.get(mode, writer.SetDataModeToAppended)()
    writer.SetEncodeAppendedData(mode == "Appended")
    writer.SetFileName(str(path))
    assert writer.Write() == 1
    return path


def _decode(data: bytes, start: int, encoded: bool, compressed: bool):
    """(Int64 values, end) of the binary array whose header starts at ``start`` (UInt32 words)."""
    def take(pos, n):  # n bytes from pos: (bytes, position after them)
        chars = -(-n // 3) * 4 if encoded else n
        raw = data[pos : pos + chars]
        return (base64.b64decode(raw)[:n] if encoded else raw), pos + chars

    if not compressed:
        raw, _ = take(start, 4)
        raw, end = take(start, 4 + struct.unpack("<I", raw[:4])[0])
        return np.frombuffer(raw[4:], "<i8").copy(), end
    raw, _ = take(start, 12)
    head, pos = take(start, 4 * (3 + struct.unpack("<I", raw[:4])[0]))
    sizes = struct.unpack(f"<{len(head) // 4}I", head)[3:]
    blob, end = take(pos, sum(sizes))
    cuts = np.cumsum((0, *sizes))
    payload = b"".join(zlib.decompress(blob[a:b]) for a, b in zip(cuts[:-1], cuts[1:]))
    return np.frombuffer(payload, "<i8").copy(), end


def _encode(values, encoded: bool, compressed: bool) -> bytes:
    payload = values.astype("<i8").tobytes()
    if not compressed:
        raw = struct.pack("<I", len(payload)) + payload
        return base64.b64encode(raw) if encoded else raw
    block = zlib.compress(payload)
    head = struct.pack("<4I", 1, len(payload), len(payload), len(block))
    return base64.b64encode(head) + base64.b64encode(block) if encoded else head + block


def _damage(path, section: str, name: str, index: int, value: int):
    """Set value ``index`` of the Int64 array ``name`` in ``<section>``, in the file's own layout.
    An appended array changing its length must be the last one (later offsets are not moved)."""
    data = path.read_bytes()
    element = re.search(rf"<{section}>.*?</{section}>".encode(), data, re.S)
    tag = re.compile(rf'<DataArray[^>]*Name="{name}"[^>]*>'.encode()).search(data, element.start(), element.end())
    compressed = b"compressor=" in data[:300]
    if b'format="ascii"' in tag.group(0):
        stop = data.index(b"<", tag.end())
        values = data[tag.end() : stop].split()
        values[index] = str(value).encode()
        new, start = b" ".join(values), tag.end()
    elif b'format="binary"' in tag.group(0):
        start = tag.end() + len(data[tag.end() :]) - len(data[tag.end() :].lstrip())
        values, stop = _decode(data, start, True, compressed)
        values[index] = value
        new = _encode(values, True, compressed)
    else:
        appended = re.search(rb'<AppendedData encoding="(\w+)">\s*_', data)
        encoded = appended.group(1) == b"base64"
        start = appended.end() + int(re.search(rb'offset="(\d+)"', tag.group(0)).group(1))
        values, stop = _decode(data, start, encoded, compressed)
        values[index] = value
        new = _encode(values, encoded, compressed)
        assert len(new) == stop - start or data[stop:].lstrip().startswith(b"</AppendedData>")
    path.write_bytes(data[:start] + new + data[stop:])
    return path


DAMAGES = [  # (mode, compressor), (section, array, index, value)
    (("ascii", "None"), ("Verts", "offsets", -1, 10 ** 12)),
    (("ascii", "None"), ("Verts", "offsets", -1, 4 * 10 ** 9)),
    (("ascii", "None"), ("Polys", "offsets", -1, 10 ** 12)),
    (("ascii", "None"), ("Verts", "offsets", -1, -5)),
    (("ascii", "None"), ("Lines", "connectivity", 1, 10 ** 12)),
    (("ascii", "None"), ("Strips", "offsets", 0, 7)),
    (("Binary", "None"), ("Verts", "offsets", -1, 10 ** 12)),
    (("Binary", "None"), ("Lines", "offsets", -1, 4 * 10 ** 9)),
    (("Binary", "ZLib"), ("Polys", "offsets", -1, 4 * 10 ** 9)),
    (("Binary", "ZLib"), ("Strips", "connectivity", 0, -(10 ** 12))),
    (("AppendedRaw", "None"), ("Verts", "offsets", -1, 10 ** 12)),
    (("AppendedRaw", "None"), ("Verts", "connectivity", 3, 10 ** 12)),
    (("Appended", "None"), ("Lines", "offsets", -1, 4 * 10 ** 9)),
    (("AppendedRaw", "ZLib"), ("Polys", "offsets", -1, 10 ** 12)),
    (("Appended", "ZLib"), ("Polys", "offsets", -1, 4 * 10 ** 9)),
]


def test_vtp_damaged_cells_leave_the_points_readable(tmp_path, helpers):
    poly, paths = _polydata(), []
    for i, ((mode, compressor), damage) in enumerate(DAMAGES):
        paths.append(_damage(_write(tmp_path / f"d{i}_{mode}.vtp", poly, mode, compressor), *damage))
    before = {path: path.read_bytes() for path in paths}
    answers = helpers.read_in_child(paths)
    for path in paths:
        assert answers[str(path)] == poly.points.tolist(), (path.name, answers[str(path)])
        assert path.read_bytes() == before[path]  # the input is never modified


@pytest.mark.parametrize("old, new", [
    ('NumberOfLines="1"', 'NumberOfLines="1000000000000"'),  # VTK allocated it before reading any data
    ('Name="cell_id" format', 'Name="cell_id" NumberOfComponents="1000000000000" format'),
    ("<CellData", "<CellData><DataArray"),
])
def test_vtp_damaged_cell_counts_and_cell_data_ignored(tmp_path, old, new):
    poly = _polydata()
    path = _write(tmp_path / "a.vtp", poly, "ascii")
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    np.testing.assert_array_equal(core.io.read_cloud(path).points, poly.points)


def test_vtp_damaged_cell_data_header_ignored(tmp_path):
    """A compressed cell-data array whose header declares 2**31 blocks was refused (VTK would
    have allocated them): the cell data are no longer read."""
    poly = _polydata()
    path = _write(tmp_path / "a.vtp", poly, "Binary", "ZLib")
    data = path.read_bytes()
    start = re.search(rb'Name="cell_id"[^>]*>\s*', data).end()
    path.write_bytes(data[:start] + base64.b64encode(struct.pack("<3I", 2 ** 31, 1, 1)) + data[start + 16 :])
    cloud = core.io.read_cloud(path)
    np.testing.assert_array_equal(cloud.points, poly.points)
    np.testing.assert_array_equal(cloud.normals, poly.point_data["Normals"])


def test_vtp_copy_without_cells_is_deleted_and_not_named(tmp_path):
    before = set(Path(tempfile.gettempdir()).glob("darboux-*.vtp"))
    poly = _polydata()
    for mode in ("ascii", "Binary", "AppendedRaw"):
        path = _write(tmp_path / f"{mode}.vtp", poly, mode, "ZLib")
        _damage(path, "Polys", "offsets", -1, -5)  # VTK refused it (in this process: not one that aborts)
        np.testing.assert_array_equal(core.io.read_cloud(path).points, poly.points)
    data = path.read_bytes()  # appended: truncated, refused on reading the copy
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(CloudFileError) as info:
        core.io.read_cloud(path)
    assert info.value.path == str(path) and "darboux-" not in str(info.value), str(info.value)
    assert set(Path(tempfile.gettempdir()).glob("darboux-*.vtp")) == before


@pytest.mark.parametrize("edit, part", [
    (lambda t: t.replace("</Verts>", ""), "its <Verts> element is not closed"),
    (lambda t: t.replace("<Lines>", "<<Lines>"), "its <Lines> element does not follow a tag"),
    (lambda t: t.replace("<Piece", '<Piece a="<"'), "cannot be read without its cells (at b'<Piece"),
    (lambda t: t.replace("<VTKFile", '<!DOCTYPE v [<!ENTITY p "&#60;Polys>">]>\n<VTKFile'),
     "cannot be read without its cells (at b'<!DOCTYPE"),
])
def test_vtp_cells_that_cannot_be_removed_safely_refused(tmp_path, edit, part):
    path = _write(tmp_path / "a.vtp", _polydata(), "ascii")
    path.write_text(edit(path.read_text()))
    with pytest.raises(CloudFileError) as info:
        core.io.read_cloud(path)
    assert part in str(info.value) and "a.vtp" in str(info.value), str(info.value)


def test_vtp_copy_through_memory_where_the_kernel_cannot(tmp_path, monkeypatch):
    poly = _polydata()
    for mode in ("Binary", "AppendedRaw"):
        path = _write(tmp_path / f"{mode}.vtp", poly, mode, "ZLib")
        expected = core.io.read_cloud(path)
        monkeypatch.delattr("os.copy_file_range", raising=False)
        cloud = core.io.read_cloud(path)
        monkeypatch.undo()
        np.testing.assert_array_equal(cloud.points, expected.points)
        np.testing.assert_array_equal(cloud.normals, expected.normals)
