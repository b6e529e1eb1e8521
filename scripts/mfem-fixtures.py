#!/usr/bin/env python3
"""Writes the MFEM fixtures of tests/spectral_mfem_files.rs with MFEM itself (PyMFEM:
pip install mfem; written with MFEM 4.10): curved quadrilateral, hexahedral, triangular and
tetrahedral meshes and GridFunctions in the collections the reader supports (H1 Gauss-Lobatto, H1Pos Bernstein, L2
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
    # MFEM's evaluation of the files as MFEM (and GLVis) read them back.
    back = mfem.Mesh(os.path.join(OUT, f"{name}.mesh"))
    back_gf = mfem.GridFunction(back, os.path.join(OUT, f"{name}.gf"))
    with open(os.path.join(OUT, f"{name}.json"), "w") as f:
        json.dump({"collection": fec.Name(), "records": evaluations(back, back_gf, points)}, f)


def nodes_json():
    """simplex_nodes.json: the reference points of MFEM's nodal simplex elements (H1 on
    Gauss-Lobatto and equispaced points, L2 on Gauss-Legendre, Gauss-Lobatto and equispaced
    points; orders 1-6) in MFEM's local DOF order, which the reader reproduces."""
    out = []
    for dim in (2, 3):
        for p in range(1, 7):
            for family, btype in (("H1", mfem.BasisType.GaussLobatto), ("H1", mfem.BasisType.ClosedUniform),
                                  ("L2", mfem.BasisType.GaussLegendre), ("L2", mfem.BasisType.GaussLobatto),
                                  ("L2", mfem.BasisType.ClosedUniform)):
                if family == "H1":
                    fec = mfem.H1_FECollection(p, dim, btype)
                else:
                    fec = mfem.L2_FECollection(p, dim, btype)
                fe = fec.FiniteElementForGeometry(mfem.Geometry.TRIANGLE if dim == 2 else mfem.Geometry.TETRAHEDRON)
                ir = fe.GetNodes()
                pts = [[ir.IntPoint(i).x, ir.IntPoint(i).y, ir.IntPoint(i).z][:dim] for i in range(ir.GetNPoints())]
                out.append({"collection": fec.Name(), "points": pts})
    with open(os.path.join(OUT, "simplex_nodes.json"), "w") as f:
        json.dump({"mfem": "4.10", "elements": out}, f)


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
    # Simplices: points of the reference triangle and tetrahedron, corners and faces included.
    tri = [(1 / 3, 1 / 3), (0.1, 0.8), (0.62, 0.27), (0.0, 0.0), (0.0, 0.35), (0.5, 0.5)]
    tet = [(0.25, 0.25, 0.25), (0.1, 0.7, 0.1), (0.53, 0.17, 0.21), (0.0, 0.0, 1.0), (0.3, 0.0, 0.45),
           (0.2, 0.3, 0.5)]
    triangles = curved(mfem.Mesh(3, 2, "TRIANGLE", False, 1.5, 1.0), 3)
    write("tri_h1_p4", triangles, mfem.H1_FECollection(4, 2), tri)
    write("tri_l2_p3", triangles, mfem.L2_FECollection(3, 2), tri)
    write("tri_h1pos_p3", triangles, mfem.H1_FECollection(3, 2, mfem.BasisType.Positive), tri)
    tets = curved(mfem.Mesh(2, 2, 1, "TETRAHEDRON", False, 1.0, 1.0, 0.5), 4)
    write("tet_h1_p5", tets, mfem.H1_FECollection(5, 3), tet)
    write("tet_l2_p2", tets, mfem.L2_FECollection(2, 3), tet)
    write("tet_h1pos_p4", tets, mfem.H1_FECollection(4, 3, mfem.BasisType.Positive), tet)
    nodes_json()
    print(f"wrote {len(os.listdir(OUT))} files to {OUT}")


if __name__ == "__main__":
    main()
