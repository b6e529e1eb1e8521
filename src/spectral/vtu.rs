//! Spectral elements in VTK XML unstructured grids (`.vtu`): Lagrange cells
//! (`VTK_LAGRANGE_QUADRILATERAL` = 70, `VTK_LAGRANGE_HEXAHEDRON` = 72; also the linear
//! `VTK_QUAD` = 9 and `VTK_HEXAHEDRON` = 12) and Bézier cells (`VTK_BEZIER_QUADRILATERAL` =
//! 77, `VTK_BEZIER_HEXAHEDRON` = 79: the points and point data are Bernstein coefficients;
//! `RationalWeights` other than 1 make rational cells, [`SpectralMesh::with_weights`]) with point data, as
//! ParaView and solvers write them; Lagrange triangles and tetrahedra (69, 71) and Bézier ones
//! (`VTK_BEZIER_TRIANGLE` = 76, `VTK_BEZIER_TETRAHEDRON` = 78, polynomial only: read as the
//! Lagrange simplex of the same order that equals them, [`simplex::FromBernstein`]). VTK's Lagrange cells are isoparametric on equispaced nodes
//! of [0, 1]; their points are
//! ordered corners, then edge interiors, then face interiors, then the body
//! (`vtkHigherOrderQuadrilateral::PointIndexFromIJK` and `vtkHigherOrderHexahedron::…`, VTK 9),
//! reproduced by [`vtk_point_index`]. Files of version 2.2 and later order a hexahedron's
//! vertical edges 0–4, 1–5, 2–6, 3–7; earlier ones 0–4, 1–5, 3–7, 2–6
//! ([`HexEdgeOrder`], chosen by the file's `version` as VTK's reader does). We write 2.2.
//!
//! Every one-component point-data array is a field, and so is every one-component cell-data
//! array — piecewise constant, each element's coefficients all its cell's value (exact: the
//! bases are partitions of unity), named `NAME (cells)` where a point field has its name; a
//! file with neither is refused listing the arrays it has. Arrays named `NAME_t0`, `NAME_t1`, … are
//! the time steps of field `NAME` (this is how [`fn@write`] stores several steps; ParaView shows
//! them as separate arrays). All cells must be of one shape and one order. The container
//! (encodings, compression) is [`crate::vtk`]'s. Errors name the file and the element or array.

use std::collections::BTreeMap;
use std::path::Path;

use super::basis::{Basis1d, NodeSet};
use super::error::SpectralError;
use super::mesh::{Field, Shape, SpectralMesh};
use super::simplex;
use crate::vtk::{self, OutArray, Values, VtkError};

/// `VTK_BEZIER_QUADRILATERAL`.
pub const VTK_BEZIER_QUADRILATERAL: u8 = 77;
/// `VTK_BEZIER_HEXAHEDRON`.
pub const VTK_BEZIER_HEXAHEDRON: u8 = 79;
/// `VTK_QUAD`.
pub const VTK_QUAD: u8 = 9;
/// `VTK_HEXAHEDRON`.
pub const VTK_HEXAHEDRON: u8 = 12;
/// `VTK_LAGRANGE_QUADRILATERAL`.
pub const VTK_LAGRANGE_QUADRILATERAL: u8 = 70;
/// `VTK_LAGRANGE_TRIANGLE`.
pub const VTK_LAGRANGE_TRIANGLE: u8 = 69;
/// `VTK_LAGRANGE_TETRAHEDRON`.
pub const VTK_LAGRANGE_TETRAHEDRON: u8 = 71;
/// `VTK_BEZIER_TRIANGLE`.
pub const VTK_BEZIER_TRIANGLE: u8 = 76;
/// `VTK_BEZIER_TETRAHEDRON`.
pub const VTK_BEZIER_TETRAHEDRON: u8 = 78;
/// `VTK_LAGRANGE_HEXAHEDRON`.
pub const VTK_LAGRANGE_HEXAHEDRON: u8 = 72;

impl From<VtkError> for SpectralError {
    fn from(e: VtkError) -> Self {
        SpectralError::File { path: e.path, detail: e.detail }
    }
}

/// The order of a Lagrange hexahedron's vertical edges (those joining the bottom face's
/// corners 0–3 to the top face's 4–7) in its point list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HexEdgeOrder {
    /// VTK XML files of version 2.2 and later (VTK ≥ 9.1): 0–4, 1–5, 2–6, 3–7.
    Current,
    /// Earlier files: 0–4, 1–5, 3–7, 2–6.
    Legacy,
}

