"""Delimited text: XYZ / PTS / TXT / CSV, one point per line.

Reading: leading non-numeric lines are a header (the last one may name the columns:
x, y, z, nx, ny, nz in any order, other names become fields); ``#`` starts a comment; a
first line holding a single integer is a point count (as in .pts) and is checked. The
separator is a comma, a semicolon or whitespace, guessed from the first data line.
Without usable column names: x y z come first; other columns become fields ``col3``,
``col4``... (0-based column numbers), except a triple that holds unit normals (lengths
1 +- 0.01 on 99 % of its non-zero rows): columns 3-5 (x y z nx ny nz ...) or else 6-8
(x y z r g b nx ny nz, CloudCompare). With 6 or more columns and no such triple (x y z
r g b, x y z i r g b) a warning says that no normals were read. A .pts file of 4 or 7
columns is Leica's x y z intensity [red green blue]. The file is decoded as UTF-8 when it
is valid UTF-8, else as latin-1. The numbers are parsed by ``np.loadtxt`` from the file.
A file of several blocks, each a count line and its rows (a PTS file of several scans), is
read whole, with the field ``scan`` (:mod:`.text_blocks`).
"""

from __future__ import annotations

import codecs
import warnings

import numpy as np

from .cloud import CloudFileError, RawCloud, find_normals
from .sniff import UTF8_BOM, wide_encoding
from .text_blocks import count_blocks, load_blocks
from .text_head import guess_delimiter as _guess_delimiter
from .text_head import header_names, token_hint
from .text_head import is_number as _is_number
from .text_head import refuse_data_like as _refuse_data_like
from .text_head import split as _split
from .text_rows import write_rows
from .text_tail import warn_if_cut

_MAX_HEADER_LINES = 1000
#: columns a line may have: far beyond any per-point descriptor (3D shape context: 1,980
#: values), and a bound on a line's tokens (3 million columns on one 9 MB line took 1 GB
#: and minutes as per-point fields)
MAX_COLUMNS = 10_000
#: headerless columns are normals where, of the finite non-zero rows, this share has a
#: length within _UNIT_TOL of 1 (colours 0-255 or 0-1, intensities do not)
_UNIT_SHARE = 0.99
_UNIT_TOL = 0.01
#: where headerless normals may start: x y z nx ny nz ..., x y z r g b nx ny nz (CloudCompare)
_NORMAL_STARTS = (3, 6)


def read_text(path, fmt: str) -> RawCloud:
    """Points, normals and extra columns from a delimited text file."""
    encoding = _encoding(path)
    head = _scan_head(path, encoding)
    table, scan = _load_table(path, encoding, head)
    if scan is None and head["count"] is not None and head["count"] != len(table):
        raise CloudFileError(
            path, f"line {head['count_line']} declares {head['count']} points but {len(table)} data lines follow"
        )
    raw = _raw_from_table(table, head["names"], fmt, path)
    warn_if_cut(path, encoding, head["delimiter"])
    if scan is not None:
        raw.fields.setdefault("scan", scan)
    return raw


def _encoding(path) -> str:
    """UTF-8, UTF-32 or UTF-16 (with a BOM) as marked; otherwise UTF-8 if the file is
    valid UTF-8, else latin-1, which never fails to decode and reads ASCII numbers right.
    NUL bytes without a BOM are refused."""
    with open(path, "rb") as f:
        start = f.read(4096)
    if start.startswith(UTF8_BOM):
        return "utf-8-sig"
    wide = wide_encoding(start)
    if wide is not None:
        return wide
    if b"\0" in start:
        kind = "UTF-16 text without a byte-order mark" if start[1::2].count(0) > len(start) // 4 else "binary data"
        raise CloudFileError(path, f"is not a text point cloud: it looks like {kind} (NUL bytes); "
                             "save it as UTF-8 or ASCII text")
    return "utf-8" if _is_utf8(path) else "latin-1"


