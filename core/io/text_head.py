"""The lines before the data of a delimited text file: tokens, numbers, and which lines
are a header (column names, units, titles) and which are data lines the parser cannot take.

A line of the data's column count made mostly of number-like tokens is a data line, never
a header: numbers in a style not taken ("3.5e", "0x1.8p+0", "1.5D+00"), missing-value
marks ("NA", "null"), numbers with a unit ("1.5m", "2.5 ft", "30°") and quoted numbers
with a decimal comma or thousands separators ("1,5", "1,000.5") are refused by line and
token; a line naming x, y and z is always a header. The names line is the last header
line naming x, y and z (else the last line, if it has one distinct name per column): one
whose names would be read against the data (x not in the first column when the data has
another column count, or a coordinate or normal named twice) is refused rather than read
by position; other repeated names get a suffix (i, i_2).
"""

from __future__ import annotations

import collections
import csv
import re

from .cloud import NORMAL_NAMES, CloudFileError

#: a token shaped like a number in a style the parser does not take ("3.5e", C99 hex
#: "0x1.8p+0", Fortran "1.5D+00"): a line made mostly of them is a data line, not a header
_NUMBERISH = re.compile(r"[+-]?(0[xX][0-9a-fA-F]*(\.[0-9a-fA-F]*)?([pP][+-]?\d*)?|(\d+(\.\d*)?|\.\d+)([eEdD][+-]?\d*)?)")
#: a number with a unit: "1.5m", "2.5 ft", "30°", "12%" (not an ordinal: "1st", "2nd")
_WITH_UNIT = re.compile(r"[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?\s?(?!(st|nd|rd|th)$)([^\W\d_]{1,4}|°[CF]?|[%\"'′″])")
#: a number with a decimal comma or thousands separators ("1,5", "1,000.5"), quoted in a CSV
_COMMA_NUMBER = re.compile(r"[+-]?(\d{1,3}(,\d{3})+(\.\d*)?|\d*,\d+)")
#: tokens that mark a missing value (R, pandas, SQL, spreadsheets): a row of them is data, not a header
_MISSING = frozenset(("na", "n/a", "nan", "null", "none", "nil", "-", "--", "?", "missing", "#n/a"))
_ANY_SEPARATOR = re.compile(r"[\s,;]+")
#: the names of coordinates and normal components, which a names line may not repeat
_GEOMETRY = frozenset(("x", "y", "z", *(name for triple in NORMAL_NAMES for name in triple)))


def guess_delimiter(text: str) -> str | None:
    return "," if "," in text else ";" if ";" in text else None


def split(line: str, delimiter: str | None) -> list[str]:
    """Tokens without quotes (a delimiter inside quotes is part of its token: "1,5";"2,5");
    a trailing delimiter ("1,2,3,") adds no empty token."""
    parts = next(csv.reader([line], delimiter=delimiter)) if delimiter and '"' in line else line.split(delimiter)
    tokens = [t.strip().strip('"').strip() for t in parts]
    while len(tokens) > 1 and tokens[-1] == "":
        tokens.pop()
    return tokens


def is_number(token: str) -> bool:
    """Whether ``np.loadtxt`` reads ``token`` as a float (Python's float also takes "1_000"
    and non-ASCII digits, which loadtxt refuses)."""
    if not token.isascii() or "_" in token:
        return False
    try:
        float(token)
    except ValueError:
        return False
    return True


def token_hint(token: str) -> str:
    """What a token that is not a number looks like, for a message: a missing value, a number
    with a unit, or nothing."""
    if token.lower() in _MISSING:
        return " (a missing value; every data line needs a number in each column)"
    if _WITH_UNIT.fullmatch(token):
        return " (a number with a unit; write bare numbers, all in one unit)"
    if _COMMA_NUMBER.fullmatch(token):
        return " (a decimal comma or thousands separator; write numbers as 1234.5)"
    return ""


def refuse_data_like(path, header, ncols: int | None) -> None:
    """Refuse a header line with the data's column count (``None``, no data line: 3 or more)
    made mostly of number-like tokens, or one that begins with a whole row of numbers
    ("1 2 3 a"): a data line the parser cannot take, named as on any later line."""
    for is_comment, text, lineno in header:
        bad = None if is_comment else _data_like(text, ncols)
        if bad is not None:
            raise CloudFileError(path, f"line {lineno}: cannot parse {bad!r} as a number{token_hint(bad)}")


