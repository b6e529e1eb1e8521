#!/usr/bin/env python3
"""The peer of `galerkin spectral render FILE --iso C` (and of `galerkin spectral bench --iso`):
VTK's own isosurface pipeline on the same high-order file, with the geometric error of what
it draws against the exact isosurface. Needs VTK (pip install vtk; measured with VTK 9.7).

What a ParaView user has for a contour of high-order cells, run here through VTK's classes:
  - `direct`: vtkContourFilter on the Lagrange cells themselves (VTK contours each cell's
    own linear subdivision at its order);
  - `tessellate L`: vtkTessellatorFilter (ParaView's "Tessellate", maximum subdivisions L,
    chord and field errors asked at 1e-9 so that every level subdivides everywhere) into linear tetrahedra, then
    vtkContourFilter — the piecewise-linear isosurface of a subdivision L levels deep.

Error: at every vertex of the contour, the exact field u and its gradient are evaluated on
the original high-order cells (# How far outside every cell (in parametric units) a contour vertex may lie and still be
# evaluated, on the nearest cell's polynomial continued: a linear facet of a subdivision cuts
# outside a bulging curved boundary.
CONTINUATION = 0.05


class Exact: Newton's method on each cell's own map through
VTK's shape functions, no subdivision), and the vertex's distance from the exact isosurface
is estimated to first order as |u - c| / |grad u|; reported as the largest and the mean
over the vertices, in units of the mesh's bounding-box diagonal, with the largest |u - c|
relative to the field's range. Vertices within 1e-3 of the diagonal of a point where
|grad u| is below 1e-3 of its median (a saddle, where the estimate means nothing) are left
out and counted. Time: wall seconds of the subdivision and the contour (median of --runs),
without reading the file or drawing. Vertices just outside every cell (a linear facet
cutting outside a bulging boundary, up to CONTINUATION) are evaluated on the nearest cell's
polynomial continued; any farther out are left out and counted too.

Usage, from the repository root:
  python3 scripts/vtk-iso-peer.py tests/data/vtk/hex_saddle_o9.vtu --iso 0.12 --levels 0-4
Prints a Markdown table.
"""
import argparse
import math
import statistics
import sys
import time

import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy
import numpy as np


def read(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    if g.GetNumberOfCells() == 0:
        sys.exit(f"{path}: no cells read")
    return g


def contour(data, name, value):
    c = vtk.vtkContourFilter()
    c.SetInputData(data)
    c.SetInputArrayToProcess(0, 0, 0, vtk.vtkDataObject.FIELD_ASSOCIATION_POINTS, name)
    c.SetValue(0, value)
    c.Update()
    return c.GetOutput()


def tessellate(g, level):
    t = vtk.vtkTessellatorFilter()
    t.SetInputData(g)
    t.SetMaximumNumberOfSubdivisions(level)
    t.SetChordError(1e-9)
    t.SetFieldCriterion(0, 1e-9)
    t.SetMergePoints(1)
    t.Update()
    return t.GetOutput()


# How far outside every cell (in parametric units) a contour vertex may lie and still be
# evaluated, on the nearest cell's polynomial continued: a linear facet of a subdivision cuts
# outside a bulging curved boundary.
CONTINUATION = 0.05


class Exact:
    """The field of the high-order cells evaluated exactly at physical points: each point's
    parametric coordinates found by Newton's method on the cell's own map (VTK's
    InterpolateFunctions of the cell, no subdivision), then u and its
    physical gradient J^-T du/dr from the same functions. (vtkProbeFilter is not used: VTK's
    higher-order cells invert their map on a linear subdivision, which is what is measured.)"""

    def __init__(self, g, name):
        self.g = g
        self.u = vtk_to_numpy(g.GetPointData().GetArray(name)).astype(float)
        self.x = vtk_to_numpy(g.GetPoints().GetData()).astype(float)
        self.cells = []
        for c in range(g.GetNumberOfCells()):
            cell = vtk.vtkGenericCell()
            g.GetCell(c, cell)
            ids = [cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())]
            b = np.array(g.GetCell(c).GetBounds()).reshape(3, 2)
            grow = 0.25 * (b[:, 1] - b[:, 0]).max()
            self.cells.append((cell, np.array(ids), b[:, 0] - grow, b[:, 1] + grow))

    @staticmethod
    def functions(cell, pc, n):
        """The shape functions at pc and their parametric derivatives (3 × n) by central
        differences of them (1e-6: ample for Newton, whose residual is exact, and for |grad u|
        to 1e-9; VTK's cells do not agree on the layout of InterpolateDerivs)."""
        w = [0.0] * n
        cell.InterpolateFunctions(list(pc), w)
        d = np.zeros((3, n))
        for a in range(3):
            hi, lo = list(pc), list(pc)
            hi[a] += 1e-6
            lo[a] -= 1e-6
            wh, wl = [0.0] * n, [0.0] * n
            cell.InterpolateFunctions(hi, wh)
            cell.InterpolateFunctions(lo, wl)
            d[a] = (np.array(wh) - np.array(wl)) / 2e-6
        return np.array(w), d

    def at(self, x):
        """(u, |grad u|) at x, or None if no cell holds it (nor comes within CONTINUATION)."""
        best = None
        for cell, ids, lo, hi in self.cells:
            if np.any(x < lo) or np.any(x > hi):
                continue
            n = len(ids)
            X, U = self.x[ids], self.u[ids]
            simplex = cell.GetCellType() in (vtk.VTK_LAGRANGE_TETRAHEDRON, vtk.VTK_TETRA)
            pc = np.array([0.25] * 3 if simplex else [0.5] * 3)
            for _ in range(40):
                w, D = self.functions(cell, pc, n)
                try:
                    step = np.linalg.solve((D @ X).T, w @ X - x)
                except np.linalg.LinAlgError:
                    break
                step *= min(1.0, 0.5 / max(1e-300, np.abs(step).max()))
                pc = pc - step
                if np.abs(step).max() < 1e-13:
                    break
            outside = max(-pc.min(), pc.sum() - 1 if simplex else pc.max() - 1, 0.0)
            if not np.isfinite(outside) or (best is not None and outside >= best[0]):
                continue
            w, D = self.functions(cell, pc, n)
            grad = np.linalg.solve(D @ X, D @ U)
            best = (outside, float(w @ U), float(np.linalg.norm(grad)))
            if outside <= 1e-9:
                break
        return None if best is None or best[0] > CONTINUATION else best[1:]


