"""VTK legacy (.vtk) and XML PolyData (.vtp) files, read with VTK (imported lazily).

The points of any point set (polydata, unstructured grid, ...) are read; the point data's
normals array (or a 3-component array called normals) gives the normals; other point data
arrays become fields (3 components give name_x/_y/_z). Cells are ignored. VTK reports
problems through its output window, which is captured while reading so that a failure
becomes a :class:`CloudFileError` instead of a message on stderr.
"""

from __future__ import annotations

import re

import numpy as np

from .cloud import CloudFileError, RawCloud, split_components


def read_vtk(path) -> RawCloud:
    """A legacy ``.vtk`` file (ascii or binary)."""
    from vtkmodules.vtkIOLegacy import vtkGenericDataObjectReader

    reader = vtkGenericDataObjectReader()
    for option in ("ReadAllScalarsOn", "ReadAllVectorsOn", "ReadAllNormalsOn", "ReadAllFieldsOn"):
        getattr(reader, option)()
    return _read(reader, path)


def read_vtp(path) -> RawCloud:
    """An XML PolyData ``.vtp`` file."""
    from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

    return _read(vtkXMLPolyDataReader(), path)


def _read(reader, path) -> RawCloud:
    _update_quietly(reader, path)
    data = reader.GetOutputDataObject(0)
    if data is None or not hasattr(data, "GetPoints"):
        kind = "nothing" if data is None else data.GetClassName()
        raise CloudFileError(path, f"contains {kind}, not a point set")
    if data.GetPoints() is None or data.GetNumberOfPoints() == 0:
        return RawCloud(np.empty((0, 3)), None, {})
    from vtkmodules.util.numpy_support import vtk_to_numpy

    points = vtk_to_numpy(data.GetPoints().GetData())
    normals, fields = _point_data(data.GetPointData())
    return RawCloud(np.array(points), None if normals is None else np.array(normals), fields)


def _update_quietly(reader, path) -> None:
    """Run the reader with VTK's messages captured; an error message is a CloudFileError."""
    from vtkmodules.vtkCommonCore import vtkLogger, vtkOutputWindow, vtkStringOutputWindow

    reader.SetFileName(str(path))
    window, previous = vtkStringOutputWindow(), vtkOutputWindow.GetInstance()
    verbosity = vtkLogger.GetCurrentVerbosityCutoff()
    vtkOutputWindow.SetInstance(window)
    vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    try:
        reader.Update()
    finally:
        vtkOutputWindow.SetInstance(previous)
        vtkLogger.SetStderrVerbosity(vtkLogger.ConvertToVerbosity(verbosity))
    messages = window.GetOutput()
    if isinstance(messages, bytes):  # VTK hands back bytes when a message is not valid UTF-8
        messages = messages.decode("utf-8", "replace")
    if "error" in messages.lower():
        raise CloudFileError(path, f"VTK cannot read it: {_first_message(messages)}")


def _point_data(point_data):
    """``(normals or None, fields)``: the normals array (or a 3-component array called
    normals) and every other numeric point-data array."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    normals_array = point_data.GetNormals()
    normals = None if normals_array is None else vtk_to_numpy(normals_array)
    fields = {}
    for i in range(point_data.GetNumberOfArrays()):
        array = point_data.GetArray(i)  # None for string arrays
        if array is None or array is normals_array:
            continue
        name = array.GetName() or f"array{i}"
        values = vtk_to_numpy(array)
        if normals is None and name.lower() in ("normals", "normal") and values.ndim == 2 and values.shape[1] == 3:
            normals = values
            continue
        fields.update(split_components(name, values))
    return normals, fields


def _first_message(text: str) -> str:
    """The first VTK message without its 'ERROR: In file, line N' and 'vtkClass (0x...):' prefixes."""
    for line in text.splitlines():
        line = line.strip()
        if not line or re.match(r"^(ERROR|Warning|Generic Warning|Generic Error): In ", line):
            continue
        return re.sub(r"^vtk\w+ \(0x[0-9a-fA-F]+\): ", "", line)
    return "unknown VTK error"
