"""The ASCII body of a PLY file: its rows checked against the header, its vertex block read.

A body with more or fewer non-blank lines (one per row) than the header declares rows is
refused, and so is a row of an element other than the vertex whose values do not fit its
properties (one per scalar, a count and that many per list): a header that miscounts two
elements shifts rows between them even when the total matches. The rows are checked with
numpy a block of lines at a time; the vertex block is read by ``np.loadtxt``.
"""

from __future__ import annotations

import io
import warnings

import numpy as np
from plyfile import PlyListProperty

from .cloud import CloudFileError, format_number

#: numpy type code -> the PLY type name, for messages
PLY_NAMES = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int", "u4": "uint",
             "f4": "float", "f8": "double", "i8": "int64", "u8": "uint64", "f2": "float16"}
#: the most digits a list count may have in a row (a row of 10**9 values is no row)
_COUNT_DIGITS = 9


def plural(name: str) -> str:
    return {"vertex": "vertices", "face": "faces", "edge": "edges"}.get(name, f"{name!r} rows")


def declared(elements) -> str:
    """The counts the header declares, as "8 vertices and 20 faces"."""
    return " and ".join(f"{el.count} {plural(el.name)}" for el in elements)


def check_ascii_rows(f, header, path) -> None:
    """Refuse an ASCII body with more or fewer non-blank lines (one per row) than the header
    declares rows (a short body is named by the first element short of its rows), or with a
    row of a non-vertex element whose values do not fit its properties."""
    start, elements, total = f.tell(), header.elements, sum(el.count for el in header.elements)
    spans, first = [], 0
    for element in (el for el in elements if el.properties):  # rows of no properties may be blank lines
        if element.name != "vertex":
            spans.append((element, first, first + element.count))
        first += element.count
    found, problem = _scan_rows(f, spans)
    if found > total:
        rows = "vertex rows" if len(elements) == 1 else f"data lines (one per row: {total} declared)"
        raise CloudFileError(path, f"the header declares {declared(elements)} but {found} {rows} follow")
    left = found
    for element in (el for el in elements if el.properties):
        if left < element.count:
            lines = f" ({found} data lines for {declared(elements)}, one per row)" if len(elements) > 1 else ""
            raise CloudFileError(path, f"truncated: the header declares {element.count} {plural(element.name)} "
                                       f"but only {left} {element.name} rows follow{lines}")
        left -= element.count
    if problem is not None:
        raise CloudFileError(path, f"{problem}; the header's counts ({declared(elements)}) may not match the rows")
    f.seek(start)


def _chunks(f):
    """The bytes from the position of ``f`` to its end, in blocks of whole lines."""
    tail = b""
    for block in iter(lambda: f.read(1 << 20), b""):
        text = tail + block
        cut = max(text.rfind(b"\n"), text.rfind(b"\r")) + 1
        tail = text[cut:]
        yield text[:cut]
    yield tail


def _scan_rows(f, spans):
    """The non-blank lines from the position of ``f`` to its end, and the first row of the
    ``spans`` [(element, first row, end row)] that does not fit its element (a message), or None."""
    rows, problem = 0, None
    for chunk in _chunks(f):
        most = chunk.count(b"\n") + chunk.count(b"\r") + 1  # rows the chunk may hold
        if problem is None and any(a < rows + most and rows < b for _, a, b in spans):
            n, problem = _chunk_rows(chunk, rows, spans)
        else:
            n = sum(1 for line in chunk.replace(b"\r", b"\n").split(b"\n") if line.strip())
        rows += n
    return rows, problem


def _tokens(chunk: bytes):
    """The bytes of ``chunk``, where its tokens start and end (inclusive), and of each
    non-blank line its first token's index and its number of tokens."""
    buf = np.frombuffer(chunk, dtype=np.uint8)
    space = np.ones(len(buf) + 2, dtype=bool)  # padded: a token may touch either end
    np.logical_or(buf == ord(" "), (buf - 9) <= 4, out=space[1:-1])  # tab, \n, \v, \f, \r
    word = ~space[1:-1]
    starts, ends = np.flatnonzero(word & space[:-2]), np.flatnonzero(word & space[2:])
    bounds = np.r_[0, np.searchsorted(starts, np.flatnonzero((buf == 10) | (buf == 13))), len(starts)]
    ntok = np.diff(bounds)
    return buf, starts, ends, bounds[:-1][ntok > 0], ntok[ntok > 0]


def _chunk_rows(chunk: bytes, rows: int, spans):
    """The rows (non-blank lines) of ``chunk``, whole lines from row ``rows`` on, and the
    first of them that does not fit its element, as a message, or None."""
    buf, starts, ends, first, ntok = _tokens(chunk)
    for element, a, b in spans:
        lo, hi = max(a - rows, 0), min(b - rows, len(first))
        if lo >= hi:
            continue
        bad = _bad_rows(buf, starts, ends, first[lo:hi], ntok[lo:hi], element)
        if bad.any():
            i = lo + int(np.flatnonzero(bad)[0])
            tokens = [chunk[s : e + 1] for s, e in zip(starts[first[i] : first[i] + ntok[i]], ends[first[i] :])]
            text = b" ".join(tokens).decode("latin-1")
            shown = text if len(text) <= 60 else text[:57] + "..."
            return len(first), f"{element.name} row {rows + i - a} ({shown!r}): {_row_problem(tokens, element)}"
    return len(first), None


