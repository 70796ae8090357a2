"""Point-cloud file input/output.

Read PLY, XYZ/PTS/TXT/CSV, PCD, OBJ, STL, OFF, VTK/VTP, LAS/LAZ, E57 and PTX files into a
:class:`Cloud` (:data:`READ_FORMATS`); write points, normals and per-point fields (or a
curvature result) to PLY, text or VTP (:data:`WRITE_FORMATS`), atomically. Every problem
with a file raises :class:`CloudFileError` (a ``ValueError``) whose message names the file.
"""

from .cloud import Cloud, CloudFileError
from .formats import READ_FORMATS, WRITE_FORMATS
from .read import describe, read_cloud
from .write import RESULT_FIELDS, RESULT_FLAGS, write_cloud, write_result

__all__ = [
    "Cloud", "CloudFileError", "READ_FORMATS", "WRITE_FORMATS", "RESULT_FIELDS", "RESULT_FLAGS",
    "read_cloud", "write_cloud", "write_result", "describe",
]
