"""ASTM E57 laser scans, read with pye57's binding of libE57: each scan's valid points in
world coordinates (spherical coordinates converted, the scan's pose applied) and the
position of its scanner, the viewpoint of its points. :func:`read_e57` reads every scan for
:func:`core.io.read_cloud`; the tiled source reads one scan at a time through :class:`E57Scans`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .cloud import CloudFileError, RawCloud, Scan, check_memory, joined_scans

#: records libE57 decodes per call, into buffers reused for every block of a scan
BLOCK = 1 << 18
_XYZ = ("cartesianX", "cartesianY", "cartesianZ")
_RAE = ("sphericalRange", "sphericalAzimuth", "sphericalElevation")
_INVALID = ("cartesianInvalidState", "sphericalInvalidState")
#: E57 colour fields -> the names core's other readers (PLY, LAS, PCD, text) give colours
_COLOURS = {"colorRed": "red", "colorGreen": "green", "colorBlue": "blue"}
_HINT = " (a damaged header, or a file to estimate in tiles: `darboux-cli estimate --tile-points ...`)"


class Layout(NamedTuple):
    """What a scan's header says, before any point is read."""

    count: int  # records declared (invalid ones included)
    coords: tuple  # _XYZ or _RAE
    dtypes: dict  # E57 field -> dtype of its buffer, for every field the scan has that is read
    rotation: np.ndarray | None  # (3, 3), None when the scan has no pose
    translation: np.ndarray  # (3,) the scanner position

    @property
    def extras(self) -> set:
        """The optional fields the scan has: "intensity", and "colour" when it has all three."""
        return {"intensity"} & set(self.dtypes) | ({"colour"} if set(_COLOURS) <= set(self.dtypes) else set())

    def bytes_per_point(self, extras) -> int:
        """Bytes a read point takes: float64 coordinates and the extra fields."""
        return 24 + sum(np.dtype(self.dtypes[name]).itemsize for name in _extra_fields(extras) if name in self.dtypes)


def read_e57(path) -> RawCloud:
    """Every scan's valid points, one after another in world coordinates; fields ``intensity``
    and ``red``, ``green``, ``blue`` when every scan has them, ``scan`` (int32, the scan's
    index); each point's viewpoint is its scan's scanner position."""
    with E57Scans(path) as scans:
        layouts = [scans.layout(i) for i in range(len(scans))]
        if not layouts:
            raise CloudFileError(path, "contains no points (the file holds no scans)")
        extras = set.intersection(*(layout.extras for layout in layouts))
        count = sum(layout.count for layout in layouts)
        per_point = max(layout.bytes_per_point(extras) for layout in layouts) + 24 + 4  # + viewpoints and scan
        check_memory(path, 2 * count * per_point,  # the scans, then joined
                     f"declares {count} points in {len(layouts)} scan{'s' * (len(layouts) > 1)}: reading them needs",
                     _HINT)
        parts = [scans.read(i, extras) for i in range(len(scans))]
    sizes = [len(part.points) for part in parts]
    if count and not sum(sizes):
        raise CloudFileError(path, f"contains no points: all {count} are marked invalid")
    return joined_scans(parts, parts[0].fields)


