#!/usr/bin/env python3
"""Writes the VTK fixtures of tests/spectral_vtk_files.rs with VTK itself (pip install vtk;
written with VTK 9.7): two order-3 Lagrange hexahedra and two order-3 Lagrange
quadrilaterals, their nodes placed and ordered by VTK's own PointIndexFromIJK, with the point
field u given below, in every encoding vtkXMLUnstructuredGridWriter offers: ascii, inline
binary and appended (raw and base64), uncompressed and zlib/LZ4/LZMA, UInt32 and UInt64
headers; `quad_series.pvd`, a ParaView collection (written as ParaView's vtkPVDWriter
writes it: VTK has no writer of its own for it) of three VTK-written files whose field is
(1 + k) times the quadrilaterals' field at times 0, 0.5, 1; `quad_time.vtu`, the
quadrilaterals with their time in the field data (`TimeValue` 2.5); `tri_lagrange.vtu`, a
quadratic Lagrange triangle (a cell the renderer refuses by name); `bezier_{quad,hex}.vtu`
and `bezier_{quad,hex}_rational.vtu`, two order-3 Bezier cells each (the latter with
RationalWeights), with VTK's own evaluation of their geometry and field at parametric points
in the `.json` beside them; `quad_cells.vtu`, the quadrilaterals with cell data only (a scalar
`pressure` = 1.5 + 2c, a vector `flux`), and `quad_vectors.vtu`, with only a vector point
array (nothing to draw); `hex_pieces.pvtu`, the hexahedra in two pieces written by
vtkXMLPUnstructuredGridWriter. Also `hex_legacy.vtu`: the same hexahedra with the node order VTK used before file
version 2.2 (vertical edges 2-6 and 3-7 swapped) and the version attribute set to 1.0, checked
by reading it back with VTK. Run from the repository root: python3 scripts/vtk-fixtures.py
"""
import json
import math
import os
import re
import sys

import vtk

OUT = os.path.join("tests", "data", "vtk")
ORDER = 3


def hex_u(x, y, z):
    return x * x * y + z**3 - x * y * z + 0.5


def quad_u(x, y, z):
    return x**3 - 2.0 * x * y * y + y


def affine(r, s, t, cell):
    # A sheared, translated box: affine, so the fields above are exact in Q3.
    return (0.2 * cell + 1.0 * r + 0.3 * s + 0.1 * t, 0.1 * r + 0.8 * s, 0.05 * r + 0.2 * s + 0.7 * t)


def grid(shape):
    g = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    u = vtk.vtkDoubleArray()
    u.SetName("u")
    if shape == "hex":
        cell, ctype, n3 = vtk.vtkLagrangeHexahedron(), vtk.VTK_LAGRANGE_HEXAHEDRON, 3
        field = hex_u
    else:
        cell, ctype, n3 = vtk.vtkLagrangeQuadrilateral(), vtk.VTK_LAGRANGE_QUADRILATERAL, 2
        field = quad_u
    per = (ORDER + 1) ** n3
    for c in range(2):
        ids = [0] * per
        for k in range(ORDER + 1 if n3 == 3 else 1):
            for j in range(ORDER + 1):
                for i in range(ORDER + 1):
                    if n3 == 3:
                        at = cell.PointIndexFromIJK(i, j, k, [ORDER] * 3)
                    else:
                        at = cell.PointIndexFromIJK(i, j, [ORDER] * 2)
                    x = affine(i / ORDER + c, j / ORDER, k / ORDER, 0)
                    if n3 == 2:
                        x = (x[0], x[1], 0.0)
                    ids[at] = pts.InsertNextPoint(*x)
                    u.InsertNextValue(field(*x))
        g.InsertNextCell(ctype, per, ids)
    g.SetPoints(pts)
    g.GetPointData().AddArray(u)
    return g


