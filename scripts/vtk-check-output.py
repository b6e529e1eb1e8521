#!/usr/bin/env python3
"""Checks that VTK reads a .vtu file galerkin wrote as galerkin meant it: VTK's own Lagrange
cells evaluated at each cell's parametric centre and at its nodes give the point data there,
and every cell's Jacobian determinant (VTK's vtkCellQuality is not defined for Lagrange cells,
so by finite differences of VTK's EvaluateLocation) keeps one sign. A node in the wrong
place (e.g. a hexahedron's vertical edges swapped) folds the cell.
A spacetime .vtu (linear tetrahedra in (x, y, t)) is checked with vtkMeshQuality instead:
every tetrahedron must have positive volume by VTK's convention.
A .pvd collection is checked file by file (each dataset it lists must exist and read).
Usage: python3 scripts/vtk-check-output.py FILE.vtu|FILE.pvd   (pip install vtk)
"""
import sys

import vtk


def main(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    if g.GetNumberOfCells() == 0:
        sys.exit(f"{path}: VTK read no cells")
    if g.GetCellType(0) == vtk.VTK_TETRA:
        q = vtk.vtkMeshQuality()
        q.SetInputData(g)
        q.SetTetQualityMeasureToVolume()
        q.Update()
        a = q.GetOutput().GetCellData().GetArray("Quality")
        negative = [i for i in range(a.GetNumberOfTuples()) if a.GetValue(i) <= 0]
        if negative:
            sys.exit(f"{path}: {len(negative)} of {a.GetNumberOfTuples()} tetrahedra have volume <= 0 in VTK (first: cell {negative[0]})")
        print(f"{path}: VTK {vtk.vtkVersion.GetVTKVersion()} reads {g.GetNumberOfCells()} tetrahedra, all of positive volume")
        return
    signs = set()
    for c in range(g.GetNumberOfCells()):
        cell = g.GetCell(c)
        dim = cell.GetCellDimension()
        h = 1e-6
        # The centre, and next to each vertical edge (where swapped edge nodes fold a cell).
        for pc in ([0.5, 0.5, 0.5], [0.02, 0.02, 0.5], [0.98, 0.02, 0.5], [0.98, 0.98, 0.5], [0.02, 0.98, 0.5]):
            if dim == 2:
                pc = [pc[0], pc[1], 0.0]
            x0 = evaluate(cell, pc)
            cols = []
            for a in range(dim):
                q = list(pc)
                q[a] += h
                cols.append([(p - p0) / h for p, p0 in zip(evaluate(cell, q), x0)])
            if dim == 3:
                (a, b, c3) = cols
                det = (a[0] * (b[1] * c3[2] - b[2] * c3[1]) - a[1] * (b[0] * c3[2] - b[2] * c3[0])
                       + a[2] * (b[0] * c3[1] - b[1] * c3[0]))
            else:
                a, b = cols
                n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
                det = sum(v * v for v in n) ** 0.5
            signs.add(det > 0)
            if abs(det) < 1e-12:
                sys.exit(f"{path}: cell {c} collapses at {pc} in VTK (Jacobian {det})")
    if len(signs) != 1:
        sys.exit(f"{path}: VTK finds cells of both orientations: a node order VTK reads differently")
    print(f"{path}: VTK {vtk.vtkVersion.GetVTKVersion()} reads {g.GetNumberOfCells()} cells, none folded")


def evaluate(cell, pc):
    sub = vtk.reference(0)
    x = [0.0, 0.0, 0.0]
    w = [0.0] * cell.GetNumberOfPoints()
    cell.EvaluateLocation(sub, pc, x, w)
    return x


def collection(path):
    import os
    import xml.etree.ElementTree as ET
    sets = ET.parse(path).getroot().iter("DataSet")
    files = [(float(s.get("timestep", "nan")), os.path.join(os.path.dirname(path), s.get("file"))) for s in sets]
    if not files:
        sys.exit(f"{path}: no DataSet")
    times = [t for t, _ in files]
    if times != sorted(times):
        sys.exit(f"{path}: time steps out of order")
    for _, f in files:
        main(f)
    print(f"{path}: {len(files)} time steps from {times[0]} to {times[-1]}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    if sys.argv[1].endswith(".pvd"):
        collection(sys.argv[1])
    else:
        main(sys.argv[1])
