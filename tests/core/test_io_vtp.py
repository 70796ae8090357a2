"""XML PolyData (.vtp) binary data: every layout VTK writes reads back unchanged, and damaged
block headers of compressed (or uncompressed) binary arrays are refused before VTK acts on
them: VTK allocated what they declared and a failed allocation aborted the process
(std::bad_alloc, which no ``except`` catches: the GUI would have died)."""

from __future__ import annotations

import base64
import re
import struct

import numpy as np
import pytest

import core

pytest.importorskip("vtkmodules.vtkIOXML")

COMPRESSORS = ["None", "ZLib", "LZ4", "LZMA"]
MODES = ["Binary", "Appended", "AppendedRaw"]


def _polydata(n=200):
    pv = pytest.importorskip("pyvista")
    rng = np.random.default_rng(7)
    poly = pv.PolyData(rng.random((n, 3)))
    poly.point_data["Normals"] = rng.random((n, 3))
    poly.point_data["label"] = np.arange(n, dtype=np.int32)
    return poly


def _write(path, poly, compressor="ZLib", mode="Binary", header="UInt32", *, big_endian=False, block=None):
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    writer = vtkXMLPolyDataWriter()
    writer.SetInputData(poly)
    getattr(writer, f"SetCompressorTypeTo{compressor}")()
    writer.SetDataModeToBinary() if mode == "Binary" else writer.SetDataModeToAppended()
    writer.SetEncodeAppendedData(mode == "Appended")
    getattr(writer, f"SetHeaderTypeTo{header}")()
    if big_endian:
        writer.SetByteOrderToBigEndian()
    if block:
        writer.SetBlockSize(block)
    writer.SetFileName(str(path))
    assert writer.Write() == 1
    return path


def _same(cloud, poly):
    np.testing.assert_array_equal(cloud.points, poly.points)
    np.testing.assert_array_equal(cloud.normals, poly.point_data["Normals"])
    np.testing.assert_array_equal(cloud.fields["label"], poly.point_data["label"])


@pytest.mark.parametrize("header", ["UInt32", "UInt64"])
@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("compressor", COMPRESSORS)
def test_vtp_layouts_vtk_writes_read_unchanged(tmp_path, compressor, mode, header):
    poly = _polydata()
    _same(core.io.read_cloud(_write(tmp_path / "a.vtp", poly, compressor, mode, header)), poly)
    # many blocks (and a partial last one), big-endian
    path = _write(tmp_path / "b.vtp", poly, compressor, mode, header, big_endian=True, block=1000)
    _same(core.io.read_cloud(path), poly)


def test_vtp_saved_by_pyvista_reads_unchanged(tmp_path):
    poly = _polydata()
    for binary in (True, False):
        poly.save(tmp_path / "p.vtp", binary=binary)
        _same(core.io.read_cloud(tmp_path / "p.vtp"), poly)


def _first_array(data: bytes):
    """(start, encoded) of the first binary array's data: inline base64 text or appended data."""
    appended = re.search(rb'<AppendedData encoding="(\w+)">\s*_', data)
    if appended:
        return appended.end(), appended.group(1) == b"base64"
    return re.search(rb'format="binary"[^>]*>\s*', data).end(), True


