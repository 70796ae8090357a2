"""A delimited text file that looks cut inside its last number.

A file cut inside its last value still reads: the value's first digits are a number, and
the row has all its columns (a cut in an earlier column leaves a short row, refused). No
count can tell, but a writer's format can: one that writes every value of a column with
the same number of decimals (and exponent digits), as ``%.6f`` or ``%.4e`` do, writes no
shorter one, and writers end a file with a newline. A last line without one, whose last
value has fewer decimals (or exponent digits) than every one of the many lines before it
has in that column, is a cut, and a warning says so. Files of shortest-digit numbers
(``repr``, ``%g``: the decimals vary) or integer columns give no such evidence and pass.
"""

from __future__ import annotations

import re
import warnings

from .text_head import split

#: bytes of the file's end that are looked at, and the fewest lines before the last that
#: must agree on their last value's format for a shorter last value to count as a cut
_TAIL, _EVIDENCE = 1 << 16, 8
_SHAPE = re.compile(r"[+-]?(\d*)(?:\.(\d*))?(?:[eEdD][+-]?(\d*))?\Z")


def warn_if_cut(path, encoding: str, delimiter) -> None:
    """Warn where the file looks cut inside its last number (see the module's text)."""
    rows = _last_rows(path, encoding, delimiter)
    if len(rows) <= _EVIDENCE:
        return
    last, before = rows[-1], [row for row in rows[:-1] if len(row) == len(rows[-1])][-1000:]
    shapes = {_shape(row[-1]) for row in before}
    if len(before) < _EVIDENCE or len(shapes) != 1 or None in shapes:
        return
    (decimals, exponent), shape = shapes.pop(), _shape(last[-1])
    if shape is not None and (shape[0] < decimals or (exponent >= 0 and shape[1] < exponent)):
        what = f"{decimals} decimals" + (f" and {exponent} exponent digits" if exponent >= 0 else "")
        warnings.warn(f"{path}: the file ends without a newline, in {last[-1][:40]!r}, shorter than the {what} of the "
                      f"{len(before)} values before it in that column: the file looks cut short (the last point is "
                      "read as it stands)", UserWarning, stacklevel=4)


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


def _shape(token: str):
    """(decimals, exponent digits or -1) of a number as written, or None for another token."""
    match = _SHAPE.match(token)
    if match is None or not (match.group(1) or match.group(2)):
        return None
    return len(match.group(2) or ""), -1 if match.group(3) is None else len(match.group(3))
