"""The on-disk state of a tiled run: binned tiles, per-tile results, what is finished.

Layout of the work directory (``.<output name>.tiles`` next to the output by default)::

    manifest.json          the input and parameters this directory belongs to
    plan.npz               the tiles (:class:`core.tiled.plan.TilePlan`)
    bins/fields.json       which of BIN_FIELDS the records hold (normals, viewpoints if any)
    bins/tile_000007.bin   the tile's own points (input order), raw records of those fields
    bins/spill.bin         the sampling pass's records in input order (removed once binned)
    bins/done.json         written last: the binning pass is complete
    results/tile_000007.npy, .links.npy, .nodes.npy, .done   one finished tile

Every file is written to a temporary name and renamed (atomic); a tile counts as finished
only once its ``.done`` marker exists, so a run killed at any moment resumes by redoing
only unfinished work. A directory whose manifest does not match the run is cleared of
what a run writes; one that holds other files and no manifest is refused, and nothing but
what a run wrote is ever deleted (``--work-dir`` names a folder the run's own lives in).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import pathlib
import shutil

import numpy as np

from ..io.atomic import atomic_write

#: what a run writes in its work directory (all that :meth:`TileStore.remove` deletes)
OWN = ("manifest.json", "plan.npz", "plan.tmp.npz", "bins", "results")
#: what a binned point can hold: coordinates, normals, viewpoint, input row
BIN_FIELDS = {"xyz": ("<f8", 3), "n": ("<f8", 3), "view": ("<f8", 3), "index": ("<i8",)}


def bin_dtype(normals: bool, views: bool) -> np.dtype:
    """Records of a binned point: 32 bytes, plus 24 with normals, 24 with viewpoints."""
    names = ["xyz"] + (["n"] if normals else []) + (["view"] if views else []) + ["index"]
    return np.dtype([(name, *BIN_FIELDS[name]) for name in names])


class TileStore:
    """Paths and atomic reads/writes of one run's work directory."""

    def __init__(self, root):
        self.root = pathlib.Path(root)

    # -- the run as a whole -------------------------------------------------------------
    def open(self, manifest: dict) -> bool:
        """Use the directory for the run described by ``manifest`` (JSON-able).

        Returns True when earlier work of the same run was found (a resume); a directory
        left by a different input or different parameters is emptied first.
        """
        path = self.root / "manifest.json"
        text = json.dumps(manifest, sort_keys=True)
        if path.exists():
            if path.read_text() == text:
                return True
            self.remove()
        elif self.root.is_dir() and any(self.root.iterdir()):
            raise ValueError(f"work directory {self.root} holds files that are not a tiled run's (no manifest.json); "
                             "give a new or empty directory (nothing in it was changed)")
        (self.root / "bins").mkdir(parents=True, exist_ok=True)
        (self.root / "results").mkdir(exist_ok=True)
        self._write_bytes(path, text.encode())
        return False

    def remove(self) -> None:
        """Delete what a run writes here (:data:`OWN`, and temporaries of its atomic
        writes), then the directory if that left it empty: never anything else in it."""
        for name in OWN:
            path = self.root / name
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
            elif path.exists() or path.is_symlink():
                path.unlink(missing_ok=True)
        for name in OWN:
            for temp in self.root.glob(f".{name}.*.tmp"):
                temp.unlink(missing_ok=True)
        with contextlib.suppress(OSError):
            self.root.rmdir()

    @property
    def plan_path(self) -> pathlib.Path:
        return self.root / "plan.npz"

    # -- binned input ---------------------------------------------------------------------
    def bin_path(self, tile: int) -> pathlib.Path:
        return self.root / "bins" / f"tile_{tile:06d}.bin"

    @property
    def spill_path(self) -> pathlib.Path:
        """Every record in input order, written by the sampling pass (until binned)."""
        return self.root / "bins" / "spill.bin"

    def set_bin_dtype(self, dtype: np.dtype) -> None:
        self._write_bytes(self.root / "bins" / "fields.json", json.dumps(list(dtype.names)).encode())
        self._dtype = dtype

    @property
    def bin_dtype(self) -> np.dtype:
        if getattr(self, "_dtype", None) is None:
            names = json.loads((self.root / "bins" / "fields.json").read_text())
            self._dtype = np.dtype([(name, *BIN_FIELDS[name]) for name in names])
        return self._dtype

    def binned(self) -> bool:
        return (self.root / "bins" / "done.json").exists()

    def mark_binned(self, counts) -> None:
        self._write_bytes(self.root / "bins" / "done.json", json.dumps([int(c) for c in counts]).encode())

    def bin_counts(self) -> list:
        return json.loads((self.root / "bins" / "done.json").read_text())

    def read_bin(self, tile: int) -> np.ndarray:
        """The tile's own points (a read-only memory map of :attr:`bin_dtype` records)."""
        path = self.bin_path(tile)
        if path.stat().st_size == 0:
            return np.zeros(0, dtype=self.bin_dtype)
        return np.memmap(path, dtype=self.bin_dtype, mode="r")

    # -- per-tile results -----------------------------------------------------------------
    def result_path(self, tile: int, part: str = "") -> pathlib.Path:
        return self.root / "results" / f"tile_{tile:06d}{part}.npy"

    def finished(self, tile: int) -> bool:
        return self._done_path(tile).exists()

    def mark_finished(self, tile: int) -> None:
        """The marker written after every file of a tile's result: a rerun skips the tile."""
        self._write_bytes(self._done_path(tile), b"")

    def _done_path(self, tile: int) -> pathlib.Path:
        return self.root / "results" / f"tile_{tile:06d}.done"

    def save_result(self, tile: int, rows: np.ndarray, links: np.ndarray, nodes: np.ndarray) -> None:
        """Write a tile's result (three arrays), then its marker: all or nothing."""
        for part, arr in (("", rows), (".links", links), (".nodes", nodes)):
            self.save_array(self.result_path(tile, part), arr)
        self.mark_finished(tile)

    def save_array(self, path, arr: np.ndarray) -> None:
        """``arr`` as a .npy file at ``path``, written atomically."""
        buf = io.BytesIO()
        np.save(buf, arr)
        self._write_bytes(path, buf.getvalue())

    def load_result(self, tile: int, part: str = "", mmap: bool = True) -> np.ndarray:
        return np.load(self.result_path(tile, part), mmap_mode="r" if mmap else None)

    @staticmethod
    def _write_bytes(path, data: bytes) -> None:
        with atomic_write(path, sweep=False) as f:  # its own folder: no sweep per file
            f.write(data)


def directory_for(output) -> pathlib.Path:
    """The default work directory of an output file: hidden, next to it."""
    out = pathlib.Path(os.path.abspath(os.fspath(output)))
    return out.with_name(f".{out.name}.tiles")
