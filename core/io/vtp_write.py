"""Writing a cloud as VTK XML PolyData (``.vtp``), for ParaView and VTK: the points, one
vertex cell each (so they render without a filter), and every column as point data.

Columns named ``name_x name_y name_z`` one after another become one 3-component array
``name`` (``e1``, ``e2``: ParaView's Glyph filter takes them as vectors); ``nx ny nz`` become
the ``Normals`` array, marked as the point data's normals. The data are raw little-endian
binary appended after the XML (``header_type="UInt64"``), read by VTK 6 and later.
"""

from __future__ import annotations

from html import escape

import numpy as np

#: numpy dtype kind + size -> VTK's type name
_TYPES = {("f", 4): "Float32", ("f", 8): "Float64", ("i", 1): "Int8", ("i", 2): "Int16", ("i", 4): "Int32",
          ("i", 8): "Int64", ("u", 1): "UInt8", ("u", 2): "UInt16", ("u", 4): "UInt32", ("u", 8): "UInt64",
          ("b", 1): "UInt8"}


def write_vtp(f, columns) -> None:
    """Write ``columns`` (list of (name, (N,) array), x y z first) to the binary stream ``f``."""
    arrays = point_arrays(columns)
    n = len(columns[0][1])
    points = np.column_stack([values for _, values in columns[:3]]).astype("<f8")
    cells = np.arange(n, dtype="<i8")
    blocks, xml, offset = [], [], 0

    def data_array(name, values, components):
        nonlocal offset
        values = np.ascontiguousarray(values.astype(values.dtype.newbyteorder("<")))
        kind = _TYPES[values.dtype.kind, values.dtype.itemsize]
        blocks.append(values.view(np.uint8).reshape(-1) if values.dtype != bool else values.astype(np.uint8))
        xml.append(f'<DataArray type="{kind}" Name={_attribute(name)} NumberOfComponents="{components}" format="appended" '
                   f'offset="{offset}"/>')
        offset += 8 + blocks[-1].nbytes

    data_array("Points", points, 3)
    point_xml = xml[:]
    xml.clear()
    data_array("connectivity", cells, 1)
    data_array("offsets", cells + 1, 1)
    verts_xml = xml[:]
    xml.clear()
    for name, values in arrays:
        data_array(name, values, 1 if values.ndim == 1 else 3)
    normals = ' Normals="Normals"' if [name for name, _ in columns[3:6]] == ["nx", "ny", "nz"] else ""
    head = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        f'<PolyData>\n<Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" NumberOfStrips="0" '
        'NumberOfPolys="0">\n'
        f'<PointData{normals}>\n' + "\n".join(xml) + '\n</PointData>\n'
        '<Points>\n' + "\n".join(point_xml) + '\n</Points>\n'
        '<Verts>\n' + "\n".join(verts_xml) + '\n</Verts>\n'
        '</Piece>\n</PolyData>\n<AppendedData encoding="raw">\n_'
    )
    f.write(head.encode("utf-8"))  # XML without an encoding declaration is UTF-8
    for block in blocks:
        f.write(np.uint64(block.nbytes).astype("<u8").tobytes())
        f.write(memoryview(block))
    f.write(b"\n</AppendedData>\n</VTKFile>\n")


def _attribute(name: str) -> str:
    """``name`` as a quoted XML attribute value (a field name may hold <, > or &)."""
    return f'"{escape(name, quote=True)}"'


def point_arrays(columns) -> list:
    """The point-data arrays after x y z: (name, (N,) or (N, 3) array), triples joined."""
    out, rest, i = [], columns[3:], 0
    while i < len(rest):
        name, values = rest[i]
        names = [c for c, _ in rest[i:i + 3]]
        if names == ["nx", "ny", "nz"]:
            out.append(("Normals", np.column_stack([v for _, v in rest[i:i + 3]]).astype(np.float64)))
            i += 3
        elif name.endswith("_x") and names == [name[:-2] + s for s in ("_x", "_y", "_z")] \
                and len({v.dtype for _, v in rest[i:i + 3]}) == 1:
            out.append((name[:-2], np.column_stack([v for _, v in rest[i:i + 3]])))
            i += 3
        else:
            out.append((name, values))
            i += 1
    return out