def _is_utf8(path) -> bool:
    """Whether the file has non-ASCII bytes and they are all valid UTF-8 (read in 1 MB blocks)."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    seen = False
    with open(path, "rb") as f:
        while block := f.read(1 << 20):
            if block.isascii() and not decoder.getstate()[0]:
                continue
            seen = True
            try:
                decoder.decode(block)
            except UnicodeDecodeError:
                return False
    try:
        decoder.decode(b"", final=True)
    except UnicodeDecodeError:
        return False
    return seen


def _decimal_comma(text: str) -> bool:
    """Whether ``text`` is numbers with decimal commas ("1,5;2,25;3" or "1,5 2,25 3")."""
    for delimiter in (";", None):
        tokens = _split(text, delimiter)
        if len(tokens) >= 3 and any("," in t for t in tokens) and \
                all(_is_number(t.replace(",", ".")) and t.count(",") <= 1 for t in tokens):
            return True
    return False


def _empty_column(lineno: int, tokens: list[str]) -> str:
    """The message for a data line with an empty field (a missing value is not a zero)."""
    column = tokens.index("") + 1
    return f"line {lineno}: column {column} of {len(tokens)} is empty; every data line needs a number in each column"


def _header_line(path, lineno: int, text: str, tokens: list[str]) -> tuple[bool, str, int]:
    """A non-numeric line before the data, as a header entry; numbers with decimal commas
    are not a header but a number style the reader does not take, and numbers with an empty
    field a data line with a hole: both refused by name."""
    if any(tokens) and all(_is_number(t) or not t for t in tokens):
        raise CloudFileError(path, _empty_column(lineno, tokens))
    if _decimal_comma(text):
        raise CloudFileError(
            path, f"line {lineno}: {text[:40]!r} uses decimal commas; write numbers with a decimal "
            "point (1.5, not 1,5), separated by commas, semicolons or spaces",
        )
    return (False, text, lineno)


def _scan_head(path, encoding) -> dict:
    """Find the first data line, the separator, the column count, names and a count line."""
    count = count_line = None
    header = []  # (is_comment, text, lineno) of the non-blank lines before the data
    with open(path, encoding=encoding, errors="replace", newline=None) as f:
        for lineno, line in enumerate(f, start=1):
            if lineno > _MAX_HEADER_LINES:
                _refuse_data_like(path, header, None)
                raise CloudFileError(path, f"no numeric data in the first {_MAX_HEADER_LINES} lines")
            text = line.strip()
            if not text.strip(',;"'):  # blank, or ",,," (a spreadsheet's empty row): not a header
                continue
            if text.startswith(("#", "//")):
                header.append((True, text.lstrip("#/ \t"), lineno))
                continue
            text = text.split("#", 1)[0].strip()
            delimiter = _guess_delimiter(text)
            _check_width(path, lineno, text, delimiter)
            tokens = _split(text, delimiter)
            if not all(_is_number(t) for t in tokens):
                header.append(_header_line(path, lineno, text, tokens))
                continue
            if len(tokens) == 1 and count is None and tokens[0].isdigit() and all(c for c, *_ in header):
                count, count_line = int(tokens[0]), lineno
                continue
            if len(tokens) < 3:
                raise CloudFileError(
                    path, f"line {lineno}: found {len(tokens)} column(s); need at least 3 (x y z [nx ny nz ...])"
                )
            _refuse_data_like(path, header, len(tokens))
            names = header_names(path, header, len(tokens))
            trailing = delimiter is not None and text.endswith(delimiter)
            return dict(skip=lineno - 1, first=lineno, delimiter=delimiter, ncols=len(tokens), names=names,
                        count=count, count_line=count_line, usecols=range(len(tokens)) if trailing else None)
    _refuse_data_like(path, header, None)  # every line numbers in a style not taken (1.5D+00, 0x1.8p+0)
    raise CloudFileError(path, "contains no points (no numeric data lines)")


def _check_width(path, lineno: int, text: str, delimiter) -> None:
    """Refuse a line of more than :data:`MAX_COLUMNS` columns, counted without splitting it whole."""
    if len(text.split(delimiter, MAX_COLUMNS)) > MAX_COLUMNS:
        raise CloudFileError(path, f"line {lineno} has more than {MAX_COLUMNS:,} columns; a text point cloud is "
                                   f"read with at most {MAX_COLUMNS:,} (x y z, normals and per-point fields)")


def _load_table(path, encoding, head):
    """The data lines as a table, and None; or for a file of several count-line blocks
    (:mod:`.text_blocks`), the table of all of them and each row's block index."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(path, dtype=np.float64, delimiter=head["delimiter"], comments="#",
                               skiprows=head["skip"], encoding=encoding, quotechar='"', ndmin=2,
                               usecols=head["usecols"])
    except UnicodeDecodeError:
        raise CloudFileError(path, "is not valid UTF-8 text") from None
    except ValueError as exc:
        blocks = count_blocks(path, encoding, head)
        if blocks is None:
            raise diagnose_lines(path, encoding, head, exc) from None
        try:
            return load_blocks(path, encoding, head, blocks)
        except ValueError as again:
            raise diagnose_lines(path, encoding, head, again, skip={n for n, _ in blocks}) from None
    return table, None