impl HexEdgeOrder {
    /// The order a file of `version` (major, minor) uses.
    pub fn of_version(version: (u32, u32)) -> Self {
        if version >= (2, 2) {
            Self::Current
        } else {
            Self::Legacy
        }
    }
}

/// The position in a VTK Lagrange cell's point list of node (i, j, k) of a cell of order `n`
/// (k = 0 for quadrilaterals): corners, edges, faces, body, as VTK 9 orders them, the
/// hexahedron's vertical edges in `edges` order.
pub fn vtk_point_index(shape: Shape, n: usize, i: usize, j: usize, k: usize, edges: HexEdgeOrder) -> usize {
    let bdy = |c: usize| c == 0 || c == n;
    let (ib, jb) = (bdy(i), bdy(j));
    let corner = |i: usize, j: usize| match (i > 0, j > 0) {
        (false, false) => 0,
        (true, false) => 1,
        (true, true) => 2,
        (false, true) => 3,
    };
    let e = n - 1;
    if shape == Shape::Quadrilateral {
        return match (ib, jb) {
            (true, true) => corner(i, j),
            (false, true) => 4 + (i - 1) + if j > 0 { 2 * e } else { 0 },
            (true, false) => 4 + (j - 1) + if i > 0 { e } else { 3 * e },
            (false, false) => 4 + 4 * e + (i - 1) + e * (j - 1),
        };
    }
    let kb = bdy(k);
    let nbdy = usize::from(ib) + usize::from(jb) + usize::from(kb);
    if nbdy == 3 {
        return corner(i, j) + if k > 0 { 4 } else { 0 };
    }
    let mut offset = 8;
    if nbdy == 2 {
        if !ib {
            return (i - 1) + if j > 0 { 2 * e } else { 0 } + if k > 0 { 4 * e } else { 0 } + offset;
        }
        if !jb {
            return (j - 1) + if i > 0 { e } else { 3 * e } + if k > 0 { 4 * e } else { 0 } + offset;
        }
        offset += 8 * e;
        let vertical = match (i > 0, j > 0, edges) {
            (false, false, _) => 0,
            (true, false, _) => 1,
            (true, true, HexEdgeOrder::Current) | (false, true, HexEdgeOrder::Legacy) => 2,
            (false, true, HexEdgeOrder::Current) | (true, true, HexEdgeOrder::Legacy) => 3,
        };
        return (k - 1) + e * vertical + offset;
    }
    offset += 12 * e;
    if nbdy == 1 {
        if ib {
            return (j - 1) + e * (k - 1) + if i > 0 { e * e } else { 0 } + offset;
        }
        offset += 2 * e * e;
        if jb {
            return (i - 1) + e * (k - 1) + if j > 0 { e * e } else { 0 } + offset;
        }
        offset += 2 * e * e;
        return (i - 1) + e * (j - 1) + if k > 0 { e * e } else { 0 } + offset;
    }
    offset += 6 * e * e;
    offset + (i - 1) + e * ((j - 1) + e * (k - 1))
}

/// Reads spectral elements from a `.vtu` file (see the module docs).
pub fn read(path: &Path) -> Result<SpectralMesh, SpectralError> {
    read_piece(path)?
        .ok_or_else(|| SpectralError::File { path: path.to_path_buf(), detail: "no cells".into() })
}

/// [`read`], but a file of no cells is `None` (a piece of a partitioned data set may be
/// empty).
pub fn read_piece(path: &Path) -> Result<Option<SpectralMesh>, SpectralError> {
    let grid = vtk::read(path)?;
    if grid.cells == 0 {
        return Ok(None);
    }
    read_grid(path, &grid).map(Some)
}