def _bad_rows(buf, starts, ends, first, ntok, element) -> np.ndarray:
    """Which rows (their first token's index and token count) do not fit ``element``: a list
    count that is not a non-negative integer, or more or fewer values than the properties need."""
    pos = np.zeros(len(first), dtype=np.int64)
    bad = np.zeros(len(first), dtype=bool)
    for prop in element.properties:
        if not isinstance(prop, PlyListProperty):
            pos += 1
            continue
        inside = pos < ntok
        at = first + np.minimum(pos, ntok - 1)
        count = _counts(buf, starts[at], ends[at])
        bad |= inside & (count < 0)
        pos += 1 + np.where(inside & (count >= 0), count, 0)
    return bad | (pos != ntok)


def _counts(buf, starts, ends) -> np.ndarray:
    """The integers the tokens spell in decimal digits (at most _COUNT_DIGITS), -1 for any other token."""
    length = ends - starts + 1
    value = np.zeros(len(starts), dtype=np.int64)
    ok = length <= _COUNT_DIGITS
    for j in range(min(int(length.max(initial=0)), _COUNT_DIGITS)):
        inside = j < length
        digit = buf[np.minimum(starts + j, ends)].astype(np.int64) - ord("0")
        ok &= ~inside | ((digit >= 0) & (digit <= 9))
        value = np.where(inside, value * 10 + digit, value)
    return np.where(ok, value, -1)


def _row_problem(tokens, element) -> str:
    """What is wrong with one row's ``tokens`` for ``element``."""
    pos, lists = 0, False
    for prop in element.properties:
        if not isinstance(prop, PlyListProperty):
            pos += 1
            continue
        lists = True
        token = tokens[pos] if pos < len(tokens) else b""
        if token and not (token.isdigit() and len(token) <= _COUNT_DIGITS):
            return (f"the count of its list {prop.name!r} is {token.decode('latin-1')!r}, "
                    f"not a list length (an integer from 0 to {10**_COUNT_DIGITS - 1})")
        pos += 1 + (int(token) if token else 0)
    need = f"its properties{' and list counts' if lists else ''} need {pos}"
    return f"it has {len(tokens)} value{'s' * (len(tokens) != 1)} but {need}"


def read_ascii_vertex(f, vertex, path):
    """The vertex properties of an ASCII body whose vertex element comes first (scalars only),
    or None when plyfile must read it (a row that np.loadtxt does not take, or 64-bit
    integers, which a float64 parse would round beyond 2**53)."""
    if any(np.dtype(p.dtype()).kind in "iu" and np.dtype(p.dtype()).itemsize == 8 for p in vertex.properties):
        return None
    text = io.TextIOWrapper(f, encoding="latin-1", newline=None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
            table = np.loadtxt(text, dtype=np.float64, comments=None, max_rows=vertex.count, ndmin=2)
    except ValueError:
        return None  # let plyfile locate and name the bad row
    finally:
        text.detach()
    if len(table) < vertex.count:
        raise CloudFileError(
            path, f"truncated: the header declares {vertex.count} vertices but only {len(table)} vertex rows follow"
        )
    if table.shape[1] != len(vertex.properties):
        return None
    return {p.name: _ascii_column(table[:, i], p, path) for i, p in enumerate(vertex.properties)}


def _ascii_column(values: np.ndarray, prop, path) -> np.ndarray:
    """An ASCII column in the declared type; integers out of range or with a fraction are refused
    (a cast would wrap 300 to 44 in a uchar), and so are finite numbers beyond a float's range
    (the cast made them inf). Float coordinates keep the float64 parse: the text has their
    precision (float32 rounds UTM northings to 0.5 m)."""
    dtype = np.dtype(prop.dtype())
    kind = f"{prop.name!r} ({PLY_NAMES.get(prop.val_dtype, prop.val_dtype)})"
    if dtype.kind == "f" and prop.name.lower() in ("x", "y", "z"):
        return values
    if dtype.kind == "f":
        with np.errstate(over="ignore"):
            cast = values.astype(dtype)
        bad = np.isfinite(values) & ~np.isfinite(cast)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise CloudFileError(path, f"vertex {row}: property {kind} has the value {values[row]:g}, "
                                       "beyond the range of its type")
        return cast
    info = np.iinfo(dtype)
    bad = (values < info.min) | (values > info.max) | (values != np.round(values))
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise CloudFileError(path, f"vertex {row}: property {kind} has the value {format_number(values[row])}, "
                                   f"not an integer in [{info.min}, {info.max}]")
    return values.astype(dtype, copy=False)
