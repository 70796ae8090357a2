"""Legacy BINARY VTK arrays that the file ends inside (core/io/vtk_binary.py).

VTK 9.7 reads a binary array as count x components x size bytes after its header's line,
whatever follows: a file cut inside one drew only a warning naming no section, after VTK had
allocated what the header declared (a dataset FIELD array of 2e10 values aborted the process:
std::bad_alloc). Every array the walk knows is measured before VTK reads the file; a second
dataset FIELD section VTK cannot read (a segmentation fault) is found in binary files too.
Files VTK's writers produce, of every dataset and array type, still read unchanged."""

from __future__ import annotations

import mmap

import numpy as np
import pytest

from core.io import read_cloud
from core.io.vtk_legacy import _legacy_header
from core.io.vtk_binary import _BinaryWalk, new_cells
from io_testutils import refused as _error

HEAD = b"# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\n"
POINTS = b"POINTS 4 float\n" + np.arange(12, dtype=">f4").tobytes() + b"\n"


def _values(n, kind=">f4"):
    return np.arange(n, dtype=kind).tobytes()


@pytest.mark.parametrize("body, part", [
    (POINTS[:-10], "POINTS section: 'POINTS 4 float' declares 12 coordinates, 48 bytes, but 39 follow its header "
                   "before the file ends"),
    (POINTS + b"POINT_DATA 4\nNORMALS n float\n" + _values(12)[:-4],
     "NORMALS section: 'NORMALS n float' declares 12 values (POINT_DATA 4), 48 bytes, but 44 follow"),
    (POINTS + b"POINT_DATA 4\nSCALARS s double 2\nLOOKUP_TABLE default\n" + _values(8, ">f8")[:-1],
     "SCALARS section: 'SCALARS s double 2' declares 8 values (POINT_DATA 4), 64 bytes, but 63 follow"),
    (POINTS + b"POINT_DATA 4\nFIELD f 2\nA 1 4 int\n" + _values(4, ">i4") + b"\nB 3 4 unsigned_short\n"
     + _values(12, ">u2")[:-2], "FIELD array 'B 3 4 unsigned_short' of 'FIELD f 2' declares 12 values, 24 bytes, "
                                "but 22 follow"),
    (b"FIELD f 1\nA 2 3 vtktypeint64\n" + _values(5, ">i8"), "FIELD array 'A 2 3 vtktypeint64' of 'FIELD f 1' "
                                                            "declares 6 values, 48 bytes, but 40 follow"),
    (POINTS + b"POINT_DATA 4\nFIELD f 1\nbits 5 4 bit\n" + b"\xff\xff", "declares 20 values, 3 bytes, but 2 follow"),
    (POINTS + b"POINT_DATA 4\nCOLOR_SCALARS c 4\n" + bytes(15), "'COLOR_SCALARS c 4' declares 16 values "
                                                              "(POINT_DATA 4), 16 bytes, but 15 follow"),
    (POINTS + b"POINT_DATA 4\nSCALARS s float\nLOOKUP_TABLE t\n" + _values(4) + b"\nLOOKUP_TABLE t 2\n" + bytes(7),
     "LOOKUP_TABLE section: 'LOOKUP_TABLE t 2' declares 8 values, 8 bytes, but 7 follow"),
], ids=["points", "normals", "scalars2", "point_field", "dataset_field", "bits", "colours", "lookup_table"])
def test_binary_arrays_the_file_ends_inside_refused(tmp_path, body, part):
    """Points, normals, scalars of 2 components, FIELD arrays (of the point data and of the
    dataset), bits, colours and lookup tables (a byte a value in binary) cut short."""
    path = tmp_path / "cut.vtk"
    path.write_bytes(HEAD + body)
    _error(path, "truncated or corrupt", part)


def test_dataset_field_array_beyond_the_file_refused_before_vtk_allocates_it(tmp_path, helpers):
    """VTK's field parser (run first on the dataset's FIELD section) allocated the 2e10 values: std::bad_alloc."""
    path = tmp_path / "huge.vtk"
    path.write_bytes(HEAD + b"FIELD f 1\nA 1 20000000000 float\n" + _values(3) + b"\n" + POINTS)
    answer = helpers.read_in_child([path])[str(path)]
    assert "FIELD array 'A 1 20000000000 float' of 'FIELD f 1' declares 20000000000 values" in answer, answer


@pytest.mark.parametrize("dataset", ["POLYDATA", "UNSTRUCTURED_GRID", "STRUCTURED_GRID"])
def test_second_dataset_field_section_vtk_cannot_read_refused(tmp_path, helpers, dataset):
    """A second FIELD section of a binary dataset (after POINTS, the first one sound) that VTK
    fails to read: a segmentation fault, as in ASCII files before their walk found them."""
    head = HEAD.replace(b"POLYDATA", dataset.encode()) + b"DIMENSIONS 2 2 1\n" * (dataset[0] == "S")
    bodies = [b"FIELD g 1\n", b"FIELDS 3 2 2\n", b"FIELD g 1\nA x 4 float\n" + _values(4)]
    paths = [tmp_path / f"f{i}.vtk" for i in range(len(bodies))]
    for path, body in zip(paths, bodies):
        path.write_bytes(head + b"FIELD f 1\nB 1 1 float\n" + _values(1) + b"\n" + POINTS + body)
    answers = helpers.read_in_child(paths)
    for path in paths:
        assert path.name in answers[str(path)] and "section (the dataset's field data)" in answers[str(path)]


