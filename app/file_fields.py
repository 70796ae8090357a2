"""A file's own per-point data as fields of the viewer: its colours ("rgb") and its other
numeric properties ("file:intensity", "file:scan", ...).

numpy only (the loader thread prepares them, :func:`app.source.load_file`). They come with
the cloud, not with the estimate: one value per input point, in the order of the points,
which a noisy copy keeps and a preview spreads back to (:mod:`app.worker`).
"""

from __future__ import annotations

import numpy as np

from .fields import FIELDS, FILE_PREFIX, RGB, FieldSpec

__all__ = ["keep", "colour_names", "colours_of", "specs_of", "listed", "find", "unknown_text", "point_values", "RGB_LABEL",
           "MAX_CATEGORIES", "LUMA"]

RGB_LABEL = "File colour (RGB)"
#: Weights of the luminance of an sRGB colour (Rec. 709), which the histogram shows of a file's colours.
LUMA = np.array([0.2126, 0.7152, 0.0722])
#: The fields holding a colour's components (every reader names them so; compared ignoring case).
COLOURS = ("red", "green", "blue")
#: An integer field whose values span at most this many integers is drawn one colour a value.
MAX_CATEGORIES = 20


def keep(fields: dict, n: int) -> dict:
    """The fields of a file the viewer can draw: numeric (N,) arrays, read-only (booleans
    as 0/1); other dtypes (text, complex) or shapes are left out."""
    out = {}
    for name, values in fields.items():
        arr = np.asarray(values)
        if arr.shape != (n,) or not (arr.dtype == bool or arr.dtype.kind in "iuf"):
            continue
        arr = np.ascontiguousarray(arr, dtype=np.uint8 if arr.dtype == bool else arr.dtype)
        arr.flags.writeable = False
        out[str(name)] = arr
    return out


def colour_names(fields) -> tuple | None:
    """The names of the red, green and blue fields (as spelled in ``fields``), or None."""
    lower = {name.lower(): name for name in fields}
    return tuple(lower[c] for c in COLOURS) if all(c in lower for c in COLOURS) else None


def colours_of(fields) -> np.ndarray | None:
    """(N, 3) uint8 colours of the red, green and blue fields, or None without them.

    8-bit colours are kept; 16-bit ones (LAS stores 16 bits, many files use only 0-255 of
    them) are divided by 257 only when a component exceeds 255 (65535 -> 255); floats of
    at most 1 are fractions (x 255). The scale is the same for the three components."""
    names = colour_names(fields)
    if names is None:
        return None
    rgb = np.column_stack([np.asarray(fields[n], dtype=np.float32) for n in names])
    rgb = np.nan_to_num(rgb, nan=0.0, posinf=255.0, neginf=0.0)
    top = float(rgb.max()) if rgb.size else 0.0
    if top > 255.0:
        rgb /= 257.0
    elif top <= 1.0 and any(np.asarray(fields[n]).dtype.kind == "f" for n in names):
        rgb *= 255.0
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8)


def _categories(values: np.ndarray) -> dict:
    """A categorical look for integer values spanning at most :data:`MAX_CATEGORIES` integers."""
    finite = values if values.dtype.kind in "iu" else values[np.isfinite(values)]
    if not finite.size or (values.dtype.kind == "f" and not np.array_equal(finite, np.rint(finite))):
        return {}
    lo, hi = float(finite.min()), float(finite.max())
    if hi - lo + 1 > MAX_CATEGORIES:
        return {}
    return {"scale": "categorical", "span": (lo - 0.5, hi + 0.5)}


def specs_of(fields: dict) -> dict:
    """Field name -> :class:`app.fields.FieldSpec` of a file's fields: "rgb" first when it has
    red, green and blue (which then are not listed one by one), then "file:NAME" in the
    file's order."""
    out = {}
    rgb = colour_names(fields)
    if rgb is not None:
        out[RGB] = FieldSpec(RGB, RGB_LABEL, False, needs="file", scale="rgb")
    for name, values in fields.items():
        if rgb is None or name not in rgb:
            key = FILE_PREFIX + name
            out[key] = FieldSpec(key, f"File: {name}", False, needs="file", **_categories(values))
    return out


def _varies(values: np.ndarray) -> bool:
    """Whether ``values`` hold two different numbers (NaN aside)."""
    finite = values if values.dtype.kind in "iu" else values[np.isfinite(values)]
    return finite.size > 1 and bool(finite.min() != finite.max())


def listed(specs: dict, fields: dict, keep: str | None = None) -> dict:
    """Field name -> title of the fields of ``specs`` worth a row in the Field box: those
    whose values vary. A field of one value at every point (LAS's unused flags and user
    data, colours a format stores but the scanner left at 0) would draw the cloud in one
    colour; CloudCompare's LAS import leaves such fields out the same way. They stay in
    ``specs`` (the command line's ``--field`` still draws them), and ``keep`` (the field
    shown) is listed whatever its values."""
    out = {}
    for key, spec in specs.items():
        names = colour_names(fields) if key == RGB else (key[len(FILE_PREFIX):],)
        if key == keep or any(_varies(np.asarray(fields[n])) for n in names):
            out[key] = spec.title
    return out


def find(name: str, specs: dict) -> str | None:
    """The key of ``specs`` that field ``name`` ("rgb", "file:NAME") means: itself, or the one
    spelled the same ignoring case (a command line's "file:Intensity"); None if none is."""
    if name in specs:
        return name
    same = [key for key in specs if key.lower() == str(name).lower()]
    return same[0] if len(same) == 1 else None


def unknown_text(name: str, specs: dict, cloud_name: str) -> str:
    """The command line's error for a field the file has not: as :func:`app.fields.resolve_field`
    says it of an unknown field, with what this file offers."""
    own = ", ".join(specs) if specs else "none"
    return (f"field {name!r} is unknown for {cloud_name}; valid fields: {', '.join(FIELDS)}; "
            f"the file's own: {own}")


def point_values(fields: dict, index: int) -> dict:
    """Label -> value of every file field at point ``index`` (the picked-point panel)."""
    return {f"file: {name}": values[index].item() for name, values in fields.items()}
