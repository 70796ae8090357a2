"""Legacy ASCII VTK arrays short of their declared count (core/io/vtk_ascii.py).

VTK 9.7 reads an ASCII float array that the file ends inside (just after a number) without a
message or error code, the missing values being whatever memory held: normals of 4.6e-41 or
NaN passed as the file's. Every array the walk knows is counted (POINTS, point and cell data,
FIELD arrays); files VTK writes, with nan and inf, strings and metadata, still read."""

from __future__ import annotations

import numpy as np
import pytest

from core.io import read_cloud
from io_testutils import refused as _error

HEAD = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
NORMALS = "NORMALS n float\n1 0 0\n0 1 0\n0 0 1\n0.6 0.8 0\n"


def _file(tmp_path, body: str, name="f.vtk"):
    path = tmp_path / name
    path.write_bytes((HEAD + body).encode())
    return path



def test_file_cut_inside_its_normals_refused(tmp_path):
    """The case VTK read in silence: the file ends just after a number of the NORMALS section."""
    path = _file(tmp_path, "POINT_DATA 4\n" + NORMALS[: NORMALS.index("0 0 1") + 3])
    _error(path, "truncated or corrupt NORMALS section: 'NORMALS n float' declares 12 values (POINT_DATA 4) "
                 "but 8 follow before the file ends")


def test_normals_missing_a_row_refused(tmp_path):
    path = _file(tmp_path, "POINT_DATA 4\n" + NORMALS.replace("0 1 0\n", "") + "SCALARS s float 1\nLOOKUP_TABLE t\n"
                           "1 2 3 4\n")
    _error(path, "'NORMALS n float' declares 12 values (POINT_DATA 4) but 9 follow before 'SCALARS s float 1'")


@pytest.mark.parametrize("body, part", [
    ("SCALARS s float 2\nLOOKUP_TABLE default\n1 2 3 4 5 6 7", "SCALARS section: 'SCALARS s float 2' declares 8"),
    ("SCALARS s double 2 LOOKUP_TABLE default 1 2\n3 4 5 6 7", "declares 8 values (POINT_DATA 4) but 7 follow"),
    ("VECTORS v float\n1 0 0 0 1 0 0 0 1 1", "VECTORS section: 'VECTORS v float' declares 12"),
    ("TEXTURE_COORDINATES uv 2 float\n0 0 1 1 0.5", "'TEXTURE_COORDINATES uv 2 float' declares 8 values"),
    ("COLOR_SCALARS c 3\n1 0 0 0 1 0 0 0 1", "'COLOR_SCALARS c 3' declares 12 values"),
    ("TENSORS t float\n" + "1 0 0 0 1 0 0 0 1\n" * 3, "'TENSORS t float' declares 36 values"),
    ("FIELD f 2\nA 1 4 float\n1 2 3 4\nB 2 4 double\n1 2 3 4 5 6 7", "FIELD array 'B 2 4 double' of 'FIELD f 2' "
                                                                    "declares 8 values but 7 follow"),
])
def test_point_data_arrays_short_of_their_count_refused(tmp_path, body, part):
    _error(_file(tmp_path, "POINT_DATA 4\n" + body), part)


def test_short_field_and_cell_data_arrays_refused(tmp_path):
    """The dataset's FIELD section and CELL_DATA arrays (not in the cloud, but VTK reads them the same way)."""
    field = tmp_path / "field.vtk"
    field.write_bytes(HEAD.replace("POINTS", "FIELD f 1\nA 1 3 int\n1 2\nPOINTS").encode())
    _error(field, "FIELD array 'A 1 3 int' of 'FIELD f 1' declares 3 values but 2 follow before 'POINTS 4 float'")
    cells = _file(tmp_path, "VERTICES 1 5\n4 0 1 2 3\nPOINT_DATA 4\n" + NORMALS + "CELL_DATA 1\nSCALARS c float 2\n"
                            "LOOKUP_TABLE default\n5", "cells.vtk")
    _error(cells, "'SCALARS c float 2' declares 2 values (CELL_DATA 1) but 1 follow before the file ends")


def test_arrays_of_nan_inf_strings_metadata_and_values_on_their_header_line_still_read(tmp_path):
    body = ("POINT_DATA 4\nNORMALS n float 1 0 0\n0 nan 0\n0 0 -inf\n+inf 1-1\nSCALARS s double 2\nLOOKUP_TABLE t\n"
            "1 2 3 4 5 6 7 8\nMETADATA\nCOMPONENT_NAMES\nfirst\n2nd\n\nFIELD f 3\nw 1 4 string\nPOINTS 9 float\n\n"
            "1 2\nab\nNULL_ARRAY\nc 2 4 float\n-1e-3 2E+2 3 4 5 6 7 8\n")
    cloud = read_cloud(_file(tmp_path, body))
    assert np.array_equal(cloud.normals, [[1, 0, 0], [0, np.nan, 0], [0, 0, -np.inf], [np.inf, 1, -1]], equal_nan=True)
    assert cloud.fields["s_0"].tolist() == [1, 3, 5, 7] and cloud.fields["c_1"].tolist() == [200, 4, 6, 8]


def test_point_data_field_array_of_another_length_refused(tmp_path):
    """A FIELD inside POINT_DATA may declare any number of tuples and VTK keeps the array: a ValueError."""
    path = _file(tmp_path, "POINT_DATA 4\nFIELD f 1\nB 1 1 double\n5\n")
    _error(path, "point data array 'B' holds 1 tuples for 4 points")


