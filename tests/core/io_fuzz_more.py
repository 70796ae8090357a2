"""More mutation classes for the hostile-file fuzz (the sixth round; ``io_fuzz_cases`` has
the seeds and the fifth round's cuts, count edits, word overwrites and byte flips): bytes
inserted into or deleted from a record, header lines or fields swapped and duplicated,
huge counts over a tiny body, other text encodings and line ends, a gzip'd file under its
format's own extension, and non-finite or extreme coordinates in every format."""

from __future__ import annotations

import gzip
import struct

import numpy as np

import io_fuzz_cases as F

#: seeds whose points are fixed-size binary records right after the header: bytes inserted
#: into or deleted from their data must be refused, or leave the points read unchanged
FIXED_RECORDS = ("ply_le_odd", "ply_be_faces", "ply_le_plain", "pcd_binary", "stl_binary", "las12_pf3",
                 "las14_pf6_odd")
#: seeds whose points are found by sizes and offsets a splice shifts: refused too, or read unchanged
SHIFT_CHECKED = FIXED_RECORDS + ("vtp",)
#: seeds that are text throughout (re-encoded and given other line ends)
TEXT = ("ply_ascii", "ply_ascii_faces", "xyz", "xyz_comment", "csv_header", "csv_semicolon", "txt_crlf_bom",
        "pts_count", "pcd_ascii", "off", "noff", "obj", "stl_ascii", "ptx", "vtk_ascii")
#: coordinates no estimate takes, put into row 3 of every format's seed
EXTREMES = {"nan": np.nan, "inf": np.inf, "-inf": -np.inf, "1e308": 1e308}


def body_start(name: str, data: bytes) -> int:
    """Where the point data start: after the text header, 84 bytes of a binary STL, a LAS header's offset."""
    if name.startswith("las"):
        return struct.unpack_from("<I", data, 96)[0]
    if name == "stl_binary":
        return 84
    return F._header_end(data) if F._header_end(data) < len(data) else 0


def spliced(name: str, data: bytes, rng, count=6):
    """(name, bytes): 1-7 random bytes inserted into, or deleted from, the point data at a random place."""
    start = body_start(name, data)
    out = []
    for i in range(count):
        at, k = int(rng.integers(start, len(data) - 1)), int(rng.integers(1, 8))
        if i % 2:
            out.append((f"del{at}+{k}", data[:at] + data[at + k :]))
        else:
            out.append((f"ins{at}+{k}", data[:at] + bytes(rng.integers(1, 256, k, dtype=np.uint8)) + data[at:]))
    return out


def reordered(name: str, data: bytes, rng):
    """(name, bytes): two header lines swapped, one duplicated, one dropped (a text header);
    two 4-byte header fields swapped and one copied over another (a binary header)."""
    end = body_start(name, data)
    if name.startswith("las") or name == "stl_binary" or not end:
        fields = [data[i : i + 4] for i in range(0, min(end or 84, 240), 4)]
        i, j = sorted(rng.choice(len(fields), 2, replace=False).tolist())
        swapped, copied = list(fields), list(fields)
        swapped[i], swapped[j], copied[j] = fields[j], fields[i], fields[i]
        rest = data[4 * len(fields) :]
        return [(f"swap{i}-{j}", b"".join(swapped) + rest), (f"copy{i}-{j}", b"".join(copied) + rest)]
    lines = data[:end].split(b"\n")[:-1]
    i, j = sorted(rng.choice(len(lines), 2, replace=False).tolist()) if len(lines) > 1 else (0, 0)
    swapped = list(lines)
    swapped[i], swapped[j] = lines[j], lines[i]
    body = data[end:]
    join = b"\n".join
    return [(f"swap{i}-{j}", join(swapped) + b"\n" + body), (f"dup{j}", join(lines[: j + 1] + lines[j:]) + b"\n" + body),
            (f"drop{j}", join(lines[:j] + lines[j + 1 :]) + b"\n" + body)]


_HUGE = (10**9, 2**31 - 1, 2**32 - 1, 10**15)


def huge_count(name: str, data: bytes, rng):
    """(name, bytes): the first count of the header made huge, the body cut to 16 bytes."""
    value = _HUGE[int(rng.integers(len(_HUGE)))]
    start = body_start(name, data)
    if name.startswith("las"):
        head = bytearray(data[:start])
        struct.pack_into("<I", head, 107, min(value, 2**32 - 1))
        if len(head) >= 255 and head[25] >= 4:
            struct.pack_into("<Q", head, 247, value)
        return [(f"count={value}", bytes(head) + data[start : start + 16])]
    if name == "stl_binary":
        return [(f"count={value}", data[:80] + struct.pack("<I", min(value, 2**32 - 1)) + data[84:100])]
    numbers = list(F._NUMBER.finditer(data[: start or 1024]))
    if not numbers:
        return []
    first = numbers[0]
    head = data[: first.start()] + str(value).encode() + data[first.end() : start or len(data)]
    return [(f"count={value}", head + data[start or len(data) :][:16])]


def reencoded(name: str, data: bytes):
    """(name, bytes): a text seed in UTF-16 (both byte orders), UTF-32, behind a UTF-8 BOM,
    with CR LF and with CR-only line ends."""
    if name not in TEXT:
        return []
    text = data.decode("utf-8").removeprefix("\ufeff")
    lf = text.replace("\r\n", "\n")
    return [("utf16le", text.encode("utf-16")), ("utf16be", b"\xfe\xff" + text.encode("utf-16-be")),
            ("utf32", text.encode("utf-32")), ("utf8bom", ("\ufeff" + text).encode()),
            ("crlf", lf.replace("\n", "\r\n").encode()), ("cr", lf.replace("\n", "\r").encode())]


def gzipped(data: bytes):
    return [("gzip", gzip.compress(data, mtime=0))]


def mutations(name: str, data: bytes, rng, count=6):
    """Every class above, for the seed ``name``: [(class, case, bytes)]."""
    out = [("splice", case, mutated) for case, mutated in spliced(name, data, rng, count)]
    out += [("reorder", case, mutated) for case, mutated in reordered(name, data, rng)]
    out += [("huge", case, mutated) for case, mutated in huge_count(name, data, rng)]
    out += [("encoding", case, mutated) for case, mutated in reencoded(name, data)]
    return out + [("gzip", case, mutated) for case, mutated in gzipped(data)]


def extreme_seeds(tmp, n=16, seed=1):
    """{(value, seed name): (extension, bytes)}: every seed with row 3's coordinates set to each extreme."""
    points = F.patch(n, seed)[0]
    out = {}
    for label, value in EXTREMES.items():
        bad = points.copy()
        bad[3] = value
        sub = tmp / f"extreme_{label}"
        sub.mkdir(exist_ok=True)
        for name, (ext, data) in F.seeds(sub, points=bad).items():
            out[(label, name)] = (ext, data)
    return out
