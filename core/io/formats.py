"""The file formats by extension, and choosing one from a path or a ``format=`` argument."""

from __future__ import annotations

from .cloud import CloudFileError

#: extension -> description, for the formats :func:`core.io.read_cloud` reads
READ_FORMATS = {
    ".ply": "Stanford PLY (ascii or binary)",
    ".xyz": "XYZ text (x y z [nx ny nz])",
    ".pts": "PTS text (optional point count line)",
    ".txt": "Text columns (x y z [nx ny nz])",
    ".csv": "CSV (header naming x, y, z [nx, ny, nz])",
    ".pcd": "PCL point cloud data",
    ".obj": "Wavefront OBJ (vertices)",
    ".stl": "STL mesh (vertices)",
    ".off": "Geomview OFF mesh (vertices)",
    ".vtk": "VTK legacy",
    ".vtp": "VTK XML PolyData",
    ".las": "LAS lidar",
    ".laz": "LAZ compressed lidar",
    ".e57": "ASTM E57 laser scans (all scans, in world coordinates)",
    ".ptx": "Leica PTX laser scans (all scans, in world coordinates)",
}

#: extension -> description, for the formats :func:`core.io.write_cloud` writes
WRITE_FORMATS = {
    ".ply": "Stanford PLY (binary little-endian)",
    ".csv": "CSV with a header line",
    ".xyz": "XYZ text columns",
    ".txt": "Text columns",
    ".vtp": "VTK XML PolyData (binary; ParaView)",
}


#: extensions of compressed files, refused with a word on decompressing them
_COMPRESSED = (".gz", ".zip", ".bz2", ".xz", ".zst", ".7z", ".tgz")


def resolve_format(path, format, table: dict, action: str) -> str:
    """The short format name (``"ply"``) from ``format`` if given, else from the extension."""
    allowed = ", ".join(table)
    if format is None:
        ext = path.suffix.lower()
        if ext not in table:
            what = f"unknown file extension {ext!r}" if ext else "no file extension"
            if ext in _COMPRESSED:
                what = f"a compressed file ({ext}); decompress it first and read the file inside, or:"
            raise CloudFileError(path, f"{what} for {action}; supported: {allowed} (or pass format=)")
        return ext[1:]
    if not isinstance(format, str) or "." + format.lower().lstrip(".") not in table:
        raise CloudFileError(path, f"format={format!r} is not supported for {action}; allowed: {allowed}")
    return format.lower().lstrip(".")