class E57Scans:
    """An E57 file open for reading, its scans (the ``data3D`` vector) by index; use in a
    ``with`` block. Every libE57 error is a :class:`CloudFileError` naming the file."""

    def __init__(self, path):
        self.path = path
        self._libe57 = _import_libe57(path)
        with open(path, "rb") as f:
            if f.read(8) != b"ASTM-E57":  # libE57 would report a checksum mismatch, or a failed read
                raise CloudFileError(path, "is not an E57 file (it does not start with 'ASTM-E57')")
        with _errors(self, "is not a readable E57 file"):
            self._file = self._libe57.ImageFile(str(path), "r")
        try:
            with _errors(self, "is not a readable E57 file"):
                root = self._file.root()
                self._scans = root["data3D"] if root.isDefined("data3D") else []
            if not isinstance(self._scans, (list, self._libe57.VectorNode)):
                raise CloudFileError(path, "is not a readable E57 file: its data3D (the scans) is not a Vector")
        except CloudFileError:
            self.close()
            raise

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        """Release the file (libE57 keeps it open until then)."""
        if self._file.isOpen():
            self._file.close()

    def __len__(self) -> int:
        return len(self._scans)

    def layout(self, index: int) -> Layout:
        """The scan's declared count, coordinates, fields and pose, checked; no point read."""
        with _errors(self, f"scan {index} is unreadable"):
            scan = self._scans[index]
            node = scan["points"] if isinstance(scan, self._libe57.StructureNode) and scan.isDefined("points") \
                else None
            if not isinstance(node, self._libe57.CompressedVectorNode):
                raise CloudFileError(self.path, f"scan {index} has no points (no CompressedVector 'points')")
            proto = self._libe57.StructureNode(node.prototype())
            names = [proto.get(i).elementName() for i in range(proto.childCount())]
            coords = _XYZ if set(_XYZ) <= set(names) else _RAE if set(_RAE) <= set(names) else None
            if coords is None:
                raise CloudFileError(self.path, f"scan {index} has neither cartesian (cartesianX/Y/Z) nor spherical "
                                                f"(sphericalRange/Azimuth/Elevation) coordinates; its fields: "
                                                f"{', '.join(names) or 'none'}")
            dtypes = {name: "f8" if name in coords else _dtype(proto[name], self._libe57)
                      for name in names if name in _WANTED or name in coords}
            count = int(node.childCount())
            if count < 0:  # libE57 reads recordCount as a signed integer
                raise CloudFileError(self.path, f"scan {index} declares a negative number of points ({count})")
            rotation, translation = _pose(scan, self, index)
            return Layout(count, coords, dtypes, rotation, translation)

    def read(self, index: int, extras=()) -> Scan:
        """The scan's valid points in world coordinates, with the ``extras`` it has of
        "intensity" (field ``intensity``) and "colour" (``red``, ``green``, ``blue``)."""
        layout = self.layout(index)
        names = [*layout.coords, *(name for name in _INVALID if name in layout.dtypes),
                 *(name for name in _extra_fields(extras) if name in layout.dtypes)]
        check_memory(self.path, layout.count * layout.bytes_per_point(extras),
                     f"scan {index} declares {layout.count} points: reading them needs", _HINT)
        points = np.empty((layout.count, 3))
        fields = {name: np.empty(layout.count, layout.dtypes[name]) for name in names[3:] if name not in _INVALID}
        filled = 0
        for block in self._blocks(index, layout, names):
            valid = np.ones(len(block[names[0]]), dtype=bool)
            for name in _INVALID:
                if name in block:
                    valid &= block[name] == 0
            stop = filled + int(valid.sum())
            with np.errstate(invalid="ignore", over="ignore"):  # NaN/inf stay non-finite: finalize's to refuse
                points[filled:stop] = _world(_cartesian([block[name][valid] for name in layout.coords],
                                                        layout.coords), layout)
            for name, values in fields.items():
                values[filled:stop] = block[name][valid]
            filled = stop
        fields = {_COLOURS.get(name, name): values[:filled] for name, values in fields.items()}
        return Scan(points[:filled], fields, layout.translation)

    def _blocks(self, index: int, layout: Layout, names):
        """The scan's records, ``BLOCK`` at a time: name -> array, valid until the next block."""
        size = max(1, min(BLOCK, layout.count))
        buffers = {name: np.empty(size, layout.dtypes[name]) for name in names}
        unreadable = _errors(self, f"scan {index} is unreadable")
        with unreadable:
            dest = self._libe57.VectorSourceDestBuffer()
            for name, values in buffers.items():
                dest.append(self._libe57.SourceDestBuffer(self._file, name, values, size, True, True))
            reader = self._scans[index]["points"].reader(dest)
        try:
            done = 0
            while done < layout.count:
                with unreadable:
                    got = min(int(reader.read()), layout.count - done)
                if got <= 0:
                    raise CloudFileError(self.path, f"scan {index} declares {layout.count} points but its data ends "
                                                    f"after {done}")
                yield {name: values[:got] for name, values in buffers.items()}
                done += got
        finally:
            with unreadable:
                reader.close()


#: the optional fields read when asked for, and the invalid states, beside the coordinates
_WANTED = {"intensity", *_COLOURS, *_INVALID}