def test_point_and_cell_data_field_sections_vtk_cannot_read_do_not_crash(tmp_path, helpers):
    """Unlike the dataset's own FIELD section, VTK drops one inside POINT_DATA or CELL_DATA that it
    fails to read (fewer arrays than declared, a bad header, huge or negative sizes): no crash."""
    bodies = ["FIELD f 2\nA 1 3 float\n1 2 3\n", "FIELD f 1\n", "FIELD f 1\nA x 4 float\n1 2 3 4\n",
              "FIELD f 1\nA -1 4 float\n1 2 3 4\n", "FIELD f 1\nA 1 4000000000000 float\n1\n", "FIELD f 2000000000\n"]
    paths = [_file(tmp_path, f"VERTICES 1 5\n4 0 1 2 3\n{part}_DATA {n}\n{body}", f"{part}{i}.vtk")
             for i, body in enumerate(bodies) for part, n in (("POINT", 4), ("CELL", 1))]
    answers = helpers.read_in_child(paths)
    assert all(isinstance(answers[str(path)], str) and path.name in answers[str(path)] for path in paths)


@pytest.mark.parametrize("version", [42, 51])
def test_files_vtk_writes_in_ascii_still_read_unchanged(tmp_path, version):
    """Normals, multi-component scalars, colours, texture coordinates, tensors, ids, strings,
    component names and information metadata, dataset and cell FIELD data, as VTK writes them."""
    pytest.importorskip("vtkmodules.vtkIOLegacy")
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints, vtkStringArray
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkIOLegacy import vtkPolyDataWriter

    rng, n = np.random.default_rng(5), 30
    arrays = {"Normals": rng.normal(size=(n, 3)), "two": rng.normal(size=(n, 2)), "uv": rng.random((n, 2)),
              "T": rng.normal(size=(n, 9)), "rgb": rng.integers(0, 255, (n, 3)).astype(np.uint8),
              "ids": np.arange(n, dtype=np.int64), "four": rng.normal(size=(n, 4))}
    arrays["Normals"][4] = [np.nan, np.inf, -np.inf]
    data, points, verts = vtkPolyData(), vtkPoints(), vtkCellArray()
    points.SetData(numpy_to_vtk(rng.normal(size=(n, 3)), deep=True))
    data.SetPoints(points)
    for i in range(n):
        verts.InsertNextCell(1, [i])
    data.SetVerts(verts)
    vtk_arrays = {name: numpy_to_vtk(values, deep=True) for name, values in arrays.items()}
    for name, array in vtk_arrays.items():
        array.SetName(name)
    vtk_arrays["two"].SetComponentName(0, "first")
    vtk_arrays["four"].GetRange(-1)  # an L2 norm range, written as INFORMATION metadata
    point_data = data.GetPointData()
    point_data.SetNormals(vtk_arrays["Normals"]), point_data.SetScalars(vtk_arrays["rgb"])  # COLOR_SCALARS
    point_data.SetTCoords(vtk_arrays["uv"]), point_data.SetTensors(vtk_arrays["T"])
    point_data.SetGlobalIds(vtk_arrays["ids"])
    for name in ("two", "four"):
        point_data.AddArray(vtk_arrays[name])
    words = vtkStringArray()
    words.SetName("words")
    for i in range(n):
        words.InsertNextValue(f"point {i}" if i % 5 else "")
    point_data.AddArray(words), data.GetFieldData().AddArray(words)
    data.GetCellData().AddArray(numpy_to_vtk(np.arange(n, dtype=np.float64)))
    path = tmp_path / "written.vtk"
    writer = vtkPolyDataWriter()
    writer.SetInputData(data), writer.SetFileName(str(path)), writer.SetFileVersion(version)
    writer.SetFileTypeToASCII(), writer.Write()
    cloud = read_cloud(path)
    assert np.allclose(cloud.normals, arrays["Normals"], equal_nan=True)
    for name in ("two", "uv", "T", "rgb", "ids", "four"):
        values = np.column_stack([cloud.fields[key] for key in cloud.fields if key.rsplit("_", 1)[0] == name
                                  or key == name])
        assert np.allclose(values, arrays[name].reshape(n, -1), atol=1e-6), name


@pytest.mark.parametrize("dataset", ["POLYDATA", "UNSTRUCTURED_GRID", "STRUCTURED_GRID"])
def test_second_dataset_field_section_vtk_cannot_read_refused(tmp_path, helpers, dataset):
    """A second FIELD section of the dataset (after POINTS, the first one sound) that VTK fails
    to read was used all the same, as the first one was: a segmentation fault."""
    head = f"# vtk DataFile Version 3.0\nt\nASCII\nDATASET {dataset}\n" + "DIMENSIONS 2 2 1\n" * (dataset[0] == "S")
    bodies = ["FIELD g 2\nA 1 3 float\n1 2 3\n", "FIELD g 1\n", "FIELDS 3 2 2\n", "FIELD g 1\nA x 4 float\n1 2 3 4\n"]
    paths = [tmp_path / f"f{i}.vtk" for i in range(len(bodies))]
    for path, body in zip(paths, bodies):
        path.write_text(head + "FIELD f 1\nB 1 1 float\n7\n" + HEAD[HEAD.index("POINTS"):] + body)
    answers = helpers.read_in_child(paths)
    for path in paths:
        assert path.name in answers[str(path)] and "section (the dataset's field data)" in answers[str(path)]