def bezier(shape, rational=False):
    """Two order-3 Bezier cells: control points at the affine map's equispaced values (linear
    precision) with the interior ones moved (curved cells), coefficients sin(i + 2j + 3k) as
    point data; with `rational`, RationalWeights between 0.6 and 2.1 varying along every axis
    (a rational cell: geometry and field are ratios of the weighted Bernstein sums)."""
    g = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    u = vtk.vtkDoubleArray()
    u.SetName("u")
    w = vtk.vtkDoubleArray()
    w.SetName("RationalWeights")
    if shape == "hex":
        cell, ctype, n3 = vtk.vtkBezierHexahedron(), vtk.VTK_BEZIER_HEXAHEDRON, 3
    else:
        cell, ctype, n3 = vtk.vtkBezierQuadrilateral(), vtk.VTK_BEZIER_QUADRILATERAL, 2
    per = (ORDER + 1) ** n3
    for c in range(2):
        ids = [0] * per
        for k in range(ORDER + 1 if n3 == 3 else 1):
            for j in range(ORDER + 1):
                for i in range(ORDER + 1):
                    at = cell.PointIndexFromIJK(i, j, k, [ORDER] * 3) if n3 == 3 else cell.PointIndexFromIJK(i, j, [ORDER] * 2)
                    x = list(affine(i / ORDER + c, j / ORDER, k / ORDER, 0))
                    if 0 < i < ORDER and 0 < j < ORDER:
                        x[2 if n3 == 3 else 0] += 0.07 * math.sin(i + j + c)
                    if n3 == 2:
                        x[2] = 0.0
                    ids[at] = pts.InsertNextPoint(*x)
                    u.InsertNextValue(math.sin(i + 2 * j + 3 * k + 5 * c))
                    w.InsertNextValue(1.0 + 0.5 * (i == 1) + 0.3 * (j == 2) - 0.4 * (k == 3) + 0.3 * c if rational else 1.0)
        g.InsertNextCell(ctype, per, ids)
    g.SetPoints(pts)
    g.GetPointData().AddArray(u)
    g.GetPointData().SetRationalWeights(w)
    return g


def evaluations(g, points):
    """VTK's own evaluation of each cell's geometry and of u at parametric `points`."""
    u = g.GetPointData().GetArray("u")
    records = []
    for c in range(g.GetNumberOfCells()):
        cell = g.GetCell(c)
        for pc in points:
            pc = list(pc) + [0.0] * (3 - len(pc))
            x = [0.0, 0.0, 0.0]
            weights = [0.0] * cell.GetNumberOfPoints()
            cell.EvaluateLocation(vtk.reference(0), pc, x, weights)
            value = sum(wt * u.GetValue(cell.GetPointId(i)) for i, wt in enumerate(weights))
            records.append({"element": c, "ref": pc[: cell.GetCellDimension()], "x": x, "value": value})
    return records


def write(g, name, mode, compressor, header64, encode=True):
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(g)
    w.SetFileName(os.path.join(OUT, name))
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary, "appended": w.SetDataModeToAppended}[mode]()
    w.SetEncodeAppendedData(1 if encode else 0)
    {"none": w.SetCompressorTypeToNone, "zlib": w.SetCompressorTypeToZLib, "lz4": w.SetCompressorTypeToLZ4, "lzma": w.SetCompressorTypeToLZMA}[compressor]()
    w.SetHeaderTypeToUInt64() if header64 else w.SetHeaderTypeToUInt32()
    # Several compressed blocks per array, so block framing is exercised.
    w.SetBlockSize(512)
    if not w.Write():
        sys.exit(f"VTK failed to write {name}")


