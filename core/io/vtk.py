"""VTK legacy (.vtk) and XML PolyData (.vtp) files, read with VTK (imported lazily).

The points of any point set (polydata, unstructured grid, ...) are read; the point data's
normals array (or a 3-component array called normals) gives the normals; other point data
arrays become fields (3 components give name_x/_y/_z). Cells are ignored (a .vtp's are
removed before VTK reads it: see :mod:`.vtp_points`). VTK reports
problems through its output window, which is captured while reading so that a failure
becomes a :class:`CloudFileError` instead of a message on stderr.
"""

from __future__ import annotations

import numpy as np

from .._memory import available_memory
from .cloud import CloudFileError, RawCloud, check_memory, split_components
from .vtk_legacy import check_legacy
from .vtk_messages import first_message, vtk_messages, vtk_output
from .vtp_points import points_only
from .vtp_sizes import check_vtp

__all__ = ["check_legacy", "check_vtp", "read_vtk", "read_vtp"]


def read_vtk(path) -> RawCloud:
    """A legacy ``.vtk`` file (ascii or binary)."""
    from vtkmodules.vtkIOLegacy import vtkGenericDataObjectReader

    check_legacy(path)
    reader = vtkGenericDataObjectReader()
    for option in ("ReadAllScalarsOn", "ReadAllVectorsOn", "ReadAllNormalsOn", "ReadAllFieldsOn"):
        getattr(reader, option)()
    return _read(reader, path)


def read_vtp(path) -> RawCloud:
    """An XML PolyData ``.vtp`` file."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    with points_only(path) as copy:  # VTK never reads the cells: damaged ones aborted it
        try:
            check_vtp(copy, available_memory())
            return _read(vtkXMLPolyDataReader(), copy)
        except CloudFileError as error:
            if copy is path:
                raise
            raise CloudFileError(path, error.problem.replace(str(copy), str(path))) from None


def _read(reader, path) -> RawCloud:
    _update_quietly(reader, path)
    data = reader.GetOutputDataObject(0)
    if data is None or not hasattr(data, "GetPoints"):
        kind = "nothing" if data is None else data.GetClassName()
        raise CloudFileError(path, f"contains {kind}, not a point set")
    _check_implicit_points(data, path)
    if data.GetPoints() is None or data.GetNumberOfPoints() == 0:
        return RawCloud(np.empty((0, 3)), None, {})
    from vtkmodules.util.numpy_support import vtk_to_numpy

    points = vtk_to_numpy(data.GetPoints().GetData())
    normals, fields = _point_data(data.GetPointData(), path, len(points))
    return RawCloud(np.array(points), None if normals is None else np.array(normals), fields)


def _update_quietly(reader, path) -> None:
    """Run the reader with VTK's messages captured; an error message is a CloudFileError."""
    reader.SetFileName(str(path))
    with vtk_messages() as window:
        reader.Update()
    messages = vtk_output(window)
    if "error" in messages.lower():
        raise CloudFileError(path, f"VTK cannot read it: {first_message(messages)}")


def _point_data(point_data, path, n: int):
    """``(normals or None, fields)``: the normals array (or a 3-component array called
    normals) and every other numeric point-data array; each must hold a tuple per point (a
    legacy file's FIELD inside its POINT_DATA may declare any number, which VTK keeps)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    normals_array = point_data.GetNormals()
    normals = None if normals_array is None else vtk_to_numpy(normals_array)
    fields = {}
    for i in range(point_data.GetNumberOfArrays()):
        array = point_data.GetArray(i)  # None for string arrays
        if array is None or array is normals_array:
            continue
        name = array.GetName() or f"array{i}"
        if array.GetNumberOfTuples() != n:
            raise CloudFileError(path, f"point data array {name!r} holds {array.GetNumberOfTuples()} tuples "
                                       f"for {n} points")
        values = vtk_to_numpy(array)
        if normals is None and name.lower() in ("normals", "normal") and values.ndim == 2 and values.shape[1] == 3:
            normals = values
            continue
        fields.update(split_components(name, values))
    return normals, fields



def _check_implicit_points(data, path) -> None:
    """Image data and rectilinear grids do not store their points: a 100-byte header can
    declare 10**15, and building their coordinates would take the machine's memory."""
    if data.IsA("vtkPointSet"):
        return
    n = data.GetNumberOfPoints()
    need = n * 3 * 8 * 4  # float64 coordinates and numpy's temporaries while building them
    check_memory(path, need, f"a {data.GetClassName()} of {n} points: building their coordinates needs")
