"""The cloud being looked at: a file or a synthetic shape with its ground truth.

Pure data, no Qt. Loading runs wherever it is called (the viewer calls it on a
job thread, :mod:`app.loader`; files are read with :func:`core.io.read_cloud`).
"""

from __future__ import annotations

import itertools
import os
import types
import warnings
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

import core.io
import core.shapes
from core.degenerate import MAX_COORD
from core.io.cloud import require_points

from . import file_fields, scanners
from .geometry import CloudGeometry
from .text import display_name

_uids = itertools.count(1)


@dataclass(frozen=True, eq=False)
class CloudSource:
    """An input cloud as loaded, never modified (noise is applied to copies).

    Attributes
    ----------
    name : str
        Short label for titles ("bunny.ply", "torus (5000)").
    points : (N, 3) float array, read-only.
    normals : (N, 3) float array or None
        Normals that came with the file, or the exact normals of a shape.
    path : Path or None
        The file it was read from.
    sample : core.shapes.Sample or None
        Ground truth for synthetic shapes (enables the error fields).
    uid : int
        Identity used by the worker's caches (noisy copies, neighbours).
    notes : tuple of str
        What the reader warned about (columns it did not take for normals, ...), for the
        window to show once the cloud is loaded.
    viewpoints : (N, 3) float array or None
        Where each point was seen from (an E57 file's scanner positions): the default
        orientation faces them (:attr:`core.io.Cloud.viewpoints`).
    fields : mapping of str -> (N,) array, read-only
        The file's own per-point data the viewer can draw (:func:`app.file_fields.keep`:
        numeric ones; colour components, intensity, scan index, ...), in the points' order.
    """

    name: str
    points: np.ndarray
    normals: np.ndarray | None = None
    path: Path | None = None
    sample: object | None = None
    uid: int = field(default_factory=lambda: next(_uids))
    notes: tuple = ()
    viewpoints: np.ndarray | None = None
    fields: dict = field(default_factory=dict)

    def __post_init__(self):
        for arr in (self.points, self.normals, self.viewpoints, *self.fields.values()):
            if arr is not None:
                arr.flags.writeable = False
        object.__setattr__(self, "fields", types.MappingProxyType(dict(self.fields)))

    @property
    def n_points(self) -> int:
        return int(self.points.shape[0])

    @property
    def has_truth(self) -> bool:
        return self.sample is not None

    @cached_property
    def geometry(self) -> CloudGeometry:
        """Box, spacing, framing sample and drawing order (:mod:`app.geometry`); the loader
        computes it on its thread, so the GUI thread only reads it."""
        return CloudGeometry.of(self.points)

    @cached_property
    def field_specs(self) -> dict:
        """Field name ("rgb", "file:NAME") -> :class:`app.fields.FieldSpec` of the file's own
        fields (:func:`app.file_fields.specs_of`; the loader computes it on its thread)."""
        return file_fields.specs_of(self.fields)

    @cached_property
    def luminance(self) -> np.ndarray | None:
        """(N,) luminance of the file's colours (:data:`app.file_fields.LUMA`), which the histogram
        shows while they are drawn: computed once, not at each recolour; None without colours."""
        return None if self.colours is None else self.colours @ file_fields.LUMA

    @cached_property
    def scanners(self) -> np.ndarray:
        """(M, 3) distinct scanner positions of the viewpoints, in the order they first
        appear ((0, 3) without viewpoints; :func:`app.scanners.positions`; the loader
        computes it on its thread)."""
        return scanners.positions(self.viewpoints)

    @cached_property
    def colours(self) -> np.ndarray | None:
        """(N, 3) uint8 colours of the file (:func:`app.file_fields.colours_of`), or None."""
        rgb = file_fields.colours_of(self.fields)
        if rgb is not None:
            rgb.flags.writeable = False
        return rgb


def load_file(path) -> CloudSource:
    """Read a cloud with :func:`core.io.read_cloud`, without its rows with NaN/inf coordinates
    (as CloudCompare does, and from its fields as well); what the reader warns about (dropped
    rows, columns not taken for normals, ...) becomes the source's ``notes``.

    The reader's warnings are caught with :func:`warnings.catch_warnings`, which swaps the
    process-wide warning state while the file is read (Python < 3.14 has no per-thread one).
    Warnings of other threads in that time are not lost but re-issued after the read (from
    this thread); only the reader's own, which name the file, become notes.

    Raises
    ------
    core.io.CloudFileError
        With a message that names the file, when it cannot be read.
    """
    path = Path(os.fsdecode(path))
    with warnings.catch_warnings(record=True) as caught:  # the reader's warnings, kept for the window
        warnings.simplefilter("always", UserWarning)
        cloud = core.io.read_cloud(path, drop_nonfinite=True)
    ours = [w for w in caught if issubclass(w.category, UserWarning) and path.name in str(w.message)]
    for w in caught:
        if w not in ours:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    notes = tuple(dict.fromkeys(str(w.message) for w in ours))
    _refuse_undrawable(path, cloud.points)
    points = np.array(cloud.points, dtype=float, copy=True)
    normals = None if cloud.normals is None else np.array(cloud.normals, dtype=float, copy=True)
    views = None if cloud.viewpoints is None else np.array(cloud.viewpoints, dtype=float, copy=True)
    return CloudSource(name=display_name(path), points=points, normals=normals, path=path, notes=notes,
                       viewpoints=views, fields=file_fields.keep(cloud.fields, len(points)))


def _refuse_undrawable(path, points) -> None:
    """A file whose cloud the window can neither estimate nor draw is refused as unreadable
    ones are (the previous cloud stays): fewer than 3 points (core.estimate's least; the
    estimate failed with an API message and a hint to change a parameter), or no point within
    ``MAX_COORD`` (nothing to draw: an empty mesh raised inside a Qt slot and no estimate ran)."""
    require_points(path, len(points))
    with np.errstate(invalid="ignore"):
        if not (np.abs(points) <= MAX_COORD).all(axis=1).any():
            raise core.io.CloudFileError(path, f"every point has a coordinate beyond {MAX_COORD:g} (up to "
                                               f"{float(np.abs(points).max()):.3g}): nothing can be drawn or "
                                               "estimated; rescale the cloud")


def make_shape(name: str, n: int = 5000, *, seed: int = 0) -> CloudSource:
    """Sample a synthetic shape from :data:`core.shapes.SHAPES` (with exact truth)."""
    try:
        factory = core.shapes.SHAPES[name]
    except KeyError:
        valid = ", ".join(sorted(core.shapes.SHAPES))
        raise ValueError(f"shape {name!r} is unknown; valid shapes: {valid}") from None
    sample = factory(int(n), seed=seed)
    points = np.array(sample.points, dtype=float, copy=True)
    normals = np.array(sample.normals, dtype=float, copy=True)
    return CloudSource(name=f"{name} ({len(points):,} pts)", points=points, normals=normals, sample=sample)