def main():
    os.makedirs(OUT, exist_ok=True)
    hexes, quads = grid("hex"), grid("quad")
    write(hexes, "hex_ascii.vtu", "ascii", "none", False)
    for mode in ["binary", "appended"]:
        for comp in ["none", "zlib", "lz4", "lzma"]:
            for h in [False, True]:
                write(hexes, f"hex_{mode}_{comp}_{'u64' if h else 'u32'}.vtu", mode, comp, h)
    write(hexes, "hex_appended_raw_zlib_u32.vtu", "appended", "zlib", False, encode=False)
    write(hexes, "hex_appended_raw_none_u64.vtu", "appended", "none", True, encode=False)
    # VTK's default settings: appended, base64, zlib, UInt32 headers... as ParaView writes.
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetInputData(quads)
    w.SetFileName(os.path.join(OUT, "quad_default.vtu"))
    w.Write()
    write(quads, "quad_ascii.vtu", "ascii", "none", False)

    # A time series: three files, the field scaled by 1 + k, and the collection naming them.
    lines = ['<?xml version="1.0"?>', '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">', "  <Collection>"]
    for k, t in enumerate([0.0, 0.5, 1.0]):
        step = vtk.vtkUnstructuredGrid()
        step.DeepCopy(quads)
        u = step.GetPointData().GetArray("u")
        for i in range(u.GetNumberOfTuples()):
            u.SetValue(i, (1 + k) * u.GetValue(i))
        write(step, f"quad_series_{k}.vtu", "appended", "zlib", False)
        lines.append(f'    <DataSet timestep="{t}" group="" part="0" file="quad_series_{k}.vtu"/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    open(os.path.join(OUT, "quad_series.pvd"), "w").write("\n".join(lines))

    # One time step as a solver writes it for ParaView: the time in the grid's field data,
    # `TimeValue` (VTK's convention, which ParaView's reader takes as the data set's time).
    timed = vtk.vtkUnstructuredGrid()
    timed.DeepCopy(quads)
    t = vtk.vtkDoubleArray()
    t.SetName("TimeValue")
    t.InsertNextValue(2.5)
    timed.GetFieldData().AddArray(t)
    write(timed, "quad_time.vtu", "appended", "zlib", False)
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(os.path.join(OUT, "quad_time.vtu"))
    r.Update()
    if r.GetOutput().GetFieldData().GetArray("TimeValue").GetValue(0) != 2.5:
        sys.exit("quad_time.vtu: VTK does not read TimeValue 2.5 back")

    # A cell the renderer does not draw (a quadratic Lagrange triangle), to be refused by name.
    tri = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0.5, 0, 0), (0.5, 0.5, 0), (0, 0.5, 0)]:
        pts.InsertNextPoint(*p)
    tri.SetPoints(pts)
    tri.InsertNextCell(vtk.VTK_LAGRANGE_TRIANGLE, 6, list(range(6)))
    u = vtk.vtkDoubleArray()
    u.SetName("u")
    for i in range(6):
        u.InsertNextValue(float(i))
    tri.GetPointData().AddArray(u)
    write(tri, "tri_lagrange.vtu", "appended", "zlib", False)

    # Bezier cells, and VTK's evaluation of them at parametric points.
    for shape, pts in [("quad", [(0.5, 0.5), (0.1, 0.8), (0.93, 0.27), (0.0, 1.0)]),
                       ("hex", [(0.5, 0.5, 0.5), (0.1, 0.8, 0.3), (0.93, 0.27, 0.61), (1.0, 0.0, 1.0)])]:
        cells = bezier(shape)
        write(cells, f"bezier_{shape}.vtu", "appended", "zlib", False)
        with open(os.path.join(OUT, f"bezier_{shape}.json"), "w") as f:
            json.dump(evaluations(cells, pts), f)
        rational = bezier(shape, rational=True)
        write(rational, f"bezier_{shape}_rational.vtu", "ascii", "none", False)
        with open(os.path.join(OUT, f"bezier_{shape}_rational.json"), "w") as f:
            json.dump(evaluations(rational, pts), f)

    # Cell data only (a solver's per-element values): the quadrilaterals without their point
    # field, a scalar `pressure` of 1.5 + 2c on cell c and a vector `flux` (not drawable);
    # and a file whose only array is a 3-component point vector (nothing to draw).
    cells_only = vtk.vtkUnstructuredGrid()
    cells_only.DeepCopy(quads)
    cells_only.GetPointData().RemoveArray("u")
    pressure, flux = vtk.vtkDoubleArray(), vtk.vtkDoubleArray()
    pressure.SetName("pressure")
    flux.SetName("flux")
    flux.SetNumberOfComponents(3)
    for c in range(cells_only.GetNumberOfCells()):
        pressure.InsertNextValue(1.5 + 2 * c)
        flux.InsertNextTuple3(c, -c, 0.5)
    cells_only.GetCellData().AddArray(pressure)
    cells_only.GetCellData().AddArray(flux)
    write(cells_only, "quad_cells.vtu", "appended", "zlib", False)
    vectors = vtk.vtkUnstructuredGrid()
    vectors.DeepCopy(quads)
    vectors.GetPointData().RemoveArray("u")
    velocity = vtk.vtkDoubleArray()
    velocity.SetName("velocity")
    velocity.SetNumberOfComponents(3)
    for i in range(vectors.GetNumberOfPoints()):
        velocity.InsertNextTuple3(1.0, 0.0, i)
    vectors.GetPointData().AddArray(velocity)
    write(vectors, "quad_vectors.vtu", "appended", "zlib", False)

    # A partitioned data set as a parallel run writes it: the hexahedra split into two pieces
    # by VTK's own piece extractor, written by the parallel writer (hex_pieces.pvtu and
    # hex_pieces_0.vtu, hex_pieces_1.vtu, a cell each).
    p = vtk.vtkXMLPUnstructuredGridWriter()
    split = vtk.vtkExtractUnstructuredGridPiece()
    split.SetInputData(hexes)
    p.SetInputConnection(split.GetOutputPort())
    p.SetFileName(os.path.join(OUT, "hex_pieces.pvtu"))
    p.SetNumberOfPieces(2)
    p.SetStartPiece(0)
    p.SetEndPiece(1)
    p.SetDataModeToAppended()
    if not p.Write():
        sys.exit("VTK failed to write hex_pieces.pvtu")

    # The legacy order: vertical edges 2-6 and 3-7 swapped, version 1.0.
    legacy = vtk.vtkUnstructuredGrid()
    legacy.DeepCopy(hexes)
    e = ORDER - 1
    first = 8 + 8 * e  # the vertical edges' interior nodes start here
    for c in range(legacy.GetNumberOfCells()):
        ids = vtk.vtkIdList()
        legacy.GetCellPoints(c, ids)
        ids = [ids.GetId(i) for i in range(ids.GetNumberOfIds())]
        a, b = first + 2 * e, first + 3 * e
        ids[a:a + e], ids[b:b + e] = ids[b:b + e], ids[a:a + e]
        legacy.ReplaceCell(c, len(ids), ids)
    path = os.path.join(OUT, "hex_legacy.vtu")
    write(legacy, "hex_legacy.vtu", "ascii", "none", False)
    text = open(path).read()
    text = re.sub(r'(<VTKFile[^>]*?)version="[0-9.]+"', r'\1version="1.0"', text, count=1)
    open(path, "w").write(text)
    # VTK reads the legacy file as the same cells: the same point at every node.
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    back = r.GetOutput()
    for c in range(hexes.GetNumberOfCells()):
        a, b = hexes.GetCell(c), back.GetCell(c)
        for i in range(a.GetNumberOfPoints()):
            pa, pb = a.GetPoints().GetPoint(i), b.GetPoints().GetPoint(i)
            if max(abs(x - y) for x, y in zip(pa, pb)) > 1e-12:
                sys.exit(f"hex_legacy.vtu: VTK reads cell {c} node {i} at {pb}, not {pa}")
    print(f"wrote {len(os.listdir(OUT))} files to {OUT} with VTK {vtk.vtkVersion.GetVTKVersion()}")


if __name__ == "__main__":
    main()
