"""Where the points of a tiled run come from: a LAS/LAZ file read in chunks, an E57 file
read scan by scan (each scan's pose gives its points' viewpoint, the scanner position),
any other cloud file read once (with its viewpoints, a PTX file's scanners), or an array; all
seen as a stream of ``(start, points, normals, viewpoints)``."""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

import numpy as np

from .._validate import as_normals, as_points
from ..io import read_cloud
from ..io.read import readable_file
from ..io.e57 import E57Scans
from ..io.las_open import open_reader
from ..io.las_stream import CHUNK, iter_las, iter_records, open_las

_STREAMED = (".las", ".laz")
_E57 = (".e57",)


@dataclass(frozen=True)
class Source:
    """A cloud to estimate in tiles.

    Attributes
    ----------
    name : the file (or "array"), for messages.
    count : number of points.
    has_normals : the source carries normals (they are then kept, as in memory).
    has_views : the source carries a viewpoint per point (E57 and PTX scanner positions).
    identity : what makes two runs on this source the same (path, size, mtime).
    scales, offsets : LAS coordinate quantisation to reuse when writing LAS/LAZ, or None.
    """

    name: str
    count: int
    has_normals: bool
    identity: tuple
    has_views: bool = False
    scales: object = None
    offsets: object = None
    _path: object = None
    _points: object = None
    _normals: object = None
    _views: object = None

    @property
    def is_file(self) -> bool:
        """Read from a file (each pass over it decompresses it again), not an array."""
        return self._path is not None

    def las_records(self, chunk: int = CHUNK):
        """``(laspy header, iterator of (start, laspy record))`` of a LAS/LAZ source in input
        order, for its own fields to be carried into a LAS/LAZ output; ``(None, None)`` else."""
        if self._path is None or not str(self._path).lower().endswith((".las", ".laz")):
            return None, None
        with open_reader(self._path) as reader:
            header = reader.header
        return header, iter_records(self._path, chunk=chunk)

    def chunks(self, chunk: int = CHUNK):
        """Yield ``(start, points (m, 3), normals (m, 3) or None, viewpoints (m, 3) or None)``
        in input order."""
        if self._path is not None and str(self._path).lower().endswith(_E57):  # read scan by scan
            yield from _iter_e57(self._path, chunk)
            return
        if self._path is not None:  # LAS/LAZ, streamed
            for start, pts, nrm in iter_las(self._path, chunk=chunk):
                yield start, pts, nrm, None
            return
        for start in range(0, self.count, chunk):
            stop = min(self.count, start + chunk)
            nrm = None if self._normals is None else self._normals[start:stop]
            view = None if self._views is None else self._views[start:stop]
            yield start, self._points[start:stop], nrm, view


def open_source(source, normals=None, *, use_normals: bool = True, drop_nonfinite: bool = False) -> Source:
    """A :class:`Source` from a path (LAS/LAZ streamed) or an (N, 3) array (+ normals);
    ``use_normals=False`` ignores normals stored in the file; ``drop_nonfinite`` drops the
    points with NaN/inf coordinates of a cloud read whole or given as an array."""
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        readable_file(path)  # a missing file is a bad input (CloudFileError), as read_cloud says it
        stat = os.stat(path)
        identity = (os.path.abspath(path), stat.st_size, stat.st_mtime_ns)
        if path.lower().endswith(_STREAMED):
            info = open_las(path)
            return Source(path, info.count, use_normals and info.normals is not None, identity, scales=info.scales,
                          offsets=info.offsets, _path=path)
        if path.lower().endswith(_E57):
            return Source(path, _e57_count(path), False, identity, has_views=True, _path=path)
        cloud = read_cloud(path, drop_nonfinite=drop_nonfinite)
        return _from_arrays(path, cloud.points, cloud.normals if use_normals else None, identity, cloud.viewpoints)
    pts, kept = as_points(source, drop_nonfinite=drop_nonfinite)
    if normals is not None and not kept.all():  # the dropped points' normals go with them
        normals = np.asarray(normals)[kept]
    nrm = None if normals is None else as_normals(normals, len(pts))
    digest = hashlib.blake2b(pts.tobytes(), digest_size=16).hexdigest()
    return _from_arrays("array", pts, nrm, ("array", len(pts), digest))


def _from_arrays(name, points, normals, identity, views=None) -> Source:
    if len(points) < 3:
        raise ValueError(f"{name}: points must hold at least 3 points, got {len(points)}")
    return Source(name, len(points), normals is not None, identity, has_views=views is not None, _points=points,
                  _normals=None if normals is None else np.asarray(normals, dtype=np.float64), _views=views)


def _e57_count(path) -> int:
    """Points declared by the scans' headers (invalid points, if any, are left out later)."""
    with E57Scans(path) as scans:
        return sum(scans.layout(i).count for i in range(len(scans)))


def _iter_e57(path, chunk):
    """Each scan in world coordinates, its valid points in chunks, the scanner position
    (the pose's translation) as their viewpoint."""
    with E57Scans(path) as scans:
        start = 0
        for index in range(len(scans)):
            pts, _, view = scans.read(index)
            for first in range(0, len(pts), chunk):
                part = pts[first:first + chunk]
                yield start, part, None, np.broadcast_to(view, part.shape)
                start += len(part)
