#!/usr/bin/env python3
"""Writes the VTK fixtures of tests/spectral_vtk_files.rs with VTK itself (pip install vtk;
written with VTK 9.7): two order-3 Lagrange hexahedra and two order-3 Lagrange
quadrilaterals, their nodes placed and ordered by VTK's own PointIndexFromIJK, with the point
field u given below, in every encoding vtkXMLUnstructuredGridWriter offers: ascii, inline
binary and appended (raw and base64), uncompressed and zlib/LZ4/LZMA, UInt32 and UInt64
headers; `quad_series.pvd`, a ParaView collection (written as ParaView's vtkPVDWriter
writes it: VTK has no writer of its own for it) of three VTK-written files whose field is
(1 + k) times the quadrilaterals' field at times 0, 0.5, 1. Also `hex_legacy.vtu`: the same hexahedra with the node order VTK used before file
version 2.2 (vertical edges 2-6 and 3-7 swapped) and the version attribute set to 1.0, checked
by reading it back with VTK. Run from the repository root: python3 scripts/vtk-fixtures.py
"""
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