fn read_grid(path: &Path, grid: &vtk::UnstructuredGrid) -> Result<SpectralMesh, SpectralError> {
    let file = |detail: String| SpectralError::File { path: path.to_path_buf(), detail };
    let cells = grid.cells;
    let points = grid.require("Points", "Points", 3, grid.points)?;
    let types = grid.require("Cells", "types", 1, cells)?;
    let offsets = grid.require("Cells", "offsets", 1, cells)?;
    let conn =
        grid.array("Cells", "connectivity").ok_or_else(|| file("no Cells array \"connectivity\"".into()))?;
    let first = types[0];
    let bezier = matches!(
        first as u8,
        VTK_BEZIER_QUADRILATERAL | VTK_BEZIER_HEXAHEDRON | VTK_BEZIER_TRIANGLE | VTK_BEZIER_TETRAHEDRON
    );
    let shape = match first as u8 {
        VTK_QUAD | VTK_LAGRANGE_QUADRILATERAL | VTK_BEZIER_QUADRILATERAL => Shape::Quadrilateral,
        VTK_HEXAHEDRON | VTK_LAGRANGE_HEXAHEDRON | VTK_BEZIER_HEXAHEDRON => Shape::Hexahedron,
        VTK_LAGRANGE_TRIANGLE | VTK_BEZIER_TRIANGLE => Shape::Triangle,
        VTK_LAGRANGE_TETRAHEDRON | VTK_BEZIER_TETRAHEDRON => Shape::Tetrahedron,
        _ => {
            return Err(file(format!(
                "element 0: cell type {first}{} (spectral elements are VTK_LAGRANGE_QUADRILATERAL = 70, VTK_LAGRANGE_HEXAHEDRON = 72, VTK_LAGRANGE_TRIANGLE = 69, VTK_LAGRANGE_TETRAHEDRON = 71, VTK_BEZIER_QUADRILATERAL = 77, VTK_BEZIER_HEXAHEDRON = 79, VTK_BEZIER_TRIANGLE = 76, VTK_BEZIER_TETRAHEDRON = 78, VTK_QUAD = 9 or VTK_HEXAHEDRON = 12)",
                vtk_cell_name(first).map_or(String::new(), |n| format!(", {n}, which the renderer does not draw"))
            )))
        }
    };
    let dim = shape.dim();
    let per_cell = offsets[0] as usize;
    let max_order = if shape.is_simplex() { simplex::MAX_SIMPLEX_ORDER } else { crate::spectral::MAX_ORDER };
    let n = (1..=max_order).find(|&n| shape.nodes(n) == per_cell).ok_or_else(|| {
        file(format!("element 0: {per_cell} points is no {shape:?} of order 1..={max_order}"))
    })?;
    let m = n + 1;
    for e in 0..cells {
        // Bézier cells do not mix with the others (their points mean something else).
        let same_shape: &[u8] = match (shape, bezier) {
            (Shape::Quadrilateral, false) => &[VTK_QUAD, VTK_LAGRANGE_QUADRILATERAL],
            (Shape::Hexahedron, false) => &[VTK_HEXAHEDRON, VTK_LAGRANGE_HEXAHEDRON],
            (Shape::Quadrilateral, true) => &[VTK_BEZIER_QUADRILATERAL],
            (Shape::Hexahedron, true) => &[VTK_BEZIER_HEXAHEDRON],
            (Shape::Triangle, false) => &[VTK_LAGRANGE_TRIANGLE],
            (Shape::Tetrahedron, false) => &[VTK_LAGRANGE_TETRAHEDRON],
            (Shape::Triangle, true) => &[VTK_BEZIER_TRIANGLE],
            (Shape::Tetrahedron, true) => &[VTK_BEZIER_TETRAHEDRON],
        };
        if !same_shape.contains(&(types[e] as u8)) || types[e].fract() != 0.0 {
            return Err(file(format!(
                "element {e}: cell type {} differs from element 0's ({first}); one shape per file",
                types[e]
            )));
        }
        if offsets[e] != ((e + 1) * per_cell) as f64 {
            return Err(file(format!(
                "element {e}: offset {} (every cell has {per_cell} points, as element 0)",
                offsets[e]
            )));
        }
        // The linear cells have their corners only.
        let linear = matches!(types[e] as u8, VTK_QUAD | VTK_HEXAHEDRON);
        if linear && per_cell != 1 << dim {
            return Err(file(format!(
                "element {e}: cell type {} ({}) has {} points, not {per_cell}; higher orders are VTK_LAGRANGE_{}",
                types[e],
                if dim == 2 { "VTK_QUAD" } else { "VTK_HEXAHEDRON" },
                1 << dim,
                if dim == 2 { "QUADRILATERAL = 70" } else { "HEXAHEDRON = 72" }
            )));
        }
    }
    if conn.values.len() != cells * per_cell {
        return Err(file(format!(
            "connectivity has {} entries, expected {}",
            conn.values.len(),
            cells * per_cell
        )));
    }
    // Our lexicographic node (i, j, k) of cell e ← VTK's point at vtk_point_index; a
    // triangle's node (i, j) at simplex::triangle_index ← VTK's recursive shells.
    let edges = HexEdgeOrder::of_version(grid.version);
    let from_vtk: Vec<usize> = if shape.is_simplex() {
        let ours = if shape == Shape::Triangle {
            simplex::triangle_from_vtk(n)?
        } else {
            simplex::tetra_from_vtk(n)?
        };
        let mut back = vec![0; per_cell];
        for (v, &o) in ours.iter().enumerate() {
            back[o] = v;
        }
        back
    } else {
        (0..per_cell)
            .map(|flat| vtk_point_index(shape, n, flat % m, (flat / m) % m, flat / (m * m), edges))
            .collect()
    };
    let mut order = crate::limits::vec_for(cells * per_cell, "the cells' nodes").map_err(file)?;
    for e in 0..cells {
        for &vtk_point in &from_vtk {
            let c = conn.values[e * per_cell + vtk_point];
            if !(c >= 0.0 && c < grid.points as f64 && c.fract() == 0.0) {
                return Err(file(format!(
                    "element {e}: point index {c} is out of range ({} points)",
                    grid.points
                )));
            }
            order.push(c as usize);
        }
    }
    let mut geometry: Vec<[f64; 3]> =
        order.iter().map(|&p| [points[3 * p], points[3 * p + 1], points[3 * p + 2]]).collect();
    // Fields: one-component point data and cell data, NAME_t<k> grouped into steps.
    let mut grouped: BTreeMap<String, Vec<(usize, &[f64])>> = BTreeMap::new();
    let mut cell_grouped: BTreeMap<String, Vec<(usize, &[f64])>> = BTreeMap::new();
    let step_of = |name: &str| match name.rsplit_once("_t") {
        Some((base, k)) if !base.is_empty() && k.parse::<usize>().is_ok() => {
            (base.to_string(), k.parse().unwrap_or(0))
        }
        _ => (name.to_string(), 0),
    };
    // Rational Bézier cells: weights not all 1 (VTK reads RationalWeights of Bézier cells only).
    let weights = match grid.optional("PointData", "RationalWeights", 1, grid.points)? {
        Some(w) if bezier && order.iter().any(|&p| w[p] != 1.0) => {
            Some(order.iter().map(|&p| w[p]).collect::<Vec<f64>>())
        }
        _ => None,
    };
    if let (Some(w), true) = (&weights, shape.is_simplex()) {
        let k = w.iter().position(|&x| x != 1.0).unwrap_or(0);
        return Err(file(format!(
            "element {}: RationalWeights {} (rational Bézier {} are not drawn; rational quadrilaterals and hexahedra are, and Bézier simplices whose weights are all 1)",
            k / per_cell,
            w[k],
            if shape == Shape::Triangle { "triangles" } else { "tetrahedra" }
        )));
    }
    for a in grid.arrays.iter().filter(|a| a.section == "PointData" && a.name != "RationalWeights") {
        if a.components != 1 {
            continue;
        }
        if a.values.len() != grid.points {
            return Err(file(format!(
                "array {}: {} values for {} points",
                a.name,
                a.values.len(),
                grid.points
            )));
        }
        let (name, step) = step_of(&a.name);
        grouped.entry(name).or_default().push((step, &a.values));
    }
    // Cell data: one value per element, drawn as a piecewise-constant field (every coefficient
    // of the element the cell's value: exact, the bases being partitions of unity).
    for a in grid.arrays.iter().filter(|a| a.section == "CellData" && a.components == 1) {
        if a.values.len() != cells {
            return Err(file(format!("cell array {}: {} values for {cells} cells", a.name, a.values.len())));
        }
        let (name, step) = step_of(&a.name);
        cell_grouped.entry(name).or_default().push((step, &a.values));
    }
    if grouped.is_empty() && cell_grouped.is_empty() {
        return Err(file(no_drawable_field(grid)));
    }
    let mut fields = Vec::new();
    // A cell field named like a point field is told apart by a suffix.
    let taken: Vec<String> = grouped.keys().cloned().collect();
    let point_fields = grouped.into_iter().map(|(name, steps)| (name, steps, false));
    let cell_fields = cell_grouped.into_iter().map(|(name, steps)| {
        let name = if taken.contains(&name) { format!("{name} (cells)") } else { name };
        (name, steps, true)
    });
    for (name, mut steps, per_cell_value) in point_fields.chain(cell_fields) {
        steps.sort_by_key(|s| s.0);
        if steps.iter().enumerate().any(|(k, s)| s.0 != k) {
            return Err(file(format!(
                "field {name:?}: time steps {:?} are not 0, 1, 2, …",
                steps.iter().map(|s| s.0).collect::<Vec<_>>()
            )));
        }
        // One step at the file's `TimeValue` where it has one (VTK's convention); else steps
        // are numbered.
        let times = match (steps.len(), grid.time_value()) {
            (1, Some(t)) => vec![t],
            (n, _) => (0..n).map(|k| k as f64).collect(),
        };
        let coefficients = |v: &[f64]| -> Vec<f64> {
            match per_cell_value {
                false => order.iter().map(|&p| v[p]).collect(),
                true => v.iter().flat_map(|&c| std::iter::repeat_n(c, per_cell)).collect(),
            }
        };
        fields.push(Field { name, times, steps: steps.iter().map(|(_, v)| coefficients(v)).collect() });
    }
    // Bézier simplices: the same polynomial's values at the Lagrange nodes.
    if let (true, Some(simplex_shape)) = (bezier, shape.simplex()) {
        let convert = simplex::FromBernstein::new(simplex_shape, n);
        let mut nodal = Vec::with_capacity(geometry.len());
        for control in geometry.chunks_exact(per_cell) {
            nodal.extend(convert.nodal_points(control));
        }
        geometry = nodal;
        for step in fields.iter_mut().flat_map(|f| f.steps.iter_mut()) {
            *step = step.chunks_exact(per_cell).flat_map(|c| convert.nodal_values(c)).collect();
        }
    }
    let nodes = if bezier && !shape.is_simplex() { NodeSet::Bernstein } else { NodeSet::Equispaced };
    let basis = Basis1d::new(nodes, n)?;
    let mesh =
        SpectralMesh::new(shape, basis.clone(), basis, geometry, fields).map_err(|e| file(e.to_string()))?;
    match weights {
        Some(w) => mesh.with_weights(w).map_err(|e| file(e.to_string())),
        None => Ok(mesh),
    }
}

