#!/usr/bin/env python3
"""Writes the MFEM fixtures of tests/spectral_mfem_files.rs with MFEM itself (PyMFEM:
pip install mfem; written with MFEM 4.10): curved quadrilateral and hexahedral meshes and
GridFunctions in the collections the reader supports (H1 Gauss-Lobatto, H1Pos Bernstein, L2
Gauss-Legendre), saved with mesh.Print / GridFunction.Save at 17 digits, and beside each a
JSON of MFEM's own evaluations at reference points: per record the element, the reference
point, the physical point (ElementTransformation.Transform) and the value
(GridFunction.GetValue). The test compares our reader's geometry and field with MFEM's at
those points. Run from the repository root: python3 scripts/mfem-fixtures.py
"""
import json
import math
import os

import mfem.ser as mfem

OUT = os.path.join("tests", "data", "mfem")


class Field(mfem.PyCoefficient):
    def EvalValue(self, x):
        z = x[2] if len(x) > 2 else 0.0
        return math.sin(1.3 * x[0]) * math.cos(0.7 * x[1]) + 0.4 * z * x[0] + 0.25 * x[1] ** 2


def bend(x):
    # A smooth bending of the box: curved elements, Jacobians far from zero.
    y = list(x)
    y[0] = x[0] + 0.08 * math.sin(2.0 * x[1])
    y[1] = x[1] + 0.06 * math.sin(2.5 * x[0])
    return y


def evaluations(mesh, gf, points):
    dim = mesh.Dimension()
    records = []
    for e in range(mesh.GetNE()):
        T = mesh.GetElementTransformation(e)
        for r in points:
            ip = mfem.IntegrationPoint()
            if dim == 2:
                ip.Set2(r[0], r[1])
            else:
                ip.Set3(r[0], r[1], r[2])
            T.SetIntPoint(ip)
            x = [float(v) for v in T.Transform(ip)]
            records.append({"element": e, "ref": list(r[:dim]), "x": x, "value": gf.GetValue(e, ip)})
    return records


def write(name, mesh, fec, points):
    fes = mfem.FiniteElementSpace(mesh, fec)
    gf = mfem.GridFunction(fes)
    gf.ProjectCoefficient(Field())
    mesh.Print(os.path.join(OUT, f"{name}.mesh"), 17)
    gf.Save(os.path.join(OUT, f"{name}.gf"), 17)
    with open(os.path.join(OUT, f"{name}.json"), "w") as f:
        json.dump({"collection": fec.Name(), "records": evaluations(mesh, gf, points)}, f)


def curved(mesh, order):
    mesh.SetCurvature(order, False, -1, mfem.Ordering.byVDIM)
    nodes = mesh.GetNodes()
    dim = mesh.Dimension()
    n = nodes.Size() // dim
    data = nodes.GetDataArray()
    for i in range(n):
        x = [data[dim * i + k] for k in range(dim)]
        y = bend(x)
        for k in range(dim):
            data[dim * i + k] = y[k]
    return mesh


def main():
    os.makedirs(OUT, exist_ok=True)
    pts2 = [(0.5, 0.5), (0.1, 0.8), (0.93, 0.27), (0.0, 0.0), (1.0, 0.35)]
    pts3 = [(0.5, 0.5, 0.5), (0.1, 0.8, 0.3), (0.93, 0.27, 0.61), (0.0, 1.0, 0.0), (1.0, 0.35, 1.0)]
    quads = curved(mfem.Mesh(3, 2, "QUADRILATERAL", False, 1.5, 1.0), 3)
    write("quad_h1_p4", quads, mfem.H1_FECollection(4, 2), pts2)
    write("quad_h1pos_p3", quads, mfem.H1_FECollection(3, 2, mfem.BasisType.Positive), pts2)
    write("quad_l2_p3", quads, mfem.L2_FECollection(3, 2), pts2)
    hexes = curved(mfem.Mesh(2, 2, 1, "HEXAHEDRON", False, 1.0, 1.0, 0.5), 2)
    write("hex_h1_p3", hexes, mfem.H1_FECollection(3, 3), pts3)
    print(f"wrote {len(os.listdir(OUT))} files to {OUT}")


if __name__ == "__main__":
    main()
