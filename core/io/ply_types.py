"""The PLY header as plyfile is given it. Property types beyond the eight of the PLY
specification: ``int64``, ``uint64`` and ``float16``, which trimesh writes (and Metashape,
half-float colours), and which plyfile refuses, are read as what they say: plyfile parses
the header with a stand-in type of the same size in their place (float64 for the 8-byte
integers, int16 for float16), and the properties then get their own type back before any
data is read. Blanks at the ends of header lines are dropped ("end_header " was refused,
as RPly and tinyply do not), and an element that repeats a property name is refused by name.
"""

from __future__ import annotations

from plyfile import PlyListProperty

from .cloud import CloudFileError

#: type name in the header -> (numpy type code, stand-in type name of the same size)
EXTRA_TYPES = {b"int64": ("i8", b"float64"), b"uint64": ("u8", b"float64"), b"float16": ("f2", b"int16")}


def stand_in_types(header: bytes) -> tuple[bytes, dict]:
    """``header`` with the extra types replaced by their stand-ins (and blanks at the ends of
    lines removed: plyfile refused "ply " and "end_header "), and what to restore:
    {(element index, property name): (list count code or None, value code or None)}."""
    lines, restore, element = [], {}, -1
    for line in map(bytes.rstrip, header.splitlines()):
        words = line.split()
        if words[:1] == [b"element"]:
            element += 1
        elif words[:1] == [b"property"] and len(words) >= 3:
            types = words[2:4] if words[1] == b"list" and len(words) >= 5 else words[1:2]
            codes = [EXTRA_TYPES[t][0] if t in EXTRA_TYPES else None for t in types]
            if any(codes):
                words[1 + (len(types) == 2) : 1 + (len(types) == 2) + len(types)] = [
                    EXTRA_TYPES[t][1] if t in EXTRA_TYPES else t for t in types]
                line = b" ".join(words)
                restore[(element, words[-1].decode("ascii", "replace"))] = tuple([None] * (2 - len(codes)) + codes)
        lines.append(line)
    return b"\n".join(lines) + b"\n", restore


def restore_types(header, restore: dict) -> None:
    """Give the properties that :func:`stand_in_types` replaced their own type back."""
    for (index, name), (count_code, value_code) in restore.items():
        prop = header.elements[index].ply_property(name)
        if value_code is not None:
            prop._val_dtype = value_code  # plyfile's setter accepts only the standard names
        if count_code is not None and isinstance(prop, PlyListProperty):
            prop._len_dtype = count_code


def refuse_repeated_names(header: bytes, path) -> None:
    """Refuse an element whose properties repeat a name (plyfile refused it naming neither)."""
    element, names = None, []
    for line in header.splitlines() + [b"element"]:
        words = line.split()
        if words[:1] == [b"element"]:
            twice = sorted({name for name in names if names.count(name) > 1})
            if twice:
                raise CloudFileError(path, f"not a valid PLY header: element {element!r} declares the property "
                                           f"{', '.join(map(repr, twice))} more than once; each needs its own name")
            element, names = b" ".join(words[1:2]).decode("ascii", "replace"), []
        elif words[:1] == [b"property"] and len(words) >= 3:
            names.append(words[-1].decode("ascii", "replace"))
