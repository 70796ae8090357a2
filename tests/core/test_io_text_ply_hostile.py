"""Readers on hostile files: a truncated ASCII PLY, text numbers in styles the parser does
not take. Each is refused by a CloudFileError naming the file and the problem."""

from __future__ import annotations

import numpy as np
import pytest

import core
from core.io import CloudFileError, read_cloud

PTS = core.shapes.sphere(30, seed=1).points
X0 = float(PTS[0, 0])
XYZ = "property float x\nproperty float y\nproperty float z\n"
FACE = "element face 5\nproperty list uchar int vertex_indices\n"
ROWS = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in PTS.tolist())
FACE_ROWS = [f"3 {i} {i + 1} {i + 2}\n" for i in range(5)]


def _error(path, *parts):
    with pytest.raises(CloudFileError) as info:
        read_cloud(path)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    for part in parts:
        assert part in message, message
    return message


def _ascii_ply(path, body, elements=FACE):
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex {len(PTS)}\n{XYZ}{elements}end_header\n{body}")
    return path


# 2. an ASCII body with fewer rows than the header declares

@pytest.mark.parametrize("faces", [0, 1, 4])
def test_ascii_ply_missing_face_rows_refused(tmp_path, faces):
    path = _ascii_ply(tmp_path / "short.ply", ROWS + "".join(FACE_ROWS[:faces]))
    _error(path, "truncated", "declares 5 faces", f"only {faces} face rows follow")


def test_ascii_ply_missing_rows_of_a_later_element_refused(tmp_path):
    extra = "element edge 3\nproperty int vertex1\nproperty int vertex2\n"
    path = _ascii_ply(tmp_path / "edges.ply", ROWS + "".join(FACE_ROWS) + "0 1\n", FACE + extra)
    _error(path, "declares 3 edges", "only 1 edge rows follow")


def test_ascii_ply_blank_lines_do_not_count_as_rows(tmp_path):
    body = ROWS + "\n  \n" + "".join(FACE_ROWS[:4]) + "\n\n"
    _error(_ascii_ply(tmp_path / "blank.ply", body), "declares 5 faces", "only 4 face rows follow")


def test_ascii_ply_missing_vertex_rows_refused(tmp_path):
    path = tmp_path / "v.ply"
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex 40\n{XYZ}end_header\n{ROWS}")
    _error(path, "truncated: the header declares 40 vertices but only 30 vertex rows follow")


@pytest.mark.parametrize("newline", ["\n", "\r\n", "\r"])
def test_ascii_ply_complete_reads(tmp_path, newline):
    body = (ROWS + "".join(FACE_ROWS) + "\n").replace("\n", newline)
    path = tmp_path / "ok.ply"
    path.write_bytes(f"ply\nformat ascii 1.0\nelement vertex {len(PTS)}\n{XYZ}{FACE}end_header\n".encode()
                     + body.encode())
    np.testing.assert_allclose(read_cloud(path).points, PTS, rtol=1e-6)


# 3. text numbers in a style np.loadtxt does not take, on every line

@pytest.mark.parametrize("style, first", [
    (lambda v: f"{v!r}D+00", f"{X0!r}D+00"),
    (float.hex, X0.hex()),
])
@pytest.mark.parametrize("n_lines", [30, 1200])  # 1200: beyond the header scan's 1000 lines
def test_text_numbers_in_other_styles_refused(tmp_path, style, first, n_lines):
    pts = np.resize(PTS, (n_lines, 3))
    path = tmp_path / "styled.xyz"
    path.write_text("".join(" ".join(style(v) for v in row) + "\n" for row in pts.tolist()))
    _error(path, f"line 1: cannot parse {first!r} as a number")


def test_text_styled_numbers_after_a_header_named_by_line(tmp_path):
    path = tmp_path / "styled.csv"
    path.write_text("x,y,z\n" + "".join(",".join(f"{v!r}D+00" for v in row) + "\n" for row in PTS.tolist()))
    _error(path, "line 2: cannot parse", "D+00' as a number")


def test_text_words_only_still_has_no_points(tmp_path):
    path = tmp_path / "words.xyz"
    path.write_text("a b c\nd e f\n")
    _error(path, "contains no points")
