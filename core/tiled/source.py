"""Where the points of a tiled run come from: a LAS/LAZ file read in chunks, any other
cloud file read once, or an array; all seen as a stream of ``(start, points, normals)``."""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

import numpy as np

from .._validate import as_normals, as_points
from ..io import read_cloud
from ..io.las_stream import CHUNK, iter_las, open_las

_STREAMED = (".las", ".laz")


@dataclass(frozen=True)
class Source:
    """A cloud to estimate in tiles.

    Attributes
    ----------
    name : the file (or "array"), for messages.
    count : number of points.
    has_normals : the source carries normals (they are then kept, as in memory).
    identity : what makes two runs on this source the same (path, size, mtime).
    scales, offsets : LAS coordinate quantisation to reuse when writing LAS/LAZ, or None.
    """

    name: str
    count: int
    has_normals: bool
    identity: tuple
    scales: object = None
    offsets: object = None
    _path: object = None
    _points: object = None
    _normals: object = None

    def chunks(self, chunk: int = CHUNK):
        """Yield ``(start, points (m, 3), normals (m, 3) or None)`` in input order."""
        if self._path is not None:
            yield from iter_las(self._path, chunk=chunk)
            return
        for start in range(0, self.count, chunk):
            stop = min(self.count, start + chunk)
            nrm = None if self._normals is None else self._normals[start:stop]
            yield start, self._points[start:stop], nrm


def open_source(source, normals=None) -> Source:
    """A :class:`Source` from a path (LAS/LAZ streamed) or an (N, 3) array (+ normals)."""
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        stat = os.stat(path)
        identity = (os.path.abspath(path), stat.st_size, stat.st_mtime_ns)
        if path.lower().endswith(_STREAMED):
            info = open_las(path)
            return Source(path, info.count, info.normals is not None, identity, info.scales, info.offsets,
                          _path=path)
        cloud = read_cloud(path)
        return _from_arrays(path, cloud.points, cloud.normals, identity)
    pts, _ = as_points(source)
    nrm = None if normals is None else as_normals(normals, len(pts))
    digest = hashlib.blake2b(pts.tobytes(), digest_size=16).hexdigest()
    return _from_arrays("array", pts, nrm, ("array", len(pts), digest))


def _from_arrays(name, points, normals, identity) -> Source:
    if len(points) < 3:
        raise ValueError(f"{name}: points must hold at least 3 points, got {len(points)}")
    return Source(name, len(points), normals is not None, identity, _points=points,
                  _normals=None if normals is None else np.asarray(normals, dtype=np.float64))