/// Why a file has nothing to draw: the arrays it has, with their components (only
/// one-component point or cell data is drawn as a field).
fn no_drawable_field(grid: &vtk::UnstructuredGrid) -> String {
    let list = |section: &str| -> String {
        let names: Vec<String> = grid
            .arrays
            .iter()
            .filter(|a| a.section == section && a.name != "RationalWeights")
            .map(|a| format!("{} ({} components)", a.name, a.components))
            .collect();
        if names.is_empty() {
            "none".into()
        } else {
            names.join(", ")
        }
    };
    format!(
        "no field to draw: point data {}; cell data {} — a field is a one-component (scalar) array of point or cell data",
        list("PointData"),
        list("CellData")
    )
}

/// The VTK name of the cell types a user is likeliest to hand the spectral renderer by mistake
/// (simplices, linear and high order), for the refusal.
fn vtk_cell_name(ty: f64) -> Option<&'static str> {
    Some(match ty as i64 {
        5 => "VTK_TRIANGLE",
        10 => "VTK_TETRA",
        22 => "VTK_QUADRATIC_TRIANGLE",
        24 => "VTK_QUADRATIC_TETRA",
        69 => "VTK_LAGRANGE_TRIANGLE",
        71 => "VTK_LAGRANGE_TETRAHEDRON",
        73 => "VTK_LAGRANGE_WEDGE",
        75 => "VTK_BEZIER_CURVE",
        _ => return None,
    })
}