def errors(exact, surface, value, diag, span):
    n = surface.GetNumberOfPoints()
    if n == 0:
        return None
    x = vtk_to_numpy(surface.GetPoints().GetData()).astype(float)
    found = [exact.at(p) for p in x]
    ok = np.array([f is not None for f in found])
    u = np.array([f[0] if f else np.nan for f in found])
    norm = np.array([f[1] if f else np.nan for f in found])
    flat = ok & (norm < 1e-3 * np.median(norm[ok]))
    near = np.zeros(n, dtype=bool)
    for c in x[flat]:
        near |= np.linalg.norm(x - c, axis=1) < 1e-3 * diag
    use = ok & ~near
    dist = np.abs(u[use] - value) / norm[use] / diag
    return {
        "vertices": n,
        "left out": int((~use).sum()),
        "max": float(dist.max()) if dist.size else math.nan,
        "mean": float(dist.mean()) if dist.size else math.nan,
        "max |u-c|": float(np.abs(u[use] - value).max() / span) if dist.size else math.nan,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file")
    ap.add_argument("--iso", type=float, required=True, help="the iso value")
    ap.add_argument("--field", default=None, help="point array (default: the first)")
    ap.add_argument("--levels", default="0-4", help="tessellation levels, e.g. 0-4")
    ap.add_argument("--runs", type=int, default=3, help="timed runs per level (the median)")
    a = ap.parse_args()
    g = read(a.file)
    name = a.field or g.GetPointData().GetArrayName(0)
    if g.GetPointData().GetArray(name) is None:
        sys.exit(f"{a.file}: no point array {name!r}")
    exact = Exact(g, name)
    b = g.GetBounds()
    diag = math.sqrt(sum((b[2 * k + 1] - b[2 * k]) ** 2 for k in range(3)))
    lo, hi = g.GetPointData().GetArray(name).GetRange()
    span = hi - lo
    lo_level, _, hi_level = a.levels.partition("-")
    levels = range(int(lo_level), int(hi_level or lo_level) + 1)
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}: {a.file} ({g.GetNumberOfCells()} cells, type {g.GetCellType(0)}), "
          f"{name} = {a.iso}; distances in units of the bounding-box diagonal ({diag:.4g})\n")
    print("| VTK pipeline | linear cells | triangles | time (s), median | max distance | mean distance | max abs(u − c) ÷ range | vertices (left out) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    cases = [("direct vtkContourFilter", None)] + [(f"vtkTessellatorFilter {L} + vtkContourFilter", L) for L in levels]
    for label, level in cases:
        times = []
        for _ in range(max(1, a.runs)):
            t = time.perf_counter()
            data = g if level is None else tessellate(g, level)
            surface = contour(data, name, a.iso)
            times.append(time.perf_counter() - t)
        cells = g.GetNumberOfCells() if level is None else data.GetNumberOfCells()
        e = errors(exact, surface, a.iso, diag, span)
        if e is None:
            print(f"| {label} | {cells} | 0 | {statistics.median(times):.3f} | – | – | – | 0 |")
            continue
        print(f"| {label} | {cells} | {surface.GetNumberOfCells()} | {statistics.median(times):.3f} | "
              f"{e['max']:.2e} | {e['mean']:.2e} | {e['max |u-c|']:.2e} | {e['vertices']} ({e['left out']}) |")


if __name__ == "__main__":
    main()