def _extra_fields(extras) -> list:
    return (["intensity"] if "intensity" in extras else []) + (list(_COLOURS) if "colour" in extras else [])


def _dtype(node, libe57) -> str:
    """The buffer type a field other than the coordinates is read into: intensity float32,
    integers (colours, invalid states) in the smallest type holding their declared range."""
    if node.elementName() == "intensity":
        return "f4"
    if isinstance(node, libe57.IntegerNode):
        low, high = node.minimum(), node.maximum()
        for dtype in ("u1", "i1", "u2", "i2"):
            if np.iinfo(dtype).min <= low and high <= np.iinfo(dtype).max:
                return dtype
        return "i8"
    return "f8"


def _pose(scan, owner, index):
    """(rotation matrix or None, translation) of a scan's pose: identity and the origin where
    the pose, or a part of it, is absent. A zero or non-finite quaternion is refused."""
    if not scan.isDefined("pose"):
        return None, np.zeros(3)
    pose = scan["pose"]
    translation = _numbers(pose, "translation", "xyz", owner, index) if pose.isDefined("translation") else np.zeros(3)
    if not pose.isDefined("rotation"):
        return None, translation
    w, x, y, z = _numbers(pose, "rotation", "wxyz", owner, index)
    norm = np.sqrt(w * w + x * x + y * y + z * z)
    if norm == 0:
        raise CloudFileError(owner.path, f"scan {index}'s pose has the rotation quaternion (0, 0, 0, 0), which is "
                                         "no rotation")
    w, x, y, z = w / norm, x / norm, y / norm, z / norm  # a non-unit quaternion rotates as its unit one
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]), translation


def _numbers(pose, part: str, names: str, owner, index) -> np.ndarray:
    """The finite numbers ``names`` of the pose's ``part`` (absent ones read as libE57 errors)."""
    values = [_value(pose[part][name]) for name in names]
    if not all(isinstance(v, (int, float)) for v in values) or not np.isfinite(values).all():
        raise CloudFileError(owner.path, f"scan {index}'s pose {part} is not {len(names)} finite numbers: {values}")
    return np.array(values, dtype=np.float64)


def _value(node):
    """A number node's value (scaled, for a ScaledInteger); None for another node."""
    if hasattr(node, "scaledValue"):
        return node.scaledValue()
    return node.value() if hasattr(node, "value") else None


def _cartesian(columns, coords) -> np.ndarray:
    """(m, 3) cartesian coordinates from the scan's columns: range, azimuth and elevation
    (radians) converted as libE57's documentation and pye57 do."""
    if coords is _XYZ:
        return np.column_stack(columns)
    r, azimuth, elevation = columns
    flat = r * np.cos(elevation)
    return np.column_stack([flat * np.cos(azimuth), flat * np.sin(azimuth), r * np.sin(elevation)])


def _world(local: np.ndarray, layout: Layout) -> np.ndarray:
    """Scanner-frame points placed in the world by the scan's pose (rotated, then moved)."""
    if layout.rotation is None:
        return local + layout.translation if layout.translation.any() else local
    return local @ layout.rotation.T + layout.translation


class _errors:
    """Turn libE57's exceptions inside the block (its own, and the C++ ones pybind11 passes
    on as RuntimeError, IndexError...) into a CloudFileError: "{what}: {libE57's reason}"."""

    def __init__(self, owner, what: str):
        self.owner, self.what = owner, what

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if kind is None or issubclass(kind, CloudFileError):
            return False
        if issubclass(kind, (self.owner._libe57.E57Exception, RuntimeError, ValueError, IndexError, OverflowError)):
            reason = (str(exc).strip().splitlines() or [kind.__name__])[0]
            if issubclass(kind, UnicodeDecodeError):  # pybind11 decoding a name or message libE57 read
                reason = f"damaged data ({reason})"
            raise CloudFileError(self.owner.path, f"{self.what}: {reason}") from None
        return False


def _import_libe57(path):
    try:
        from pye57 import libe57
    except ModuleNotFoundError as exc:
        raise CloudFileError(path, f"reading .e57 files needs the Python package {exc.name!r}; "
                                   "pip install 'darboux[big]'") from None
    return libe57
