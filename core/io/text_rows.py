"""The data lines of a delimited text file (:func:`core.io.text.write_text`), formatted a
block of rows at a time by a compiled kernel (:mod:`.float_repr`) rather than by Python's
``%`` per row, to the same bytes.

Each value is spelled as Python spells it: a float64 (or wider, cast to float64) as
``repr`` (the shortest decimal that reads back exactly; ``nan``, ``inf``, ``-0.0``), an
integer or a boolean as ``'%d'`` (0/1), a float32 as ``'%.9g'`` (enough digits to read back
the float32): float32 columns are the one kind still formatted by Python, value by value.
"""

from __future__ import annotations

import numpy as np

from .float_repr import FLOAT64, INT64, REPR_WIDTH, TEXT, UINT64, join_blocks

#: rows formatted and written at a time (~40 MB of text for 17 columns)
_CHUNK_ROWS = 100_000
#: rows one thread formats at a time
_BLOCK_ROWS = 8192


def _kind(values: np.ndarray) -> int:
    if np.issubdtype(values.dtype, np.unsignedinteger):
        return UINT64
    if values.dtype == bool or np.issubdtype(values.dtype, np.integer):
        return INT64
    return TEXT if values.dtype == np.float32 else FLOAT64


#: how each kind of column is held as 64-bit words for the kernel
_WORD_TYPES = {FLOAT64: np.float64, INT64: np.int64, UINT64: np.uint64}


def _block(arrays, kinds, start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
    """Rows start:stop as 64-bit words (rows, columns): the bits of the float64 columns,
    the integers as int64 or uint64; and the float32 columns' '%.9g' as NUL-padded bytes
    (rows, columns, width), by column (each kind's other slots are left empty)."""
    words = np.zeros((stop - start, len(arrays)), dtype=np.uint64)
    spelled = {j: np.array(list(map("%.9g".__mod__, values[start:stop].astype(np.float64).tolist())), dtype=bytes)
               for j, (values, kind) in enumerate(zip(arrays, kinds)) if kind == TEXT}
    width = max([text.itemsize for text in spelled.values()], default=1)
    texts = np.zeros((stop - start, len(arrays) if spelled else 0, width), dtype=np.uint8)
    for j, (values, kind) in enumerate(zip(arrays, kinds)):
        if kind != TEXT:
            words[:, j] = values[start:stop].astype(_WORD_TYPES[kind]).view(np.uint64)
    for j, text in spelled.items():
        texts[:, j, : text.itemsize] = text.view(np.uint8).reshape(stop - start, text.itemsize)
    return words, texts


def write_rows(f, arrays, delimiter: str) -> None:
    """Write one line per row of the (N,) ``arrays``, the values joined by ``delimiter``:
    the bytes of ``(delimiter.join(spellings) + "\\n").encode()`` for each row."""
    if not arrays:
        return
    kinds = np.array([_kind(values) for values in arrays], dtype=np.int64)
    separator = np.frombuffer(delimiter.encode(), dtype=np.uint8)
    for start in range(0, len(arrays[0]), _CHUNK_ROWS):
        stop = min(start + _CHUNK_ROWS, len(arrays[0]))
        words, texts = _block(arrays, kinds, start, stop)
        row_bytes = len(arrays) * (max(REPR_WIDTH, texts.shape[2]) + len(separator)) + 1
        out = np.empty((stop - start) * row_bytes, dtype=np.uint8)
        written = join_blocks(words, texts, kinds, separator, out, _BLOCK_ROWS, row_bytes)
        for b, length in enumerate(written.tolist()):
            f.write(out[b * _BLOCK_ROWS * row_bytes :][:length].tobytes())
