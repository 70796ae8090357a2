"""A LAS file's point data longer than its header's records by less than one record.

Bytes inserted into the point data (or lost from it and made up at its end) shift every
record after them: their coordinates read as garbage (1e6 for points of 1), and the data's
length is then the header's records plus a part of one. Trailing bytes after whole records
are what some writers leave (PDAL reads them without a word; it refuses only data short of
the header's count). The two are told apart by the header's bounds, which the LAS standard
defines as the points' extent: where a record lies outside them, the records are not where
the header says, and the file is refused naming the first; where all lie inside, the bytes
after the last record are ignored with a warning.
"""

from __future__ import annotations

import struct
import warnings

import numpy as np

from .cloud import CloudFileError, format_number

#: where a LAS header holds the coordinate scales (3 doubles), offsets and bounds (max x, min x, ...)
_SCALES_AT, _OFFSETS_AT, _BOUNDS_AT = 131, 155, 179
#: records whose coordinates are checked at a time (12 MB of int32 per million)
_CHUNK = 1 << 20


def check_partial_record(path, head: bytes, offset: int, count: int, record: int, end: int) -> None:
    """Refuse, or warn about, point data (from ``offset`` to ``end``) longer than ``count``
    records of ``record`` bytes by less than one record (see the module's text)."""
    extra = end - offset - count * record
    if not 0 < extra < record or record < 12 or count == 0:
        return
    said = f"the point data is {extra} byte{'s' * (extra != 1)} longer than the header's {count} records of {record} bytes"
    bounds = _header_bounds(head)
    if bounds is None:
        warnings.warn(f"{path}: {said}; those bytes are ignored (the header's bounds are unset, so the records could "
                      "not be checked for a shift)", UserWarning, stacklevel=2)
        return
    outside = _first_outside(path, head, offset, count, record, bounds)
    if outside is None:
        warnings.warn(f"{path}: {said}; those bytes (after the last record, whose points all lie within the "
                      "header's bounds) are ignored", UserWarning, stacklevel=2)
        return
    i, xyz = outside
    low, high = (" ".join(format_number(v) for v in side) for side in bounds)
    raise CloudFileError(path, f"{said}, and point {i} ({' '.join(f'{v:.6g}' for v in xyz)}) lies outside the header's "
                               f"bounds ({low} to {high}): bytes were inserted into (or lost from) the point data "
                               f"before it, shifting the records after; the file is damaged")


def _header_bounds(head: bytes):
    """(low, high) x y z of the header, or None where they are unset (all 0) or not bounds."""
    values = np.array(struct.unpack_from("<6d", head, _BOUNDS_AT))
    high, low = values[0::2], values[1::2]
    if not np.isfinite(values).all() or not (values != 0).any() or (low > high).any():
        return None
    return low, high


def _first_outside(path, head: bytes, offset: int, count: int, record: int, bounds):
    """(index, x y z) of the first record outside the bounds (by more than one scale unit), or None."""
    scales = np.array(struct.unpack_from("<3d", head, _SCALES_AT))
    offsets = np.array(struct.unpack_from("<3d", head, _OFFSETS_AT))
    low, high = bounds
    slack = np.abs(scales) + 1e-9 * np.maximum(np.abs(low), np.abs(high))
    layout = np.dtype({"names": ["xyz"], "formats": [("<i4", 3)], "offsets": [0], "itemsize": record})
    records = np.memmap(path, dtype=layout, mode="r", offset=offset, shape=(count,))
    for start in range(0, count, _CHUNK):
        with np.errstate(all="ignore"):
            xyz = records["xyz"][start : start + _CHUNK] * scales + offsets
            outside = ((xyz < low - slack) | (xyz > high + slack) | ~np.isfinite(xyz)).any(axis=1)
        if outside.any():
            first = int(np.argmax(outside))
            return start + first, xyz[first]
    return None