/// Writes `mesh` as Lagrange cells of order max(field order, geometry order) on equispaced
/// nodes — an exact representation of both polynomials — with every field's steps as point
/// data (`NAME`, or `NAME_t0`, `NAME_t1`, … for several steps). Each element has its own points
/// (the data may be discontinuous). Written whole or not at all ([`crate::atomic_file`]).
pub fn write(path: &Path, mesh: &SpectralMesh) -> Result<(), SpectralError> {
    if let Some(weights) = &mesh.weights {
        return write_rational(path, mesh, weights);
    }
    let n = mesh.basis.order.max(mesh.geometry.order);
    let nodes = Basis1d::new(NodeSet::Equispaced, n)?.nodes;
    let m = n + 1;
    let dim = mesh.shape.dim();
    let per_cell = mesh.shape.nodes(n);
    let cells = mesh.elements();
    // Reference points in VTK's order.
    let refs: Vec<[f64; 3]> = if let Some(shape) = mesh.shape.simplex() {
        let vtk = simplex::vtk_nodes(shape, n)?;
        vtk.iter().map(|b| simplex::node_point(shape, n, b)).collect()
    } else {
        let mut refs = vec![[0.0; 3]; per_cell];
        for flat in 0..per_cell {
            let (i, j, k) = (flat % m, (flat / m) % m, flat / (m * m));
            refs[vtk_point_index(mesh.shape, n, i, j, k, HexEdgeOrder::Current)] =
                [nodes[i], nodes[j], if dim == 3 { nodes[k] } else { 0.0 }];
        }
        refs
    };
    let mut points = Vec::with_capacity(3 * cells * per_cell);
    for e in 0..cells {
        for r in &refs {
            let x = match mesh.shape {
                Shape::Quadrilateral | Shape::Triangle => mesh.map(e, r[0], r[1]).0,
                Shape::Hexahedron | Shape::Tetrahedron => mesh.map_hex(e, *r).0,
            };
            points.extend(x);
        }
    }
    let cell_type = match mesh.shape {
        Shape::Quadrilateral => VTK_LAGRANGE_QUADRILATERAL,
        Shape::Hexahedron => VTK_LAGRANGE_HEXAHEDRON,
        Shape::Triangle => VTK_LAGRANGE_TRIANGLE,
        Shape::Tetrahedron => VTK_LAGRANGE_TETRAHEDRON,
    };
    let mut arrays = grid_arrays(points, cells, per_cell, cell_type);
    for (fi, f) in mesh.fields.iter().enumerate() {
        for step in 0..f.steps.len() {
            let mut v = Vec::with_capacity(cells * per_cell);
            for e in 0..cells {
                for r in &refs {
                    v.push(match mesh.shape {
                        Shape::Quadrilateral | Shape::Triangle => mesh.value(fi, step, e, r[0], r[1]),
                        Shape::Hexahedron | Shape::Tetrahedron => mesh.value_hex(fi, step, e, *r),
                    });
                }
            }
            let name = if f.steps.len() == 1 { f.name.clone() } else { format!("{}_t{step}", f.name) };
            arrays.push(OutArray { section: "PointData", name, components: 1, values: Values::F64(v) });
        }
    }
    vtk::write(
        path,
        "galerkin spectral elements (seed 002): VTK Lagrange cells on equispaced nodes, one field per point-data array",
        cells * per_cell,
        cells,
        &arrays,
    )?;
    Ok(())
}

