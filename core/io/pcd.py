"""PCL's PCD format: DATA ascii, binary and binary_compressed (LZF, decoded in Python).

Fields x y z are the points, normal_x normal_y normal_z (or nx ny nz) the normals;
a packed ``rgb``/``rgba`` field becomes uint8 fields red, green, blue (in ASCII, a TYPE F
colour written as an integer, as PCL writes it, is that uint32; a float token keeps its
bits); ``_`` padding is skipped; a field with COUNT 3 becomes name_x/_y/_z, other counts
name_0, name_1, ... ASCII 8-byte integers are parsed exactly, not through float64. Binary
data is read as little-endian; a point count that does not match the data is refused.
"""

from __future__ import annotations

import warnings

import numpy as np

from .cloud import (CloudFileError, RawCloud, check_memory, find_normals, format_number, is_padding, remaining_bytes,
                    split_components)
from .text import diagnose_lines

_MAX_HEADER_LINES = 100
_TYPES = {"F": "f", "I": "i", "U": "u"}
_SIZES = ("1", "2", "4", "8")
_PACKED = ("rgb", "rgba")
_UINT32_MAX = 0xFFFFFFFF


def read_pcd(path) -> RawCloud:
    """Points, normals and other fields of a PCD file."""
    with open(path, "rb") as f:
        header, n_header_lines = _read_header(f, path)
        fields, n = _layout(header, path)
        mode = header["DATA"][0].lower() if header["DATA"] else ""
        if mode == "ascii":
            props = _read_ascii(path, fields, n, n_header_lines)
        elif mode == "binary":
            props = _read_binary(f, path, fields, n)
        elif mode == "binary_compressed":
            props = _read_compressed(f, path, fields, n)
        else:
            raise CloudFileError(path, f"unknown DATA type {mode!r}; expected ascii, binary or binary_compressed")
    return _raw_from_props(props, path)


def _read_header(f, path):
    header = {}
    for lineno in range(1, _MAX_HEADER_LINES + 1):
        line = f.readline()
        if not line:
            raise CloudFileError(path, "truncated: the PCD header ends before its DATA line")
        text = line.decode("ascii", "replace").split("#", 1)[0].strip()
        if not text:
            continue
        key, *values = text.split()
        header[key.upper()] = values
        if key.upper() == "DATA":
            return header, lineno
    raise CloudFileError(path, f"not a PCD file: no DATA line in the first {_MAX_HEADER_LINES} lines")


def _layout(header, path):
    """[(name, numpy dtype string, count)] and the number of points."""
    for key in ("FIELDS", "SIZE", "TYPE"):
        if key not in header:
            raise CloudFileError(path, f"the PCD header has no {key} line")
    names, sizes, types = header["FIELDS"], header["SIZE"], header["TYPE"]
    counts = header.get("COUNT", ["1"] * len(names))
    if not len(names) == len(sizes) == len(types) == len(counts):
        raise CloudFileError(path, f"the PCD header lists {len(names)} FIELDS but {len(sizes)} SIZE, "
                                   f"{len(types)} TYPE and {len(counts)} COUNT entries")
    bad = next(((name, size) for name, size in zip(names, sizes) if size not in _SIZES), None)
    if bad is not None:  # numpy would take "4," as a structured dtype
        raise CloudFileError(path, f"the PCD header gives field {bad[0]!r} SIZE {bad[1]!r}; allowed: {', '.join(_SIZES)}")
    fields = [_field(path, i, *entry) for i, entry in enumerate(zip(names, sizes, types, counts))]
    _check_unique(path, [name for name, _, _ in fields])
    return fields, _point_count(path, header)


def _point_count(path, header) -> int:
    """POINTS, or without it WIDTH x HEIGHT (HEIGHT 1 if not given)."""
    if "POINTS" not in header and "WIDTH" not in header:
        raise CloudFileError(path, "the PCD header has no POINTS or WIDTH line")
    n = 1
    for key in ("POINTS",) if "POINTS" in header else ("WIDTH", "HEIGHT"):
        value = " ".join(header.get(key, ["1"]))
        if not value.isdigit():
            raise CloudFileError(path, f"the PCD header gives {key} {value!r}; it must be an integer >= 0")
        n *= int(value)
    return n