def diagnose_lines(path, encoding, head, exc, skip=frozenset()) -> CloudFileError:
    """Re-read the data lines in Python to name the first bad line (``head``: first, ncols,
    delimiter, and optionally ``declared``, where ncols comes from; the line numbers ``skip``
    are not data lines)."""
    delimiter, ncols = head["delimiter"], head["ncols"]
    with open(path, encoding=encoding, errors="replace", newline=None) as f:
        for lineno, line in enumerate(f, start=1):
            text = line.split("#", 1)[0].strip()
            if lineno < head["first"] or not text or lineno in skip:
                continue
            _check_width(path, lineno, text, delimiter)
            tokens = _split(text, delimiter)
            if len(tokens) != ncols:
                said = head.get("declared", f"line {head['first']} has")  # a PCD's come from its header
                return CloudFileError(path, f"line {lineno}: found {len(tokens)} columns but {said} {ncols}")
            bad = next((t for t in tokens if not _is_number(t)), None)
            if bad == "":
                return CloudFileError(path, _empty_column(lineno, tokens))
            if bad is not None:
                return CloudFileError(path, f"line {lineno}: cannot parse {bad!r} as a number{token_hint(bad)}")
    return CloudFileError(path, f"cannot parse the data lines: {exc}")


def _raw_from_table(table, names, fmt, path) -> RawCloud:
    ncols = table.shape[1]
    lower = [n.lower() for n in names] if names else None
    if lower and {"x", "y", "z"} <= set(lower):
        xyz = [lower.index(c) for c in "xyz"]
        nrm = find_normals(lower)
        nrm_idx = [lower.index(n) for n in nrm] if nrm else []
    else:
        xyz, nrm_idx, names = _by_position(table, names, fmt, path)
    points = table[:, xyz]
    normals = table[:, nrm_idx] if nrm_idx else None
    used = set(xyz) | set(nrm_idx)
    fields = {names[i]: table[:, i] for i in range(ncols) if i not in used}
    return RawCloud(points, normals, fields)


def _by_position(table, names, fmt: str, path):
    """Without x/y/z names: x y z first, then normals at the first of columns 3-5 and 6-8
    that holds unit vectors (none in a 7-column .pts: x y z intensity red green blue);
    column names col0, col1... With 6 or more columns and no normals found, a warning."""
    ncols = table.shape[1]
    if names is None:
        names = [f"col{i}" for i in range(ncols)]
        if fmt == "pts" and ncols in (4, 7):
            names[3:] = ["intensity", "red", "green", "blue"][: ncols - 3]
    if ncols < 6 or (fmt == "pts" and ncols == 7):
        return [0, 1, 2], [], names
    starts = [s for s in _NORMAL_STARTS if s + 3 <= ncols]
    start = next((s for s in starts if _unit_rows(table[:, s : s + 3])), None)
    if start is not None:
        return [0, 1, 2], [start, start + 1, start + 2], names
    _warn_no_normals(path, table, names, starts)
    return [0, 1, 2], [], names


def _warn_no_normals(path, table, names, starts) -> None:
    """Say that a headerless file of 6 or more columns was read without normals, and why."""
    spans = " and ".join(f"{s}-{s + 2}" for s in starts)
    kept = ", ".join(names[3:9]) + (", ..." if len(names) > 9 else "")
    row = ", ".join(f"{v:g}" for v in table[0, 3:6])
    warnings.warn(f"{path}: no header names the columns x y z ..., and columns {spans} (counting from 0) are not "
                  f"unit normals (row 0: {row}); they are read as fields {kept} and the cloud has no normals. "
                  "To read normals, name the columns in a first line, e.g. 'x y z nx ny nz'", UserWarning, stacklevel=8)


def _unit_rows(block: np.ndarray) -> bool:
    """Whether a column triple looks like normals: of its finite non-zero rows (zero and NaN
    rows are "no normal"), at least _UNIT_SHARE have a length within _UNIT_TOL of 1."""
    length = np.linalg.norm(block[np.isfinite(block).all(axis=1)], axis=1)
    length = length[length > 0]
    return len(length) > 0 and np.count_nonzero(np.abs(length - 1.0) <= _UNIT_TOL) >= _UNIT_SHARE * len(length)


def write_text(f, columns, *, delimiter: str, header: bool) -> None:
    """Write ``columns`` (list of (name, (N,) array)) as delimited lines.

    ``header=True`` writes a first line of names (CSV style); otherwise a ``# names``
    comment line is written only when there are columns beyond x y z [nx ny nz], or normals
    the reader would not take for normals without it (not unit length, or none finite).
    """
    f.write(header_line(columns, delimiter=delimiter, header=header))
    write_rows(f, [values for _, values in columns], delimiter)


def header_line(columns, *, delimiter: str, header: bool) -> bytes:
    """The names line :func:`write_text` writes before the rows (b"" for plain x y z [nx ny nz])."""
    names = [name for name, _ in columns]
    plain = names == ["x", "y", "z"] or (names == ["x", "y", "z", "nx", "ny", "nz"] and
                                         _unit_rows(np.column_stack([v for _, v in columns[3:]]).astype(np.float64)))
    if header:
        return (delimiter.join(names) + "\n").encode()
    return b"" if plain else ("# " + delimiter.join(names) + "\n").encode()
