"""A legacy VTK file in ASCII whose POINTS section ends early, refused before VTK reads it.

VTK 9.7 reads such a file without an error message or code and returns the declared number of
points, those the file lacks being whatever memory held (1e+259 and 2e-312 in a file cut
after its first point; NaN or plausible numbers in others): garbage that passed as a cloud.
"""

from __future__ import annotations

import re

import numpy as np

from .cloud import CloudFileError

_POINTS = re.compile(rb"^[ \t]*points[ \t]+(\d+)[^\n]*\n", re.I | re.M)
#: the line after the coordinates: one that starts with a word, not a number (nan, inf are numbers)
_NEXT_SECTION = re.compile(rb"^[ \t]*(?![+-]?(?:nan|inf))[a-z_]", re.I | re.M)
#: bytes counted at a time (its temporaries, a few times this, stay small on a large file)
_CHUNK = 1 << 26
_SPACE = np.zeros(256, dtype=bool)
_SPACE[list(b" \t\r\n\v\f")] = True


def check_ascii_points(path, data, body: int) -> None:
    """The first POINTS section after ``body`` (where the header lines end) of the ASCII
    legacy file ``data`` holds at least 3 numbers per declared point before the next section."""
    match = _POINTS.search(data, body)
    if match is None:
        return
    need = 3 * int(match.group(1))
    after = _NEXT_SECTION.search(data, match.end())
    have = _words(data, match.end(), after.start() if after else len(data))
    if have < need:
        line = bytes(match.group(0)).decode("latin-1").strip()
        raise CloudFileError(path, f"truncated or corrupt POINTS section: {line!r} declares {need} coordinates "
                                   f"but {have} follow{'' if after else ' before the file ends'}")


def _words(data, start: int, stop: int) -> int:
    """Whitespace-separated words in ``data[start:stop]``, counted chunk by chunk."""
    count, after_space = 0, True
    for lo in range(start, stop, _CHUNK):
        space = _SPACE[np.frombuffer(data, np.uint8, min(_CHUNK, stop - lo), lo)]
        count += int(np.count_nonzero(space[:-1] & ~space[1:])) + int(after_space and not space[0])
        after_space = bool(space[-1])
    return count