def _data_like(text: str, ncols: int | None) -> str | None:
    """The first token that is not a number, when the line ``text`` is a data line (see
    :func:`refuse_data_like`); None for a header line."""
    tokens = split(text, guess_delimiter(text))
    if {"x", "y", "z"} <= {token.lower() for token in tokens}:
        return None  # a names line, whatever its other names look like ("x,y,z,1,2,3,4")
    words = _ANY_SEPARATOR.split(text)
    if ncols is not None and len(words) > ncols and all(is_number(t) for t in words[:ncols]):
        return _not_a_number(words, tokens, text)  # "1 2 3 a", or "1,2,3;4" (its token "3;4")
    numberish = sum(map(_numberish, tokens))
    shaped = len(tokens) == ncols if ncols is not None else len(tokens) >= 3
    return _not_a_number(tokens, text) if shaped and 2 * numberish > len(tokens) else None


def _not_a_number(*lists) -> str:
    """The first token of the first of ``lists`` that holds one that is not a number (the
    last of ``lists`` is the line itself)."""
    return next((t for tokens in lists[:-1] for t in tokens if not is_number(t)), lists[-1])


def _numberish(token: str) -> bool:
    """Whether ``token`` is a number, or a number in a style not taken, or a missing value."""
    return bool(is_number(token) or _NUMBERISH.fullmatch(token) or _WITH_UNIT.fullmatch(token)
                or _COMMA_NUMBER.fullmatch(token) or token.lower() in _MISSING)


def header_names(path, header, ncols: int):
    """Column names: the last header line naming x, y and z (a units line or comment after
    it does not hide it; checked by :func:`_checked_names`), else the last line if it has
    one distinct name per column and is not a comment; None to read by position."""
    for i, (is_comment, text, lineno) in enumerate(reversed(header)):
        names = split(text, guess_delimiter(text))
        lower = [n.lower() for n in names]
        if {"x", "y", "z"} <= set(lower) and (len(names) == ncols or not is_comment):
            return _checked_names(path, names, ncols, lineno)
        if i == 0 and not is_comment and len(names) == ncols and len(set(lower)) == ncols:
            return _filled(names)
    return None


def _checked_names(path, names, ncols: int, lineno: int):
    """The names of a line naming x, y and z; None (read by position) when their count is
    not the data's but x, y, z come first, as position reads them. A line that would be read
    against the data is refused: another count with the coordinates elsewhere, or a
    coordinate or normal named twice. Other names named twice get a suffix (i, i_2)."""
    lower = [n.lower() for n in names]
    if len(names) != ncols:
        if lower[:3] == ["x", "y", "z"]:
            return None
        raise CloudFileError(path, f"line {lineno} names {len(names)} columns ({', '.join(names)}) but the data "
                                   f"lines have {ncols}: give one name per column, or none (x y z first)")
    twice = sorted(name for name, count in collections.Counter(lower).items() if count > 1)
    if set(twice) & _GEOMETRY:
        raise CloudFileError(path, f"line {lineno} names the column(s) {', '.join(twice)} more than once "
                                   f"({', '.join(names)}); name each column once")
    return _filled(_suffixed(names, set(lower)))


def _suffixed(names, taken: set):
    """``names`` with each repeat given the first suffix not taken (i, i_2, i_3); each name's
    count goes on from its last suffix (trying every suffix from 2 was quadratic: a names
    line of 100,000 columns took hours)."""
    unique, last = [], {}
    for name in names:
        key, new = name.lower(), name
        n = last.get(key)
        if n is not None:  # a repeat: the first free suffix after this name's last
            while new.lower() in taken:
                n += 1
                new = f"{name}_{n}"
            taken.add(new.lower())
        last[key] = n or 1
        unique.append(new)
    return unique


def _filled(names):
    """``names`` with an empty one (a pandas index column: ",x,y,z") as col0, col1..."""
    return [name or f"col{i}" for i, name in enumerate(names)]