def _field(path, i: int, name: str, size: str, kind: str, count: str):
    """(name, numpy dtype string, count) of one PCD field; an unnamed field "_" is called _<i>."""
    if kind.upper() not in _TYPES:
        raise CloudFileError(path, f"the PCD header gives field {name!r} TYPE {kind!r}; allowed: F, I, U")
    if not count.isdigit() or int(count) < 1:
        raise CloudFileError(path, f"the PCD header gives field {name!r} COUNT {count!r}; a count is an integer >= 1")
    try:
        dtype = np.dtype("<" + _TYPES[kind.upper()] + size)
    except TypeError:  # a float of 1 byte
        raise CloudFileError(path, f"the PCD header gives field {name!r} TYPE {kind!r} SIZE {size!r}; a float (F) "
                                   "has SIZE 4 or 8") from None
    return name if name != "_" else f"_{i}", dtype.str, int(count)


def _check_unique(path, names) -> None:
    """Refuse a field listed twice (ASCII kept its last column, numpy's dtype refused it in binary)."""
    seen = set()
    for name in names:
        if name in seen:
            raise CloudFileError(path, f"malformed PCD header: field {name!r} occurs more than once in FIELDS")
        seen.add(name)


def _read_ascii(path, fields, n, n_header_lines):
    ncols = sum(count for _, _, count in fields)
    exact = _exact_columns(fields)
    table, columns = _load_ascii(path, n_header_lines, ncols, exact)
    if len(table) and table.shape[1] != ncols:
        raise CloudFileError(path, f"the data lines have {table.shape[1]} columns but the header declares {ncols}")
    if len(table) != n:
        problem = "truncated: " if len(table) < n else ""
        raise CloudFileError(path, f"{problem}the header declares {n} points but {len(table)} data lines follow")
    if columns is None:  # a token loadtxt's integer parse refused: parse the exact columns from their text
        columns = _exact_from_text(path, n_header_lines, fields, exact, table)
    props, col = {}, 0
    for name, dtype, count in fields:
        if col in exact:
            block = np.column_stack([columns[c] for c in range(col, col + count)])
            block = _colour(path, block, name) if dtype == "<f4" else block
        else:
            block = _ascii_block(path, table[:, col : col + count], name, np.dtype(dtype))
        props[name] = block[:, 0] if count == 1 else block
        col += count
    return props


def _exact_columns(fields) -> dict:
    """{column: loadtxt dtype} of the columns not read through float64: 8-byte integers, and
    packed colours (a uint32 when PCL wrote one)."""
    exact, col = {}, 0
    for name, dtype, count in fields:
        if np.dtype(dtype).kind in "iu" and np.dtype(dtype).itemsize == 8:
            exact.update((c, dtype) for c in range(col, col + count))
        elif name in _PACKED and dtype == "<f4" and count == 1:
            exact[col] = "<u8"
        col += count
    return exact