/// The points and cells of `cells` cells of `per_cell` points each, every cell with its own
/// points in order, all of type `cell_type`.
fn grid_arrays(points: Vec<f64>, cells: usize, per_cell: usize, cell_type: u8) -> Vec<OutArray> {
    vec![
        OutArray { section: "Points", name: "Points".into(), components: 3, values: Values::F64(points) },
        OutArray {
            section: "Cells",
            name: "connectivity".into(),
            components: 1,
            values: Values::I64((0..(cells * per_cell) as i64).collect()),
        },
        OutArray {
            section: "Cells",
            name: "offsets".into(),
            components: 1,
            values: Values::I64((1..=cells as i64).map(|c| c * per_cell as i64).collect()),
        },
        OutArray {
            section: "Cells",
            name: "types".into(),
            components: 1,
            values: Values::U8(vec![cell_type; cells]),
        },
    ]
}

/// [`fn@write`] for a rational mesh (no polynomial cell represents it): VTK Bézier cells with
/// its control points, weights (`RationalWeights`) and field coefficients as they are.
fn write_rational(path: &Path, mesh: &SpectralMesh, weights: &[f64]) -> Result<(), SpectralError> {
    let n = mesh.geometry.order;
    let m = n + 1;
    let per_cell = mesh.points_per_element();
    let cells = mesh.elements();
    // Our lexicographic node of each of VTK's points.
    let mut ours = vec![0; per_cell];
    for flat in 0..per_cell {
        let (i, j, k) = (flat % m, (flat / m) % m, flat / (m * m));
        ours[vtk_point_index(mesh.shape, n, i, j, k, HexEdgeOrder::Current)] = flat;
    }
    let in_vtk_order = |per_node: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..cells)
            .flat_map(|e| ours.iter().map(move |&k| (e, k)))
            .map(|(e, k)| per_node(e * per_cell + k))
            .collect()
    };
    let points = (0..cells)
        .flat_map(|e| ours.iter().map(move |&k| e * per_cell + k))
        .flat_map(|node| mesh.points[node])
        .collect();
    let cell_type = match mesh.shape {
        Shape::Quadrilateral => VTK_BEZIER_QUADRILATERAL,
        Shape::Hexahedron => VTK_BEZIER_HEXAHEDRON,
        Shape::Triangle | Shape::Tetrahedron => {
            return Err(SpectralError::Missing("rational simplices are not written (none are read)".into()))
        }
    };
    let mut arrays = grid_arrays(points, cells, per_cell, cell_type);
    arrays.push(OutArray {
        section: "PointData",
        name: "RationalWeights".into(),
        components: 1,
        values: Values::F64(in_vtk_order(&|node| weights[node])),
    });
    for f in &mesh.fields {
        for (step, v) in f.steps.iter().enumerate() {
            let name = if f.steps.len() == 1 { f.name.clone() } else { format!("{}_t{step}", f.name) };
            arrays.push(OutArray {
                section: "PointData",
                name,
                components: 1,
                values: Values::F64(in_vtk_order(&|node| v[node])),
            });
        }
    }
    vtk::write(
        path,
        "galerkin spectral elements (seed 002): VTK rational Bézier cells, one field per point-data array",
        cells * per_cell,
        cells,
        &arrays,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vtk_point_order_is_a_permutation_with_corners_first() {
        for shape in [Shape::Quadrilateral, Shape::Hexahedron] {
            for n in 1..=6usize {
                let m = n + 1;
                let count = m.pow(shape.dim());
                let mut seen = vec![false; count];
                for flat in 0..count {
                    let (i, j, k) = (flat % m, (flat / m) % m, flat / (m * m));
                    let p = vtk_point_index(shape, n, i, j, k, HexEdgeOrder::Current);
                    assert!(!seen[p], "{shape:?} order {n}: {p} twice");
                    seen[p] = true;
                }
                assert_eq!(vtk_point_index(shape, n, n, n, 0, HexEdgeOrder::Current), 2);
                assert_eq!(vtk_point_index(shape, n, 0, n, 0, HexEdgeOrder::Current), 3);
            }
        }
        // VTK's order-2 quadrilateral: corners, edge midpoints (bottom, right, top, left), centre.
        let q = |i, j| vtk_point_index(Shape::Quadrilateral, 2, i, j, 0, HexEdgeOrder::Current);
        assert_eq!([q(1, 0), q(2, 1), q(1, 2), q(0, 1), q(1, 1)], [4, 5, 6, 7, 8]);
        // The order-2 hexahedron's vertical edges 16–19 join corners 0–4, 1–5, 2–6, 3–7 (VTK
        // 9.7's vtkLagrangeHexahedron::PointIndexFromIJK gives 16, 17, 19, 18 for the nodes
        // above corners 0, 1, 3, 2), and 0–4, 1–5, 3–7, 2–6 in files before version 2.2.
        let h = |i, j, k, e| vtk_point_index(Shape::Hexahedron, 2, i, j, k, e);
        let vertical = |e| [h(0, 0, 1, e), h(2, 0, 1, e), h(0, 2, 1, e), h(2, 2, 1, e)];
        assert_eq!(vertical(HexEdgeOrder::Current), [16, 17, 19, 18]);
        assert_eq!(vertical(HexEdgeOrder::Legacy), [16, 17, 18, 19]);
        assert_eq!(h(1, 1, 1, HexEdgeOrder::Current), 26);
        // Order 3, against the same VTK function: face and body nodes.
        let h3 = |i, j, k| vtk_point_index(Shape::Hexahedron, 3, i, j, k, HexEdgeOrder::Current);
        assert_eq!(
            [h3(1, 0, 0), h3(0, 1, 1), h3(1, 1, 0), h3(1, 0, 1), h3(0, 1, 2), h3(1, 2, 1)],
            [8, 32, 48, 40, 34, 58]
        );
    }
}
