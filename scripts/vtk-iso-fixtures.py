#!/usr/bin/env python3
"""Writes the isosurface fixtures of tests/spectral_iso.rs with VTK itself (pip install vtk;
written with VTK 9.7): `hex_saddle_o6.vtu` and `hex_saddle_o9.vtu`, two curved Lagrange
hexahedra (VTK_LAGRANGE_HEXAHEDRON = 72) of orders 6 and 9 side by side, nodes placed and
ordered by VTK's own PointIndexFromIJK, shared along the common face, with the point field

    u = X^2 + Y^2 - Z^2 + 2 X^3 Y Z + 0.5 X^4 Y^2,   (X, Y, Z) = p - (1, 1/2, 1/2),

where p in [0, 2] x [0, 1] x [0, 1] is the node's place on the undeformed grid (so u is a
polynomial of each element's reference coordinates, of degree at most 4 per axis: exact at
both orders). The geometry is p moved by a smooth bend (not affine: curved cells), so the
isosurfaces are curved in space. u has a saddle at the centre of the shared face (value 0,
gradient 0, Hessian diag(2, 2, -2)): the level set u = 0 is a double cone whose two sheets
touch there, and the level sets 0.04 and 0.12 are nested hyperboloids around it. Beside each
file a `.json` holds VTK's own evaluation (EvaluateLocation and the interpolation weights) of
the geometry and of u at parametric points of both cells. Run from the repository root:
python3 scripts/vtk-iso-fixtures.py
"""
import json
import math
import os

import vtk

OUT = os.path.join("tests", "data", "vtk")
PARAMETRIC = [[0.13, 0.41, 0.77], [0.5, 0.5, 0.5], [0.91, 0.06, 0.33]]


def u_of(p):
    X, Y, Z = p[0] - 1.0, p[1] - 0.5, p[2] - 0.5
    return X * X + Y * Y - Z * Z + 2.0 * X**3 * Y * Z + 0.5 * X**4 * Y * Y


def bend(p):
    """The undeformed point p moved: smooth, Jacobian near the identity."""
    x, y, z = p
    return (
        x + 0.06 * math.sin(math.pi * y) * math.sin(math.pi * z),
        y + 0.05 * math.sin(0.5 * math.pi * x) * math.sin(math.pi * z),
        z + 0.10 * math.sin(0.5 * math.pi * x) * math.sin(math.pi * y),
    )


def grid(order):
    g = vtk.vtkUnstructuredGrid()
    pts = vtk.vtkPoints()
    pts.SetDataTypeToDouble()
    u = vtk.vtkDoubleArray()
    u.SetName("u")
    cell = vtk.vtkLagrangeHexahedron()
    shared = {}
    per = (order + 1) ** 3
    for c in range(2):
        ids = [0] * per
        for k in range(order + 1):
            for j in range(order + 1):
                for i in range(order + 1):
                    at = cell.PointIndexFromIJK(i, j, k, [order] * 3)
                    key = (c * order + i, j, k)
                    if key not in shared:
                        p = (key[0] / order, j / order, k / order)
                        shared[key] = pts.InsertNextPoint(*bend(p))
                        u.InsertNextValue(u_of(p))
                    ids[at] = shared[key]
        g.InsertNextCell(vtk.VTK_LAGRANGE_HEXAHEDRON, per, ids)
    g.SetPoints(pts)
    g.GetPointData().AddArray(u)
    return g


def evaluations(g):
    u = g.GetPointData().GetArray("u")
    records = []
    for c in range(g.GetNumberOfCells()):
        cell = g.GetCell(c)
        for pc in PARAMETRIC:
            x = [0.0, 0.0, 0.0]
            weights = [0.0] * cell.GetNumberOfPoints()
            cell.EvaluateLocation(vtk.reference(0), pc, x, weights)
            value = sum(wt * u.GetValue(cell.GetPointId(i)) for i, wt in enumerate(weights))
            records.append({"element": c, "ref": pc, "x": x, "value": value})
    return records


def main():
    for order in (6, 9):
        g = grid(order)
        name = f"hex_saddle_o{order}"
        w = vtk.vtkXMLUnstructuredGridWriter()
        w.SetInputData(g)
        w.SetFileName(os.path.join(OUT, name + ".vtu"))
        w.SetDataModeToAppended()
        w.SetCompressorTypeToZLib()
        w.Write()
        with open(os.path.join(OUT, name + ".json"), "w") as f:
            json.dump({"writer": f"VTK {vtk.vtkVersion.GetVTKVersion()}", "order": order, "evaluations": evaluations(g)}, f, indent=1)
        print(f"{name}: {g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} cells")


if __name__ == "__main__":
    main()
