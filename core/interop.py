"""Point clouds of other libraries in, pyvista out: duck-typed, with no dependency on them.

:func:`unwrap` turns a ``pyvista.PolyData`` (any pyvista data set), an Open3D
``PointCloud``, a ``trimesh.PointCloud`` (or ``Trimesh``: its vertices), a
``laspy.LasData`` or a :class:`core.io.Cloud` into ``(points, normals)`` arrays, which is
what :func:`core.estimate` takes; the normals the object carries are used unless normals
are given. :func:`to_pyvista` makes a ``pyvista.PolyData`` of a result.
"""

from __future__ import annotations

from typing import Any, Callable, NamedTuple

import numpy as np

from ._validate import word
from .io.cloud import find_normals


class _Kind(NamedTuple):
    name: str
    matches: Callable[[Any], bool]
    points: Callable[[Any], Any]
    normals: Callable[[Any], Any]


def _pyvista_normals(obj):
    data = obj.point_data
    active = getattr(data, "active_normals", None)
    if active is not None:
        return active
    key = next((k for k in data.keys() if str(k).lower() == "normals"), None)
    return None if key is None else data[key]


def _las_normals(obj):
    names = find_normals(list(obj.point_format.dimension_names))
    return None if names is None else np.column_stack([np.asarray(obj[n], dtype=np.float64) for n in names])


#: the kinds of objects understood, tried in order (a registry, not an if-chain)
KINDS = (
    _Kind("laspy.LasData", lambda o: hasattr(o, "point_format") and all(hasattr(o, c) for c in "xyz"),
          lambda o: np.column_stack([np.asarray(o.x), np.asarray(o.y), np.asarray(o.z)]), _las_normals),
    _Kind("open3d PointCloud", lambda o: hasattr(o, "has_normals") and hasattr(o, "points"),
          lambda o: np.asarray(o.points), lambda o: np.asarray(o.normals) if o.has_normals() else None),
    _Kind("pyvista data set", lambda o: hasattr(o, "point_data") and hasattr(o, "points"),
          lambda o: np.asarray(o.points), _pyvista_normals),
    _Kind("trimesh", lambda o: hasattr(o, "vertices") and not isinstance(o, np.ndarray),
          lambda o: np.asarray(o.vertices), lambda o: None),
    _Kind("core.io.Cloud", lambda o: hasattr(o, "points") and hasattr(o, "normals") and not isinstance(o, np.ndarray),
          lambda o: o.points, lambda o: o.normals),
)


def kind_of(obj) -> str | None:
    """The name of the kind ``obj`` is understood as, or None for arrays and sequences."""
    if isinstance(obj, (np.ndarray, list, tuple)):
        return None
    return next((k.name for k in KINDS if k.matches(obj)), None)


def unwrap(points: Any, normals: Any = None) -> tuple[Any, Any]:
    """``(points, normals)``: arrays from a point-cloud object, or the arguments unchanged.

    Given ``normals`` win over the object's own; an object without normals gives None.
    """
    if isinstance(points, (np.ndarray, list, tuple)):
        return points, normals
    kind = next((k for k in KINDS if k.matches(points)), None)
    if kind is None:
        return points, normals
    own = kind.normals(points) if normals is None else normals
    return kind.points(points), (None if own is None else np.asarray(own))


def viewpoints(obj) -> np.ndarray | None:
    """The viewpoint of each point a :class:`core.io.Cloud` carries (the scanner positions
    of an E57 file's scans), or None for any other object."""
    if kind_of(obj) != "core.io.Cloud":
        return None
    return getattr(obj, "viewpoints", None)


def facing(obj, normals, orientation):
    """``orientation`` for :func:`core.estimate` of ``obj``'s points with ``normals`` in use:
    "auto" on a cloud that carries each point's viewpoint (an E57 file's scanners) with no
    normals in use is those viewpoints (what ``core.estimate(obj)`` does itself); else as given."""
    views = viewpoints(obj)
    if views is None or normals is not None or not isinstance(orientation, str) or word(orientation) != "auto":
        return orientation
    return views


def point_fields(result, scalars: dict) -> dict:
    """Every per-point array of a :class:`core.CurvatureResult`, by name; ``scalars`` maps
    the scalar fields' names to attributes (:data:`core.result.SCALAR_FIELDS`)."""
    fields = {name: getattr(result, attr) for name, attr in scalars.items()}
    for name in ("k1", "k2", "e1", "e2", "valid", "crease", "outlier"):
        fields[name] = getattr(result, name)
    return fields


def to_pyvista(result, scalars: dict) -> "pyvista.PolyData":  # noqa: F821 - imported lazily
    """A ``pyvista.PolyData`` of the result's points with its normals (active normals
    "Normals") and every per-point field as point data (see :func:`point_fields`); the
    active scalars are "mean"."""
    import pyvista as pv

    cloud = pv.PolyData(np.asarray(result.points, dtype=np.float64))
    for name, values in point_fields(result, scalars).items():
        cloud.point_data[name] = np.asarray(values)
    cloud.point_data["Normals"] = np.asarray(result.normals)
    cloud.point_data.active_normals_name = "Normals"
    cloud.point_data.active_scalars_name = "mean"
    return cloud
