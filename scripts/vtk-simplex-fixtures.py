#!/usr/bin/env python3
"""Writes tests/data/vtk/lagrange_simplices.json with VTK itself (pip install vtk; written
with VTK 9.7): for vtkLagrangeTriangle (VTK_LAGRANGE_TRIANGLE = 69) and vtkLagrangeTetra
(VTK_LAGRANGE_TETRAHEDRON = 71) of orders 1 to 10, the parametric coordinates VTK gives
each point of the cell in its own point order (GetParametricCoords), and VTK's shape
functions (InterpolateFunctions) at two parametric points inside the cell, with their
parametric derivatives (InterpolateDerivs) at the first; values to 13 significant digits. tests/spectral_simplex.rs checks our node order and
basis against them. Beside it, curved cells VTK wrote as .vtu files with VTK's own evaluation
of them read back (.json): Lagrange triangles and tetrahedra, and Bézier ones
(vtkBezierTriangle, VTK_BEZIER_TRIANGLE = 76; vtkBezierTetra, VTK_BEZIER_TETRAHEDRON = 78;
one rational) for tests/spectral_bezier_simplices.rs. Run from the repository root:
python3 scripts/vtk-simplex-fixtures.py (everything) or ... bezier (the Bézier files only).
"""
import json
import math
import os
import sys

import vtk

OUT = os.path.join("tests", "data", "vtk", "lagrange_simplices.json")
MAX_ORDER = 10
SAMPLES = {
    "triangle": [[0.2113, 0.3371, 0.0], [0.61, 0.07, 0.0]],
    "tetrahedron": [[0.1531, 0.2207, 0.3109], [0.05, 0.62, 0.11]],
}


def short(x):
    """x to 13 significant digits (the tests compare to 1e-11)."""
    return float(f"{x:.13g}")


def cell_of(kind, order):
    if kind == "triangle":
        cell = vtk.vtkLagrangeTriangle()
        n = (order + 1) * (order + 2) // 2
        dim = 2
    else:
        cell = vtk.vtkLagrangeTetra()
        n = (order + 1) * (order + 2) * (order + 3) // 6
        dim = 3
    cell.GetPointIds().SetNumberOfIds(n)
    cell.GetPoints().SetNumberOfPoints(n)
    for i in range(n):
        cell.GetPointIds().SetId(i, i)
        cell.GetPoints().SetPoint(i, 0.0, 0.0, 0.0)
    cell.Initialize()
    return cell, n, dim


def main():
    if sys.argv[1:] == ["bezier"]:
        bezier_files()
        return
    out = {"vtk": vtk.vtkVersion.GetVTKVersion(), "cells": []}
    for kind in ("triangle", "tetrahedron"):
        for order in range(1, MAX_ORDER + 1):
            cell, n, dim = cell_of(kind, order)
            pc = cell.GetParametricCoords()
            coords = [[short(pc[3 * i + a]) for a in range(dim)] for i in range(n)]
            samples = []
            for k, r in enumerate(SAMPLES[kind]):
                weights = [0.0] * n
                cell.InterpolateFunctions(r, weights)
                sample = {"r": r[:dim], "weights": [short(w) for w in weights]}
                if k == 0:
                    derivs = [0.0] * (dim * n)
                    cell.InterpolateDerivs(r, derivs)
                    sample["derivatives"] = [[short(x) for x in derivs[a * n:(a + 1) * n]] for a in range(dim)]
                samples.append(sample)
            out["cells"].append({"shape": kind, "order": order, "points": coords, "samples": samples})
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as f:
        json.dump(out, f, separators=(",", ":"))
    print(OUT, os.path.getsize(OUT), "bytes")
    curved_file("triangle", "tri_curved")
    curved_file("tetrahedron", "tet_curved")
    # Per-pixel drawing: higher orders on more cells (shared curved edges).
    curved_file("triangle", "tri_curved_o6", order=6, side=2)
    curved_file("triangle", "tri_curved_o10", order=10, side=1)
    curved_file("tetrahedron", "tet_cube_o6", order=6, side=2)
    curved_file("tetrahedron", "tet_cube_o3", order=3, side=2)
    bezier_files()
    # A curved surface in 3D: order-4 triangles lifted off the plane.
    curved_file("triangle", "tri_surface_o4", order=4, side=2, lifted=True)


def bezier_files():
    """Bézier simplices: the control points are the bent lattice points of the straight cells
    and the field's control values the field there (a curved cell that interpolates neither)."""
    curved_file("triangle", "bezier_tri_o5", order=5, side=2, bezier=True)
    curved_file("tetrahedron", "bezier_tet_o4", order=4, side=2, bezier=True)
    # Rational: weights 1 + 0.4 x y on one order-2 triangle (not drawn; refused by name).
    curved_file("triangle", "bezier_tri_rational", order=2, side=1, bezier=True, rational=True)


def field(x, y, z):
    return math.sin(1.3 * x) + y * y - 0.5 * x * z + 0.25


def bend(p, planar):
    """A smooth curving of the straight cells (keeps the shared face shared; the triangles
    stay in the plane z = 0)."""
    x, y, z = p
    return (x + 0.08 * math.sin(2.0 * y), y + 0.06 * math.sin(1.7 * x + 0.5 * z), z + (0.0 if planar else 0.05 * x * y))