def test_exact_files_and_data_without_newlines_after_them_still_read(tmp_path):
    """VTK reads the bytes an array declares and whatever follows: no newline is needed after them."""
    path = tmp_path / "tight.vtk"
    path.write_bytes(HEAD + POINTS[:-1] + b"POINT_DATA 4\nNORMALS n double\n" + _values(12, ">f8"))
    cloud = read_cloud(path)
    assert cloud.points.ravel().tolist() == list(range(12)) and cloud.normals.ravel().tolist() == list(range(12))


def _dataset(kind, rng):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkImageData, vtkPolyData, vtkRectilinearGrid, vtkUnstructuredGrid

    if kind == "image":
        data = vtkImageData()
        data.SetDimensions(3, 2, 2)
        return data, 2
    if kind == "rectilinear":
        data = vtkRectilinearGrid()
        data.SetDimensions(3, 2, 2)
        for axis, values in zip("XYZ", ([0, 1, 2.0], np.array([0, 1], np.float32), np.array([0, 5], np.int32))):
            getattr(data, f"Set{axis}Coordinates")(numpy_to_vtk(np.asarray(values)))
        return data, 2
    data = vtkPolyData() if kind == "poly" else vtkUnstructuredGrid()
    points = vtkPoints()
    points.SetData(numpy_to_vtk(rng.normal(size=(12, 3)).astype(np.float32)))
    data.SetPoints(points)
    if kind == "poly":
        data.Allocate(12)
    for i in range(12):
        data.InsertNextCell(1, 1, [i])  # vertices
    return data, 12


def _fill(data, cells, rng):
    """Normals, scalars of every type in 1 to 3 components, vectors, tensors, texture
    coordinates, ids, bits, colours, a lookup table, component names, field and cell data."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import vtkBitArray, vtkLookupTable

    def named(values, name):
        array = numpy_to_vtk(values, deep=1)
        array.SetName(name)
        return array

    points = data.GetPointData()
    points.SetNormals(named(rng.normal(size=(12, 3)).astype(np.float32), "n"))
    for kind in ("i1", "u1", "i2", "u2", "i4", "u4", "i8", "u8", "f4", "f8"):
        for components in (1, 2, 3):
            array = named(rng.integers(0, 100, size=(12, components)).astype(kind).squeeze(), f"s{kind}{components}")
            array.SetComponentName(0, "first")
            points.AddArray(array)
    points.SetScalars(named(rng.normal(size=12), "sc"))
    table = vtkLookupTable()
    table.Build()
    points.GetScalars().SetLookupTable(table)
    points.SetVectors(named(rng.normal(size=(12, 3)), "vec"))
    points.SetTensors(named(rng.normal(size=(12, 9)).astype(np.float32), "ten"))
    points.SetTCoords(named(rng.random(size=(12, 2)).astype(np.float32), "uv"))
    points.SetGlobalIds(named(np.arange(12, dtype=np.int64), "gid"))
    bits = vtkBitArray()
    bits.SetName("bits")
    bits.SetNumberOfTuples(12)
    for i in range(12):
        bits.SetValue(i, i % 3 == 0)
    points.AddArray(bits)
    points.AddArray(named(np.arange(48, dtype=np.uint8).reshape(12, 4), "rgba"))
    data.GetFieldData().AddArray(named(np.arange(7.0), "field_x"))
    data.GetCellData().SetScalars(named(np.arange(3 * cells, dtype=np.uint8).reshape(cells, 3), "colours"))
    data.GetCellData().AddArray(named(rng.normal(size=(cells, 3)).astype(np.float32), "cn"))


@pytest.mark.parametrize("kind", ["poly", "unstructured", "rectilinear", "image"])
@pytest.mark.parametrize("version", [42, 51])
def test_files_vtk_writes_walked_to_their_end_and_read_unchanged(tmp_path, kind, version):
    vtk = pytest.importorskip("vtkmodules.vtkIOLegacy")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    rng = np.random.default_rng(version)
    data, cells = _dataset(kind, rng)
    _fill(data, cells, rng)
    path = tmp_path / f"{kind}.vtk"
    writer = vtk.vtkDataSetWriter()
    writer.SetInputData(data)
    writer.SetFileName(str(path))
    writer.SetFileVersion(version)
    writer.SetFileTypeToBinary()
    writer.Write()
    with open(path, "rb") as f, mmap.mmap(f.fileno(), 0, access=mmap.ACCESS_READ) as mapped:
        lines, body = _legacy_header(mapped)
        walk = _BinaryWalk(path, mapped, not new_cells(lines))
        assert walk.walk(body)[0] is not None and len(walk.fields) == 1  # to the end: every array measured
    cloud = read_cloud(path)
    point_data = data.GetPointData()
    if kind in ("poly", "unstructured"):
        assert np.array_equal(cloud.points, vtk_to_numpy(data.GetPoints().GetData()))
    assert np.array_equal(cloud.normals, vtk_to_numpy(point_data.GetNormals()))
    for name in ("si83", "su22", "sf41", "su81", "sc", "vec", "ten", "uv", "gid", "rgba"):
        values = vtk_to_numpy(point_data.GetArray(name)).reshape(12, -1)
        found = [cloud.fields[key] for key in sorted(cloud.fields) if key == name or key.startswith(name + "_")]
        assert np.array_equal(np.column_stack(found), values), name
    assert cloud.fields["bits"].tolist() == [i % 3 == 0 for i in range(12)]


def test_scalars_of_more_components_than_an_int_still_read_without_them(tmp_path):
    """VTK reads a SCALARS component count as an int: 4294967295 ends its point data, no error."""
    path = tmp_path / "comps.vtk"
    path.write_bytes(HEAD + POINTS + b"POINT_DATA 4\nSCALARS s float 4294967295\nLOOKUP_TABLE default\n" + _values(4))
    assert len(read_cloud(path)) == 4 and not read_cloud(path).fields
