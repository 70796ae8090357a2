"""Open a LAS/LAZ file with laspy, reading a LAS 1.4 header whose 64-bit point count is 0
but whose legacy 32-bit count is not (as some older tools write point formats 0-5).

laspy reads only the 64-bit count of a LAS 1.4 file (byte 247), so such a file read as
empty; LAStools and PDAL take the legacy count (byte 107). :func:`open_reader` does the
same without changing or copying the file: laspy reads it through :class:`OverlaidFile`,
which serves the header with the legacy count in those 8 bytes and every other byte from
the file (seekable, as the LAZ decompressor needs).
"""

from __future__ import annotations

import io
import struct

from .cloud import CloudFileError

#: the header bytes that say how the file counts its points (the 64-bit count ends at 255)
HEAD_BYTES = 255
#: where the legacy 32-bit and the LAS 1.4 64-bit point counts are
LEGACY_COUNT_AT, COUNT_AT = 107, 247


def legacy_only_count(head: bytes) -> int | None:
    """The legacy point count of a LAS 1.4+ header whose 64-bit count is 0 (None otherwise)."""
    if len(head) < HEAD_BYTES or not head.startswith(b"LASF") or tuple(head[24:26]) < (1, 4):
        return None
    legacy = struct.unpack_from("<I", head, LEGACY_COUNT_AT)[0]
    if legacy == 0 or struct.unpack_from("<Q", head, COUNT_AT)[0] != 0:
        return None
    return legacy


def point_count(head: bytes) -> int:
    """The point count of a LAS header as the file is read: the 64-bit count of LAS 1.4+, or
    the legacy count when the 64-bit one is 0, or the legacy count of older versions."""
    legacy = legacy_only_count(head)
    if legacy is not None:
        return legacy
    if head[25] >= 4 and len(head) >= HEAD_BYTES:
        return struct.unpack_from("<Q", head, COUNT_AT)[0]
    return struct.unpack_from("<I", head, LEGACY_COUNT_AT)[0]


class OverlaidFile(io.RawIOBase):
    """A read-only, seekable view of a file in which the bytes from ``at`` read as ``data``
    (the file itself is neither changed nor copied)."""

    def __init__(self, path, at: int, data: bytes):
        super().__init__()
        self._file = open(path, "rb")
        self._at, self._data = at, bytes(data)
        self.name = str(path)

    def readable(self) -> bool:
        return True

    def seekable(self) -> bool:
        return True

    def seek(self, pos: int, whence: int = io.SEEK_SET) -> int:
        return self._file.seek(pos, whence)

    def tell(self) -> int:
        return self._file.tell()

    def readinto(self, buffer) -> int:
        """Read into ``buffer`` from the file, the overlaid bytes replaced."""
        pos = self._file.tell()
        view = memoryview(buffer).cast("B")
        n = self._file.readinto(view)
        lo, hi = max(pos, self._at), min(pos + n, self._at + len(self._data))
        if lo < hi:
            view[lo - pos:hi - pos] = self._data[lo - self._at:hi - self._at]
        return n

    def close(self) -> None:
        self._file.close()
        super().close()


def open_reader(path, **kwargs):
    """``laspy.open(path, **kwargs)`` for reading; a LAS 1.4 file with only the legacy point
    count is read with that count (through an :class:`OverlaidFile`)."""
    import laspy

    with open(path, "rb") as f:
        legacy = legacy_only_count(f.read(HEAD_BYTES))
    if legacy is None:
        return laspy.open(path, **kwargs)
    return laspy.open(OverlaidFile(path, COUNT_AT, struct.pack("<Q", legacy)), closefd=True, **kwargs)


def unreadable(path, exc: BaseException):
    """The CloudFileError for laspy's refusal ``exc`` of a LAS/LAZ file; laspy says only "35"
    of a point format it does not know (the header's byte 104 was 99, bits 6-7 its compression)."""
    import laspy

    problem = str(exc)
    if isinstance(exc, laspy.errors.PointFormatNotSupported):
        problem = f"its header's point format {exc} is none of the formats LAS defines (0-10)"
    return CloudFileError(path, f"not a readable LAS/LAZ file: {problem}")


def read(path):
    """The whole ``laspy.LasData`` of a LAS/LAZ file, as ``laspy.read`` (with :func:`open_reader`)."""
    with open_reader(path) as reader:
        return reader.read()
