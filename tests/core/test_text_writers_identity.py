"""The text writers (CSV, XYZ, TXT) format rows in a compiled kernel, to the very bytes of
the per-row Python ``%`` they replaced (kept below as the reference): repr() of float64,
'%.9g' of float32, '%d' of integers and booleans; and the UTF-8 byte-order mark has one name."""

from __future__ import annotations

import io
import re
from pathlib import Path

import numpy as np
import pytest

from core.io import text_rows, write_cloud
from core.io.sniff import UTF8_BOM
from core.io.text import header_line
from core.io.write import _columns_for

FORMATS = {"csv": (",", True), "xyz": (" ", False), "txt": (" ", False)}


def reference_write_text(f, columns, *, delimiter: str, header: bool) -> None:
    """The writer before the kernel: its names line (unchanged, :func:`core.io.text.header_line`),
    then one Python ``%`` per row, 100k rows at a time."""
    f.write(header_line(columns, delimiter=delimiter, header=header))

    def row_format(values):
        if values.dtype == bool or np.issubdtype(values.dtype, np.signedinteger):
            return "%d", "i8"
        if np.issubdtype(values.dtype, np.unsignedinteger):
            return "%d", "u8"
        return ("%.9g" if values.dtype == np.float32 else "%r"), "f8"

    formats, dtypes = zip(*(row_format(values) for _, values in columns))
    line = delimiter.join(formats) + "\n"
    table = np.empty(len(columns[0][1]), dtype=[(f"c{i}", dt) for i, dt in enumerate(dtypes)])
    for i, (_, values) in enumerate(columns):
        table[f"c{i}"] = values
    for start in range(0, len(table), 100_000):
        f.write("".join(map(line.__mod__, table[start : start + 100_000].tolist())).encode())


def _awkward_doubles(rng, n: int) -> np.ndarray:
    """Every kind of double: any bit pattern (subnormals, huge, tiny), NaN, +-inf, -0.0,
    1e+-300, powers of 2 and 10 and their neighbours, integers, short decimals."""
    special = [np.nan, -np.nan, np.inf, -np.inf, 0.0, -0.0, 1e-300, 1e300, -1e-300, 5e-324, -5e-324,
               2.2250738585072014e-308, 1.7976931348623157e308, 1e16, 1e15, 9999999999999998.0, 1e-4, 1e-5,
               0.1, 1 / 3, 2.0**53, 2.0**53 + 2, 2.0**52, 123456789012345678.0, 0.30000000000000004]
    powers = np.concatenate([np.ldexp(1.0, rng.integers(-1074, 1024, n)), 10.0 ** rng.integers(-323, 309, n)])
    kinds = [rng.integers(0, 2**64, n, dtype=np.uint64).view(np.float64), powers, np.nextafter(powers, np.inf),
             np.nextafter(powers, -np.inf), rng.integers(-10**17, 10**17, n) * 1.0,
             rng.integers(-10**6, 10**6, n) / 10.0 ** rng.integers(-20, 25, n), rng.normal(size=n)]
    return rng.permutation(np.concatenate([special, rng.permutation(np.concatenate(kinds))[: n - len(special)]]))


def _fields(rng, n: int) -> dict:
    """One field of each kind the writer meets: float64, float32, float16, long double,
    integers of every width and sign (their extremes too), booleans, (N, 3) vectors."""
    with np.errstate(over="ignore"):
        f32 = _awkward_doubles(rng, n).astype(np.float32)  # with overflows to inf
    return {"k1": _awkward_doubles(rng, n), "e1": _awkward_doubles(rng, 3 * n).reshape(n, 3),
            "f32": f32, "f16": rng.normal(size=n).astype(np.float16), "ld": _awkward_doubles(rng, n).astype(np.longdouble),
            "i64": np.resize(np.array([np.iinfo(np.int64).min, np.iinfo(np.int64).max, -1, 0]), n) * (rng.random(n) < 0.5),
            "u64": np.resize(np.array([np.iinfo(np.uint64).max, 0, 7], dtype=np.uint64), n),
            "i8": rng.integers(-128, 128, n, dtype=np.int8), "u16": rng.integers(0, 65536, n, dtype=np.uint16),
            "valid": rng.random(n) < 0.5}


def _both(fmt, pts, normals=None, fields=None) -> tuple[bytes, bytes]:
    new = io.BytesIO()
    write_cloud(new, pts, normals=normals, fields=fields, format=fmt)
    old = io.BytesIO()
    delimiter, header = FORMATS[fmt]
    reference_write_text(old, _columns_for(fmt, pts, normals, fields), delimiter=delimiter, header=header)
    return new.getvalue(), old.getvalue()


@pytest.mark.parametrize("fmt", sorted(FORMATS))
@pytest.mark.parametrize("seed", [0, 1])
def test_every_kind_of_value_is_written_byte_for_byte_as_before(fmt, seed, monkeypatch):
    """Across chunks and kernel blocks of odd sizes (so their seams fall mid-file)."""
    monkeypatch.setattr(text_rows, "_CHUNK_ROWS", 1013)
    monkeypatch.setattr(text_rows, "_BLOCK_ROWS", 97)
    rng = np.random.default_rng(seed)
    n = 5000
    normals = rng.normal(size=(n, 3))
    new, old = _both(fmt, _awkward_doubles(rng, 3 * n).reshape(n, 3), normals, _fields(rng, n))
    assert new == old


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_plain_clouds_and_default_chunks_are_written_as_before(fmt, tmp_path):
    """x y z alone, with unit normals (no '# names' line in XYZ), one row, and more rows than
    one default chunk; through a file path (the atomic write) too."""
    rng = np.random.default_rng(2)
    pts = rng.normal(size=(100_017, 3)) * 10.0 ** rng.integers(-8, 9, size=(100_017, 1))
    normals = rng.normal(size=(100_017, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    for args in [(pts[:1],), (pts[:50], normals[:50]), (pts, normals)]:
        new, old = _both(fmt, *args)
        assert new == old
    write_cloud(tmp_path / f"out.{fmt}", pts, normals=normals)
    assert (tmp_path / f"out.{fmt}").read_bytes() == new


def test_the_utf8_byte_order_mark_is_spelled_once():
    """core.io.sniff.UTF8_BOM is the one spelling of EF BB BF in the readers."""
    assert UTF8_BOM == b"\xef\xbb\xbf"
    io_dir = Path(__file__).resolve().parents[2] / "core" / "io"
    literal = re.compile(r"\\xef\\xbb\\xbf|\\ufeff", re.IGNORECASE)
    assert [p.name for p in sorted(io_dir.glob("*.py")) if literal.search(p.read_text())] == []
