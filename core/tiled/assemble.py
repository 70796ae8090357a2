"""The final file: every tile's own points, in input order, with the agreed signs, written
atomically (a failure leaves no partial file and an existing target untouched).

LAS/LAZ outputs are written chunk by chunk in bounded memory (each chunk of input rows is
found in every tile's result, sorted by input row, by binary search); PLY and text
outputs are built in memory, for results that fit.
"""

from __future__ import annotations

import os
import pathlib
from types import SimpleNamespace

import numpy as np

from ..anisotropy import striped
from ..frame import signed_directions
from ..io import write_result
from ..io.atomic import atomic_write
from ..io.cloud import CloudFileError
from ..io.las_stream import CHUNK, LasResultWriter, quantisation
from ..tuning import OUTLIER_SCORE
from .task import ROW_DTYPE, ROW_FLAGS

_LAS = (".las", ".laz")
#: largest result assembled in memory for PLY/text output (~250 bytes a point)
IN_MEMORY_MAX = 20_000_000


def assemble(store, n_tiles: int, n_points: int, signs, output, source) -> pathlib.Path:
    """Write the result of all tiles to ``output`` (LAS/LAZ streamed, else in memory)."""
    output = pathlib.Path(os.fspath(output))
    if output.suffix.lower() in _LAS:
        scales, offsets = _quantisation(store, n_tiles, source)
        like, records = source.las_records(CHUNK)  # the input's own fields, in step with the rows
        try:
            with atomic_write(output) as f, LasResultWriter(f, scales=scales, offsets=offsets, like=like,
                                                            laz=output.suffix.lower() == ".laz") as w:
                for start in range(0, n_points, CHUNK):
                    cols = _gather(store, n_tiles, signs, start, min(n_points, start + CHUNK))
                    w.write(cols.pop("xyz"), cols, None if records is None else next(records)[1])
        except OSError as exc:
            raise CloudFileError(output, f"cannot be written: {exc.strerror or exc}") from exc
        return output
    if n_points > IN_MEMORY_MAX:
        raise ValueError(f"{output}: {n_points} points are too many for a {output.suffix} output "
                         f"(at most {IN_MEMORY_MAX}); write .laz or .las instead")
    c = _gather(store, n_tiles, signs, 0, n_points)
    normals = np.stack([c["nx"], c["ny"], c["nz"]], axis=1)
    e1 = np.stack([c["e1_x"], c["e1_y"], c["e1_z"]], axis=1)
    e2 = np.stack([c["e2_x"], c["e2_y"], c["e2_z"]], axis=1)
    flags = {attr: c[name] for name, attr in ROW_FLAGS.items()}
    flags.update(k_point=c["k"], outlier=c["outlier"].astype(bool), striped=c["striped"].astype(bool))
    res = SimpleNamespace(points=c["xyz"], normals=normals, k1=c["k1"], k2=c["k2"], e1=e1, e2=e2,
                          gaussian=c["gaussian"], mean=c["mean"], valid=c["valid"].astype(bool), **flags)
    return write_result(output, res)


def _gather(store, n_tiles, signs, start, stop) -> dict:
    """Columns (named as in the LAS/PLY output) of input rows [start, stop)."""
    m = stop - start
    out = {"xyz": np.empty((m, 3)), "n": np.empty((m, 3)), "k1": np.empty(m), "k2": np.empty(m),
           "e1": np.empty((m, 3)), "e2": np.empty((m, 3)), "valid": np.zeros(m, np.uint8),
           "k": np.zeros(m, np.int32), **{name: np.zeros(m, ROW_DTYPE[name]) for name in ROW_FLAGS}}
    filled = 0
    for t in range(n_tiles):
        rows = store.load_result(t)
        if len(rows) == 0:
            continue
        index = rows["index"]
        lo, hi = np.searchsorted(index, start), np.searchsorted(index, stop)
        if lo == hi:
            continue
        part = np.asarray(rows[lo:hi])
        at = part["index"] - start
        sign = _row_signs(store, t, signs[t], part["comp"])
        flip = sign < 0
        out["xyz"][at], out["n"][at] = part["xyz"], part["n"] * sign[:, None]
        out["k1"][at] = np.where(flip, -part["k2"], part["k1"])  # flipping the normal: k1, k2 -> -k2, -k1
        out["k2"][at] = np.where(flip, -part["k1"], part["k2"])
        e1 = np.where(flip[:, None], part["e2"], part["e1"])  # ... and e1 <-> e2
        out["e1"][at], out["e2"][at] = signed_directions(e1, np.where(flip[:, None], part["e1"], part["e2"]))
        out["valid"][at], out["k"][at] = part["valid"], part["k"]
        for name in ROW_FLAGS:
            out[name][at] = part[name]
        filled += len(part)
    if filled != m:
        raise ValueError(f"tile results cover {filled} of input rows {start}..{stop - 1}; the work directory "
                         f"{store.root} is inconsistent: delete it and run again")
    cols = {"xyz": out["xyz"], "k1": out["k1"], "k2": out["k2"], "valid": out["valid"], "k": out["k"],
            "gaussian": out["k1"] * out["k2"], "mean": 0.5 * (out["k1"] + out["k2"]),
            **{name: out[name] for name in ROW_FLAGS},
            "outlier": (np.nan_to_num(out["outlier_score"]) > OUTLIER_SCORE).astype(np.uint8),
            "striped": striped(out["anisotropy"]).astype(np.uint8)}
    for name, arr in (("n", out["n"]), ("e1", out["e1"]), ("e2", out["e2"])):
        for j, c in enumerate("xyz"):
            cols[f"{name}{c}" if name == "n" else f"{name}_{c}"] = arr[:, j]
    return cols


def _row_signs(store, tile, node_signs, comp) -> np.ndarray:
    nodes = store.load_result(tile, ".nodes", mmap=False)
    sign = np.ones(len(comp))
    if len(nodes):
        pos = np.minimum(np.searchsorted(nodes["comp"], comp), len(nodes) - 1)
        hit = nodes["comp"][pos] == comp
        sign[hit] = node_signs[pos[hit]]
    return sign


def _quantisation(store, n_tiles, source):
    """The input's LAS scales/offsets, or :func:`quantisation` of the result's bounds."""
    if source.scales is not None:
        return source.scales, source.offsets
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for t in range(n_tiles):
        rows = store.load_result(t)
        if len(rows):
            lo, hi = np.minimum(lo, rows["xyz"].min(axis=0)), np.maximum(hi, rows["xyz"].max(axis=0))
    return quantisation(lo, hi)