def _loadtxt(path, skip, dtype, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return np.loadtxt(path, dtype=dtype, comments="#", skiprows=skip, encoding="latin-1", **options)


def _load_ascii(path, skip, ncols, exact):
    """The data as a float64 table, and {column: values} of the ``exact`` columns when one
    pass with them parsed as integers succeeds (None: read them from their text)."""
    if exact:
        dtype = np.dtype([(str(c), exact.get(c, "<f8")) for c in range(ncols)])
        try:
            data = _loadtxt(path, skip, dtype, ndmin=1)
        except ValueError:
            pass  # a float colour, a bad token or line: read as float64, then each exact column
        else:
            table = np.column_stack([data[str(c)].astype(np.float64) for c in range(ncols)]).reshape(-1, ncols)
            return table, {c: data[str(c)] for c in exact}
    try:
        return _loadtxt(path, skip, np.float64, ndmin=2), None
    except ValueError as exc:
        head = dict(first=skip + 1, ncols=ncols, delimiter=None, declared="the header's FIELDS and COUNT declare")
        raise diagnose_lines(path, "latin-1", head, exc) from None


def _exact_from_text(path, skip, fields, exact, table) -> dict:
    """The exact columns parsed from their tokens: integers exactly, colours as integers or
    float bits (the text is read again only for colours with integral values >= 1)."""
    declared = [(name, np.dtype(dtype)) for name, dtype, count in fields for _ in range(count)]
    columns = {}
    for c in exact:
        name, dtype = declared[c]
        values = table[:, c]
        if dtype.kind == "f" and not (np.isfinite(values) & (values >= 1) & (values == np.round(values))).any():
            columns[c] = _ascii_block(path, values[:, None], name, dtype)[:, 0].view("<u4")  # float tokens only
    text = sorted(set(exact) - set(columns))
    tokens = _loadtxt(path, skip, str, usecols=text, ndmin=2) if text else None
    for j, c in enumerate(text):
        name, dtype = declared[c]
        parse = _packed_colour if dtype.kind == "f" else _exact_integers
        columns[c] = parse(path, tokens[:, j], name, dtype)
    return columns


def _exact_integers(path, tokens, name, dtype):
    """8-byte integer tokens parsed exactly; integral floats ("5.0") up to 2**53 are taken."""
    try:
        return tokens.astype(dtype)
    except (ValueError, OverflowError):
        pass
    info, values = np.iinfo(dtype), []
    for row, token in enumerate(tokens.tolist()):
        value = _integer(token)
        if value is None or not info.min <= value <= info.max:
            raise CloudFileError(path, f"point {row}: field {name!r} (TYPE {dtype.kind.upper()} SIZE 8) has the value "
                                       f"{token}, not an integer in [{info.min}, {info.max}]")
        values.append(value)
    return np.array(values, dtype=dtype)


def _integer(token: str):
    """The integer ``token`` spells (an integral float only up to 2**53, where it is exact), or None."""
    try:
        return int(token)
    except ValueError:
        value = float(token)  # the float64 pass parsed every token
    return int(value) if value.is_integer() and abs(value) <= 2**53 else None


def _packed_colour(path, tokens, name, dtype):
    """A colour field's tokens as uint32: an integer token is the colour (PCL's writeASCII
    writes it so), a float token holds it in its bits (as a binary PCD does)."""
    digits = np.char.isdecimal(tokens)
    floats = np.where(digits, "0", tokens).astype(np.float64)
    values = _ascii_block(path, floats[:, None], name, dtype)[:, 0].view("<u4").astype(np.uint64)
    values[digits] = [min(int(token), _UINT32_MAX + 1) for token in tokens[digits].tolist()]  # 2**64 fits no uint64
    return _colour(path, values, name, tokens)


def _colour(path, values, name, tokens=None):
    """Packed colours as uint32; an integer beyond 32 bits is refused."""
    bad = values.reshape(-1) > _UINT32_MAX
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        value = values.reshape(-1)[row] if tokens is None else tokens[row]
        raise CloudFileError(path, f"point {row}: field {name!r} (a packed colour, TYPE F SIZE 4) has the integer "
                                   f"value {value}, not a colour in [0, {_UINT32_MAX}]")
    return values.astype("<u4")


def _ascii_block(path, values, name, dtype):
    """ASCII values in the declared type; integers out of range or with a fraction are refused
    (a cast would wrap 1000 to -24 in a 1-byte I), and so are finite numbers beyond a 4-byte
    F's range (the cast made them inf with numpy's overflow warning)."""
    if dtype.kind == "f":
        with np.errstate(over="ignore"):
            cast = values.astype(dtype)
        bad = np.isfinite(values) & ~np.isfinite(cast)
        if bad.any():
            row = int(np.flatnonzero(bad.any(axis=1))[0])
            raise CloudFileError(path, f"point {row}: field {name!r} (TYPE F SIZE {dtype.itemsize}) has the value "
                                       f"{values[row][bad[row]][0]:g}, beyond the range of its type")
        return cast
    if dtype.kind in "iu":
        info = np.iinfo(dtype)
        bad = (values < info.min) | (values > info.max) | (values != np.round(values))
        if bad.any():
            row = int(np.flatnonzero(bad.any(axis=1))[0])
            value = values[row][bad[row]][0]
            raise CloudFileError(
                path, f"point {row}: field {name!r} (TYPE {dtype.kind.upper()} SIZE {dtype.itemsize}) has the value "
                f"{format_number(value)}, not an integer in [{info.min}, {info.max}]",
            )
    return values.astype(dtype)


def _read_binary(f, path, fields, n):
    """The records of DATA binary; fewer bytes than declared, or a whole record more, refused."""
    dtype = np.dtype([(name, dt, (count,)) if count > 1 else (name, dt) for name, dt, count in fields])
    need, have = n * dtype.itemsize, remaining_bytes(f)
    if have < need:
        raise CloudFileError(
            path, f"truncated: the header declares {n} points ({need} bytes) but only {have} bytes follow"
        )
    if have - need >= dtype.itemsize:
        raise CloudFileError(
            path, f"the header declares {n} points ({need} bytes) but {have} bytes follow, "
            f"{have // dtype.itemsize} points of {dtype.itemsize} bytes; the point count does not match the data"
        )
    body = f.read(have)
    if not is_padding(body[need:], b"\r\n"):  # bytes inserted into the records shifted those after them
        raise CloudFileError(path, f"the header declares {n} points ({need} bytes) but {have} bytes follow, "
                                   f"{have - need} more, less than a point and not a newline: bytes "
                                   "were inserted into the data, shifting the points after them; the file is damaged")
    data = np.frombuffer(body, dtype=dtype, count=n)
    return {name: data[name] for name in dtype.names}


def _read_compressed(f, path, fields, n):
    sizes = f.read(8)
    if len(sizes) < 8:
        raise CloudFileError(path, "truncated: the compressed PCD data has no size header")
    packed, unpacked = np.frombuffer(sizes, dtype="<u4").tolist()
    if remaining_bytes(f) < packed:
        raise CloudFileError(
            path, f"truncated: the header declares {packed} compressed bytes but only {remaining_bytes(f)} follow"
        )
    need = n * sum(np.dtype(dt).itemsize * count for _, dt, count in fields)
    if unpacked != need:
        raise CloudFileError(path, f"the compressed data expands to {unpacked} bytes but {n} points need {need}")
    # the decoder's output grows to `unpacked` bytes, then is copied: a 48 MB file may ask for 4 GB
    check_memory(path, 2 * unpacked, f"decompressing its {unpacked} bytes of points needs")
    data = f.read(packed)
    try:
        raw = lzf_decompress(data, unpacked)
    except ValueError as exc:
        raise CloudFileError(path, f"corrupt compressed PCD data: {exc}") from None
    props, offset = {}, 0
    for name, dt, count in fields:  # column-major: all values of a field, then the next field
        values = np.frombuffer(raw, dtype=dt, count=n * count, offset=offset)
        props[name] = values.reshape(n, count) if count > 1 else values
        offset += values.nbytes
    return props


def lzf_decompress(data: bytes, size: int) -> bytes:
    """Decompress an LZF (liblzf) block whose decompressed length is ``size``."""
    out = bytearray()
    i, end = 0, len(data)
    while i < end:
        ctrl = data[i]
        i += 1
        if ctrl < 32:  # a run of ctrl + 1 literal bytes
            run = ctrl + 1
            if i + run > end:
                raise ValueError("literal run past the end of the input")
            out += data[i : i + run]
            i += run
            continue
        length = ctrl >> 5  # a back reference
        if length == 7:
            if i >= end:
                raise ValueError("back reference past the end of the input")
            length += data[i]
            i += 1
        if i >= end:
            raise ValueError("back reference past the end of the input")
        start = len(out) - ((ctrl & 0x1F) << 8) - data[i] - 1
        i += 1
        length += 2
        if start < 0:
            raise ValueError("back reference before the start of the output")
        chunk = out[start : start + length]
        if len(chunk) < length:  # the reference overlaps what it writes: repeat the period
            chunk = (chunk * (length // len(chunk) + 1))[:length]
        out += chunk
        if len(out) > size:
            raise ValueError(f"output exceeds the declared {size} bytes")
    if len(out) != size:
        raise ValueError(f"decompressed {len(out)} bytes, expected {size}")
    return bytes(out)


def _lower_case(props) -> dict:
    """``props`` with lower-case names where x, y, z are spelled otherwise (FIELDS X Y Z) and
    the lower-case names stay distinct; else ``props``."""
    lower = {name.lower() for name in props}
    if all(c in props for c in "xyz") or not {"x", "y", "z"} <= lower or len(lower) != len(props):
        return props
    return {name.lower(): values for name, values in props.items()}


def _raw_from_props(props, path) -> RawCloud:
    props = _lower_case(props)
    if not all(c in props for c in "xyz"):
        raise CloudFileError(path, f"the PCD file has no x, y, z fields (found: {', '.join(props)})")
    points = np.column_stack([props[c] for c in "xyz"])
    nrm = find_normals(props)
    normals = None if nrm is None else np.column_stack([props[name] for name in nrm])
    fields = {}
    for name, values in props.items():
        if name in ("x", "y", "z") or name in (nrm or ()) or name.startswith("_"):
            continue
        if name in ("rgb", "rgba") and values.ndim == 1 and values.dtype.itemsize == 4:
            fields.update(_unpack_rgb(values))
        else:
            fields.update(split_components(name, values))
    return RawCloud(points, normals, fields)


def _unpack_rgb(values):
    packed = np.ascontiguousarray(values).view("<u4")
    return {name: ((packed >> shift) & 0xFF).astype(np.uint8) for name, shift in
            (("red", 16), ("green", 8), ("blue", 0))}
