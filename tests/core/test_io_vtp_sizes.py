"""XML PolyData (.vtp) sizes are read as VTK's XML parser reads them: VTK allocated what a
NumberOf... attribute declares before reading any data (std::bad_alloc aborted the process),
and the guard before it matched only NumberOfPoints="digits" in double quotes within the first
MiB, so single quotes, spaces around '=', a character reference or a long comment before the
sizes went past it; a huge NumberOfComponents kept VTK busy for over a minute, and
NumberOfPoints="1e12" was read as 1 point without a word. Hostile files are read in a
subprocess with its address space limited, so that a regression fails the test instead of
ending the test run."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import core
from core._memory import available_memory
from core.io import CloudFileError
from core.io import vtk as vtk_io, xml_scan
from io_testutils import cpu_seconds

pytest.importorskip("vtkmodules.vtkIOXML")

HUGE = "1000000000000"
MEMORY = "GB of memory available"
NOT_A_COUNT = "allowed: a count in decimal digits (no sign, point or exponent)"


def _check(path):
    """The checks read_cloud makes before VTK reads a .vtp (one parse of its XML)."""
    vtk_io.check_vtp(path, available_memory())


def _vtp(piece='NumberOfPoints="4"', components='"3"', before=""):
    """Four points in ascii, with the Piece attributes and NumberOfComponents spelled as given."""
    return (f'<?xml version="1.0"?>{before}<VTKFile type="PolyData"><PolyData><Piece {piece}>'
            f'<Points><DataArray type="Float32" NumberOfComponents={components} format="ascii">'
            "0 0 0 1 0 0 0 1 0 1 1 1</DataArray></Points></Piece></PolyData></VTKFile>")


HOSTILE = {  # name: (file text, parts of the message)
    "single_quotes": (_vtp(f"NumberOfPoints='{HUGE}'"), [f'NumberOfPoints="{HUGE}"', MEMORY]),
    "spaces_around_eq": (_vtp(f'NumberOfPoints = "{HUGE}"'), [f'NumberOfPoints="{HUGE}"', MEMORY]),
    "char_reference": (_vtp(f'NumberOfPoints="&#49;{HUGE[1:]}"'), [f'NumberOfPoints="{HUGE}"', MEMORY]),
    "hex_reference": (_vtp(f"NumberOfPoints='&#x31;{HUGE[1:]}'"), [f'NumberOfPoints="{HUGE}"', MEMORY]),
    "after_long_comment": (_vtp(f'NumberOfPoints="{HUGE}"', before="<!--" + "x" * (1 << 20) + "-->"),
                           [f'NumberOfPoints="{HUGE}"', MEMORY]),
    "plus_sign": (_vtp(f'NumberOfPoints="+{HUGE}"'), [f'NumberOfPoints="+{HUGE}"', NOT_A_COUNT]),
    "exponent": (_vtp('NumberOfPoints="1e12"'), ['<Piece> declares NumberOfPoints="1e12"', NOT_A_COUNT]),
    "decimal_point": (_vtp('NumberOfPoints="4.0"'), ['NumberOfPoints="4.0"', NOT_A_COUNT]),
    "negative": (_vtp("NumberOfPoints='-4'"), ['NumberOfPoints="-4"', NOT_A_COUNT]),
    "empty": (_vtp('NumberOfPoints=""'), ['NumberOfPoints=""', NOT_A_COUNT]),
    "hexadecimal": (_vtp('NumberOfPoints="0x10"'), ['NumberOfPoints="0x10"', NOT_A_COUNT]),
    "wide_digits": (_vtp('NumberOfPoints="４"'), ['NumberOfPoints="４"', NOT_A_COUNT]),
    "beyond_int64": (_vtp(f'NumberOfPoints="{2 ** 63}"'), [f'NumberOfPoints="{2 ** 63}"', f"at most {2 ** 63 - 1}"]),
    "thousands_of_digits": (_vtp(f'NumberOfPoints="{"9" * 5000}"'), ["NumberOfPoints=", "at most"]),
    "components_single_quoted": (_vtp(components="'1000000000'"), ['NumberOfComponents="1000000000"']),
    "components_not_a_count": (_vtp(components="'3e9'"), ['<DataArray> declares NumberOfComponents="3e9"',
                                                          NOT_A_COUNT]),
    "components_beyond_the_file": (_vtp(components="'1000000'"),  # fits in memory (32 MB), not in the file
                                   ['NumberOfPoints="4" x NumberOfComponents="1000000"', "4000000 values",
                                    "what the file's"]),
}


def test_vtp_sizes_read_as_xml_refused_at_once(tmp_path, helpers):
    cases = {}
    for name, (text, parts) in HOSTILE.items():
        path = tmp_path / f"{name}.vtp"
        path.write_text(text, encoding="utf-8")
        cases[path] = parts
    answers = helpers.read_in_child(cases)
    for path, parts in cases.items():
        for part in (path.name, *parts):
            assert part in answers[str(path)], (path.name, answers[str(path)][:300])
        with pytest.raises(CloudFileError):  # at once: refused before VTK (73 s on one of them) reads it
            _check(path)


@pytest.mark.parametrize("piece", [
    "NumberOfPoints='4'", 'NumberOfPoints = "4"', 'NumberOfPoints="&#52;"', 'NumberOfPoints=" 4 "',
    'NumberOfPoints="0004"',
])
def test_vtp_sizes_spelled_any_valid_way_read(tmp_path, piece):
    path = tmp_path / "a.vtp"
    path.write_text(_vtp(piece, components="'3'", before="<!--" + "x" * (1 << 20) + "-->"))
    np.testing.assert_array_equal(core.io.read_cloud(path).points, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1]])


@pytest.mark.parametrize("doctype", [
    '<!DOCTYPE v [<!ENTITY n "1000000000000">]>',
    '<!DOCTYPE v [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
    '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">]>',
    '<!DOCTYPE v [<!ENTITY n SYSTEM "file:///etc/hostname">]>',
])
def test_vtp_document_types_refused(tmp_path, doctype):
    """Entities could spell a size (or an element) where no check sees it; none is expanded."""
    path = tmp_path / "d.vtp"
    path.write_text(_vtp('NumberOfPoints="&n;"', before=doctype))
    for check in (core.io.read_cloud, _check):
        with pytest.raises(CloudFileError) as info:
            check(path)
        assert "DOCTYPE" in str(info.value) and "d.vtp" in str(info.value), str(info.value)


def test_vtp_long_comment_skipped_not_rescanned(tmp_path, monkeypatch):
    """expat 2.5 scans an unfinished comment again with each chunk it is given: a comment of
    2,000 chunks took minutes. Its rest is skipped, and the sizes after it are still read."""
    monkeypatch.setattr(xml_scan, "_CHUNK", 4096)
    path = tmp_path / "c.vtp"
    path.write_text(_vtp(f"NumberOfPoints='{HUGE}'", before="<!--" + "x- " * ((8 << 20) // 3) + "-->"))
    short = tmp_path / "short.vtp"  # as many bytes of comments, each within a chunk
    short.write_text(_vtp(f"NumberOfPoints='{HUGE}'", before="<!-- x- -->" * ((8 << 20) // 11)))

    def refused(cloud):
        with pytest.raises(CloudFileError, match=f'NumberOfPoints="{HUGE}"'):
            _check(cloud)

    assert cpu_seconds(lambda: refused(path), 1) < 10 * cpu_seconds(lambda: refused(short))
    path.write_text(_vtp(before="<!--" + "x" * (8 << 20) + "-- -->"))  # '--' inside: expat names it
    _check(path)
    with pytest.raises(CloudFileError, match="VTK cannot read it"):
        core.io.read_cloud(path)


def test_vtp_long_tag_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(xml_scan, "_CHUNK", 4096)
    monkeypatch.setattr(xml_scan, "_MAX_MARKUP", 1 << 16)
    path = tmp_path / "t.vtp"
    text = _vtp(f'a="{"x" * (1 << 20)}" NumberOfPoints="4"')
    path.write_text(text)
    with pytest.raises(CloudFileError, match=f"a tag .* of more than 65536 bytes at byte {text.index('<Piece')};"):
        _check(path)


def test_vtp_count_refused_through_the_cli(tmp_path):
    path = tmp_path / "q.vtp"
    path.write_text(_vtp(f"NumberOfPoints='{HUGE}'"))
    run = subprocess.run([sys.executable, "-m", "core", "info", str(path)], capture_output=True, text=True,
                         timeout=120, cwd=Path(core.__file__).resolve().parents[1])
    assert run.returncode == 2, (run.returncode, run.stderr[-2000:])
    assert run.stderr.startswith("darboux-cli: error: ") and run.stderr.count("\n") == 1, run.stderr
    for part in ("q.vtp", f'NumberOfPoints="{HUGE}"', MEMORY):
        assert part in run.stderr, run.stderr