def triangle_grid(side):
    """The unit square cut into side x side squares, each split into two triangles along its
    diagonal (counter-clockwise corners)."""
    h = 1.0 / side
    out = []
    for j in range(side):
        for i in range(side):
            a, b = (i * h, j * h, 0.0), ((i + 1) * h, j * h, 0.0)
            c, d = ((i + 1) * h, (j + 1) * h, 0.0), (i * h, (j + 1) * h, 0.0)
            out += [[a, b, d], [b, c, d]]
    return out


def kuhn_cube():
    """The unit cube in six tetrahedra around its diagonal (Kuhn's subdivision), each from
    (0, 0, 0) to (1, 1, 1) along one order of the axes, positively oriented."""
    out = []
    for perm, even in (((0, 1, 2), True), ((1, 2, 0), True), ((2, 0, 1), True),
                       ((0, 2, 1), False), ((2, 1, 0), False), ((1, 0, 2), False)):
        v = [0.0, 0.0, 0.0]
        verts = [tuple(v)]
        for axis in perm:
            v[axis] = 1.0
            verts.append(tuple(v))
        if not even:
            verts[1], verts[2] = verts[2], verts[1]
        out.append(verts)
    return out


def curved_file(kind, name, order=3, side=1, bezier=False, rational=False, lifted=False):
    """Curved Lagrange (or, with `bezier`, Bézier) cells of `order` written by VTK as
    `name`.vtu (ascii), with VTK's own evaluation of them at sample points in `name`.json.
    Triangles: the unit square in side x side squares of two triangles each (side 1: only the
    first, when rational); tetrahedra: two (side 1) or the unit cube in six (side 2). Bézier
    cells take the bent lattice points as control points, and `rational` ones RationalWeights
    1 + 0.4 x y; `lifted` triangles rise off the plane to z = 0.3 sin(2.2 x + 0.4) cos(1.3 y)."""
    if kind == "triangle":
        corners = triangle_grid(side)[: 1 if rational else None]
        cell_type = vtk.VTK_BEZIER_TRIANGLE if bezier else vtk.VTK_LAGRANGE_TRIANGLE
    elif side == 2:
        corners = kuhn_cube()
        cell_type = vtk.VTK_BEZIER_TETRAHEDRON if bezier else vtk.VTK_LAGRANGE_TETRAHEDRON
    else:
        corners = [[(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)],
                   [(1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]]
        cell_type = vtk.VTK_LAGRANGE_TETRAHEDRON
    grid = vtk.vtkUnstructuredGrid()
    weights_array = vtk.vtkDoubleArray()
    weights_array.SetName("RationalWeights")
    points = vtk.vtkPoints()
    points.SetDataTypeToDouble()
    values = vtk.vtkDoubleArray()
    values.SetName("u")
    cells = []
    for c in corners:
        cell, n, dim = cell_of(kind, order)
        pc = cell.GetParametricCoords()
        ids = []
        for i in range(n):
            r = [pc[3 * i + a] for a in range(3)]
            # The straight cell's point at r (vertex 0 plus r along the axes), then curved.
            straight = [c[0][a] + sum(r[k] * (c[k + 1][a] - c[0][a]) for k in range(dim)) for a in range(3)]
            x = bend(straight, kind == "triangle")
            if lifted:
                x = (x[0], x[1], 0.3 * math.sin(2.2 * x[0] + 0.4) * math.cos(1.3 * x[1]))
            ids.append(points.InsertNextPoint(*x))
            values.InsertNextValue(field(*x))
            weights_array.InsertNextValue(1.0 + 0.4 * x[0] * x[1])
        cells.append(ids)
    grid.SetPoints(points)
    for ids in cells:
        idl = vtk.vtkIdList()
        for i in ids:
            idl.InsertNextId(i)
        grid.InsertNextCell(cell_type, idl)
    grid.GetPointData().AddArray(values)
    if rational:
        grid.GetPointData().SetRationalWeights(weights_array)
    writer = vtk.vtkXMLUnstructuredGridWriter()
    writer.SetFileName(os.path.join(os.path.dirname(OUT), name + ".vtu"))
    writer.SetInputData(grid)
    writer.SetDataModeToAscii()
    writer.Write()
    # VTK's evaluation of what it wrote, read back.
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(os.path.join(os.path.dirname(OUT), name + ".vtu"))
    reader.Update()
    back = reader.GetOutput()
    u = back.GetPointData().GetArray("u")
    samples = []
    for e in range(back.GetNumberOfCells()):
        cell = back.GetCell(e)
        n = cell.GetNumberOfPoints()
        for r in SAMPLES[kind] + ([[0.1, 0.1, 0.7]] if kind == "tetrahedron" else [[0.1, 0.8, 0.0]]):
            x = [0.0, 0.0, 0.0]
            weights = [0.0] * n
            cell.EvaluateLocation(vtk.reference(0), r, x, weights)
            value = sum(weights[i] * u.GetValue(cell.GetPointId(i)) for i in range(n))
            samples.append({"element": e, "r": r[: 2 if kind == "triangle" else 3], "x": x, "u": value})
    with open(os.path.join(os.path.dirname(OUT), name + ".json"), "w") as f:
        json.dump({"vtk": vtk.vtkVersion.GetVTKVersion(), "samples": samples}, f, indent=1)


if __name__ == "__main__":
    main()