def _set_words(path, values: dict):
    """Set header words (index -> value) of the file's first binary array, in place, keeping the
    header's length (base64 headers are decoded and encoded again)."""
    data = bytearray(path.read_bytes())
    head = re.search(rb'byte_order="(\w+)" header_type="(\w+)"', data)
    word = (">" if head.group(1) == b"BigEndian" else "<") + ("Q" if head.group(2) == b"UInt64" else "I")
    size = struct.calcsize(word)
    start, encoded = _first_array(bytes(data))
    if b"compressor=" in data[:300]:  # the whole header, encoded on its own
        nbytes = (3 + struct.unpack(word, _decode(data, start, encoded, size))[0]) * size
    else:  # the length word, encoded with the data: whole triplets
        nbytes = -(-size // 3) * 3 if encoded else size
    raw = bytearray(_decode(data, start, encoded, nbytes))
    for index, value in values.items():
        struct.pack_into(word, raw, index * size, value)
    chars = base64.b64encode(bytes(raw)) if encoded else bytes(raw)
    data[start : start + len(chars)] = chars
    path.write_bytes(bytes(data))


def _decode(data, start, encoded, nbytes):
    if not encoded:
        return bytes(data[start : start + nbytes])
    return base64.b64decode(bytes(data[start : start + -(-nbytes // 3) * 4]))[:nbytes]


HOSTILE = [  # (compressor, mode, header type), header words to set, what the message says
    (("ZLib", "Binary", "UInt32"), {3: 0xFFFFFFF0}, ["compressed to 4294967280 bytes", "past the end of the data"]),
    (("LZ4", "AppendedRaw", "UInt64"), {3: 2 ** 62}, [f"compressed to {2 ** 62} bytes", "past the end of the data"]),
    (("LZMA", "Appended", "UInt32"), {3: 10 ** 6}, ["compressed to 1000000 bytes", "past the end of the data"]),
    (("ZLib", "Appended", "UInt32"), {0: 0xFFFFFFFF}, ["4294967295 block(s)", "bytes of header, past the end"]),
    (("LZMA", "Binary", "UInt64"), {0: 2 ** 40}, [f"{2 ** 40} block(s)", "bytes of header, past the end"]),
    (("ZLib", "AppendedRaw", "UInt32"), {1: 0}, ["of 0 bytes", "allowed: a block size above 0"]),
    (("ZLib", "Binary", "UInt32"), {2: 40000}, ["(the last of 40000)", "a last block of at most the block size"]),
    (("ZLib", "AppendedRaw", "UInt64"), {1: 2 ** 40, 2: 0}, [f"{2 ** 40} bytes uncompressed", "allowed: at most "
                                                             "4800 bytes, what the array holds (200 tuples x 3 "
                                                             "components x 8 bytes)"]),
    (("LZ4", "Appended", "UInt64"), {0: 2, 2: 0}, ["65536 bytes uncompressed", "at most 4800 bytes"]),
    (("None", "Binary", "UInt32"), {0: 0xFFFFFFFF}, ["binary data header declares 4294967295 bytes",
                                                     "allowed: at most 4800 bytes"]),
    (("None", "AppendedRaw", "UInt64"), {0: 2 ** 63}, [f"declares {2 ** 63} bytes", "at most 4800 bytes"]),
    (("None", "Appended", "UInt32"), {0: 4808}, ["declares 4808 bytes", "at most 4800 bytes"]),
]


@pytest.mark.parametrize("mode", ["Binary", "Appended"])
@pytest.mark.parametrize("compressor", ["None", "ZLib"])
@pytest.mark.parametrize("extra", [b",", b" ", b"\n"])
def test_vtp_base64_with_a_foreign_character_refused(tmp_path, compressor, mode, extra):
    """VTK's base64 decoder skips nothing, white space included: a character inserted into an
    array's base64 text shifted the values read after it, or left them unwritten (whatever
    memory held: 1e+277 and 8e+291 on two reads of one fuzzed file), without a word."""
    path = _write(tmp_path / "a.vtp", _polydata(), compressor, mode)
    data = path.read_bytes()
    start = _first_array(data)[0]
    at = start + (60 if compressor == "None" else 40)  # past a compressed array's header, inside its data
    path.write_bytes(data[:at] + extra + data[at:])
    with pytest.raises(core.io.CloudFileError, match=re.escape(f"{extra.decode()!r} at character {at - start} of its base64")):
        core.io.read_cloud(path)


_SPELLINGS = {  # each aborted the process (std::bad_alloc) past the double-quote regex that read the tags
    "single_quotes": lambda d: re.sub(rb'="([^"]*)"', rb"='\1'", d),
    "comment_first": lambda d: d.replace(b"<VTKFile", b"<!--" + b"x" * (1 << 17) + b"-->\n<VTKFile", 1),
    "char_reference": lambda d: d.replace(b'format="binary"', b'format="&#98;inary"'),
}


def test_vtp_damaged_block_headers_refused_before_vtk_reads_them(tmp_path, helpers):
    """Each file is a valid one with header words changed; all are read in one subprocess (with
    its address space limited, as on a small machine) so that a regression, which aborts the
    process, fails this test instead of ending the test run."""
    poly, cases = _polydata(), {}
    for i, (layout, values, parts) in enumerate(HOSTILE):
        path = _write(tmp_path / f"h{i}.vtp", poly, *layout)
        _set_words(path, values)
        cases[path] = parts
    garbled = _write(tmp_path / "garbled.vtp", poly, "ZLib", "Binary")
    data = garbled.read_bytes()
    start = _first_array(data)[0]
    garbled.write_bytes(data[:start] + b"!!!!" + data[start + 4 :])
    cases[garbled] = ["compression header (12 bytes) cannot be decoded"]
    for mode in ("Appended", "AppendedRaw"):  # the appended data's '_' lost (and a header, encoded): VTK read on
        path = _write(tmp_path / f"no_marker_{mode}.vtp", poly, "ZLib", mode)
        data = path.read_bytes()
        start = _first_array(data)[0]
        path.write_bytes(data[: start - 1] + data[start + (8 if mode == "Appended" else 0) :])
        cases[path] = ["the AppendedData does not start with '_'"]
    for name, respell in _SPELLINGS.items():  # the XML as VTK reads it, not one byte pattern
        path = tmp_path / f"{name}.vtp"
        path.write_bytes(respell((tmp_path / "h0.vtp").read_bytes()))
        cases[path] = HOSTILE[0][2]
    answers = helpers.read_in_child(cases)
    for path, parts in cases.items():
        for part in (path.name, "array 'Normals' in PointData of piece 0", *parts):
            assert part in answers[str(path)], answers[str(path)]
