#!/usr/bin/env python3
"""Writes tests/data/vtk/lagrange_simplices.json with VTK itself (pip install vtk; written
with VTK 9.7): for vtkLagrangeTriangle (VTK_LAGRANGE_TRIANGLE = 69) and vtkLagrangeTetra
(VTK_LAGRANGE_TETRAHEDRON = 71) of orders 1 to 10, the parametric coordinates VTK gives
each point of the cell in its own point order (GetParametricCoords), and VTK's shape
functions (InterpolateFunctions) at two parametric points inside the cell, with their
parametric derivatives (InterpolateDerivs) at the first; values to 13 significant digits. tests/spectral_simplex.rs checks our node order and
basis against them. Run from the repository root: python3 scripts/vtk-simplex-fixtures.py
"""
import json
import os

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


if __name__ == "__main__":
    main()
