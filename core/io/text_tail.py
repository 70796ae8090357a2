"""A delimited text file that looks cut inside its last number.

A file cut inside its last value still reads: the value's first digits are a number, and
the row has all its columns (a cut in an earlier column leaves a short row, refused). No
count can tell, but a writer's format can: one that writes every value of a column with
the same number of decimals (and exponent digits), as ``%.6f`` or ``%.4e`` do, writes no
shorter one, and writers end a file with a newline. A last line without one, whose last
value has fewer decimals (or exponent digits) than every one of the many lines before it
has in that column, is a cut, and a warning says so. Files of shortest-digit numbers
(``repr``, ``%g``: the decimals vary) or integer columns give no such evidence and pass.
The same holds for the rows of every text format (:func:`warn_if_text_cut`): an ASCII PLY or
PCD, an OBJ, OFF, PTX or ASCII legacy VTK file cut in its last number reads whole as well.
"""

from __future__ import annotations

import re
import warnings

from .text_head import split

#: bytes of the file's end that are looked at, and the fewest lines before the last that
#: must agree on their last value's format for a shorter last value to count as a cut
_TAIL, _EVIDENCE = 1 << 16, 8
_SHAPE = re.compile(r"[+-]?(\d*)(?:\.(\d*))?(?:[eEdD][+-]?(\d*))?\Z")


#: a text format's data, told by its first KiB (the formats of text only: None)
_TEXT_DATA = {"ply": re.compile(rb"\nformat[ \t]+ascii[ \t]"), "pcd": re.compile(rb"\nDATA[ \t]+ascii\b"),
              "vtk": re.compile(rb"\A[^\n]*\n[^\n]*\n[ \t]*ASCII", re.I), "obj": None, "off": None, "ptx": None}


def warn_if_text_cut(path, fmt: str) -> None:
    """:func:`warn_if_cut` for a file of another text format than delimited columns (an ASCII
    STL cut in a facet and a .vtp without its closing tag are refused by their readers)."""
    if fmt not in _TEXT_DATA:
        return
    if _TEXT_DATA[fmt] is not None:
        with open(path, "rb") as f:
            if not _TEXT_DATA[fmt].search(f.read(1024)):
                return
    warn_if_cut(path, "latin-1", None, stacklevel=5)


def warn_if_cut(path, encoding: str, delimiter, stacklevel: int = 4) -> None:
    """Warn where the file looks cut inside its last number (see the module's text)."""
    rows = _last_rows(path, encoding, delimiter)
    if len(rows) <= _EVIDENCE:
        return
    last = rows[-1]
    before = [row for row in rows[:-1] if _numbers(row, last)][-1000:]
    shapes = {_shape(row[-1]) for row in before}
    if len(before) < _EVIDENCE or len(shapes) != 1 or None in shapes:
        return
    (decimals, exponent), shape = shapes.pop(), _shape(last[-1])
    if shape is not None and (shape[0] < decimals or (exponent >= 0 and shape[1] < exponent)):
        what = f"{decimals} decimals" + (f" and {exponent} exponent digits" if exponent >= 0 else "")
        warnings.warn(f"{path}: the file ends without a newline, in {last[-1][:40]!r}, shorter than the {what} of the "
                      f"{len(before)} values before it in that column: the file looks cut short (the last point is "
                      "read as it stands)", UserWarning, stacklevel=stacklevel)


def _last_rows(path, encoding: str, delimiter) -> list:
    """The tokens of the data lines in the file's last 64 KiB, or [] when the file ends
    with a newline (or is UTF-16/32, whose bytes are not looked at)."""
    if encoding.startswith(("utf-16", "utf-32")):
        return []
    with open(path, "rb") as f:
        size = f.seek(0, 2)
        f.seek(max(0, size - _TAIL))
        tail = f.read()
    if not tail or tail.endswith((b"\n", b"\r")):
        return []
    lines = tail.decode("latin-1").splitlines()[1 if size > _TAIL else 0 :]
    return [split(line.strip(), delimiter) for line in lines if line.strip() and "#" not in line]


def _numbers(row, last) -> bool:
    """Whether ``row`` is a data row like ``last``: as many tokens, numbers but for a leading
    keyword they share (OBJ's ``v``), the last one not an integer (integers are no evidence of
    a format: a header's counts, an OFF's or PTX's, are not data rows)."""
    keyword = _shape(last[0]) is None
    return (len(row) == len(last) and (not keyword or row[0] == last[0]) and _shape(row[-1]) != (0, -1)
            and all(_shape(token) is not None for token in row[keyword:]))


def _shape(token: str):
    """(decimals, exponent digits or -1) of a number as written, or None for another token."""
    match = _SHAPE.match(token)
    if match is None or not (match.group(1) or match.group(2)):
        return None
    return len(match.group(2) or ""), -1 if match.group(3) is None else len(match.group(3))
