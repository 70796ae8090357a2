"""Text files of several blocks, each a point count line and that many rows: Leica Cyclone
writes a PTS file of several scans so (CloudCompare reads them). They were refused at the
second count line ("found 1 columns"). A file whose data lines, from its first count line
on, are exactly such blocks is read whole, with the field ``scan`` (int32: the block's
index, as for E57 and PTX); any other file is left to the reader's usual message.
"""

from __future__ import annotations

import warnings

import numpy as np

from .cloud import CloudFileError


def count_blocks(path, encoding, head) -> list | None:
    """[(line number, count)] of the count lines when, from the file's first count line on,
    the non-blank, non-comment lines are two or more blocks of a count line and that many
    rows; None when they are not blocks. A file of two or more blocks whose last block is
    short of its count, or with a row where the next count line should be, is refused."""
    if head["count"] is None:
        return None
    blocks, left = [], 0
    with open(path, encoding=encoding, errors="replace", newline=None) as f:
        for lineno, line in enumerate(f, start=1):
            text = line.split("#", 1)[0].strip()
            if lineno < head["count_line"] or not text:
                continue
            if left:
                left -= 1
            elif text.isdigit():
                blocks.append((lineno, int(text)))
                left = int(text)
            elif len(blocks) > 1:
                raise CloudFileError(path, f"line {lineno}: expected the point count of the next block, as on "
                                           f"lines {', '.join(str(n) for n, _ in blocks)}; the block of line "
                                           f"{blocks[-1][0]} has more than the {blocks[-1][1]} rows it declares")
            else:
                return None
    if len(blocks) > 1 and left:
        raise CloudFileError(path, f"truncated: line {blocks[-1][0]} declares {blocks[-1][1]} points but "
                                   f"{blocks[-1][1] - left} rows follow")
    return blocks if len(blocks) > 1 else None


def load_blocks(path, encoding, head, blocks) -> tuple[np.ndarray, np.ndarray]:
    """The rows of every block (``np.loadtxt`` over the lines without the count lines), and
    each row's block index."""
    skip = {lineno for lineno, _ in blocks}

    def rows():
        with open(path, encoding=encoding, errors="replace", newline=None) as f:
            for lineno, line in enumerate(f, start=1):
                if lineno > head["count_line"] and lineno not in skip:
                    yield line

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "input contained no data"
        table = np.loadtxt(rows(), dtype=np.float64, delimiter=head["delimiter"], comments="#", quotechar='"',
                           ndmin=2, usecols=head["usecols"])
    scan = np.repeat(np.arange(len(blocks), dtype=np.int32), [count for _, count in blocks])
    return table, scan
