//! High-order triangles and tetrahedra read from VTK files (`VTK_LAGRANGE_TRIANGLE` = 69,
//! `VTK_LAGRANGE_TETRAHEDRON` = 71, and the polynomial Bézier ones, `VTK_BEZIER_TRIANGLE` = 76,
//! `VTK_BEZIER_TETRAHEDRON` = 78), with the f64 reference evaluation the per-pixel renderer
//! of simplices is to be tested against: the geometry map `x(r) = Σ_b X_b L_b(r)` and its
//! Jacobian, each point field `f(r) = Σ_b F_b L_b(r)`, and the inverse map by Newton's method
//! (the basis and node order: [`super::simplex`]); for Bézier cells `L_b` is the Bernstein
//! polynomial `B_b` of the control point (no conversion, unlike the renderer's loader).
//! Checked against VTK's own evaluation (`EvaluateLocation`) of files VTK wrote,
//! `tests/spectral_simplex.rs` and `tests/spectral_bezier_simplices.rs`.

use std::path::Path;

use super::error::SpectralError;
use super::mesh::{Field, NEWTON_ITERATIONS};
use super::simplex::{basis, bernstein_basis, vtk_nodes, SimplexShape, MAX_SIMPLEX_ORDER};
use super::vtu::{
    VTK_BEZIER_TETRAHEDRON, VTK_BEZIER_TRIANGLE, VTK_LAGRANGE_TETRAHEDRON, VTK_LAGRANGE_TRIANGLE,
};

/// Lagrange simplices of one shape and order with their point fields (one step each).
#[derive(Clone, Debug, PartialEq)]
pub struct SimplexElements {
    /// The shape of every element.
    pub shape: SimplexShape,
    /// The order of every element (geometry and fields).
    pub order: usize,
    /// The nodes' barycentric multi-indices, in VTK's point order.
    pub nodes: Vec<[usize; 4]>,
    /// Bézier cells: the points and values are Bernstein coefficients.
    pub bernstein: bool,
    /// Geometry nodes: elements × nodes, element e's node i at `e · nodes + i`.
    pub points: Vec<[f64; 3]>,
    /// One-component point fields, laid out as the points.
    pub fields: Vec<Field>,
}

impl SimplexElements {
    /// Reads a `.vtu` of Lagrange triangles or tetrahedra (one shape and order per file, every
    /// one-component point array a field). Errors name the file and the element or array.
    pub fn read(path: &Path) -> Result<Self, SpectralError> {
        let file = |detail: String| SpectralError::File { path: path.to_path_buf(), detail };
        let grid = crate::vtk::read(path)?;
        let cells = grid.cells;
        if cells == 0 {
            return Err(file("no cells".into()));
        }
        let points = grid.require("Points", "Points", 3, grid.points)?;
        let types = grid.require("Cells", "types", 1, cells)?;
        let offsets = grid.require("Cells", "offsets", 1, cells)?;
        let conn = grid
            .array("Cells", "connectivity")
            .ok_or_else(|| file("no Cells array \"connectivity\"".into()))?;
        let (shape, bernstein) = match types[0] {
            t if t == f64::from(VTK_LAGRANGE_TRIANGLE) => (SimplexShape::Triangle, false),
            t if t == f64::from(VTK_LAGRANGE_TETRAHEDRON) => (SimplexShape::Tetrahedron, false),
            t if t == f64::from(VTK_BEZIER_TRIANGLE) => (SimplexShape::Triangle, true),
            t if t == f64::from(VTK_BEZIER_TETRAHEDRON) => (SimplexShape::Tetrahedron, true),
            t => {
                return Err(file(format!(
                    "element 0: cell type {t} (high-order simplices are VTK_LAGRANGE_TRIANGLE = 69, VTK_LAGRANGE_TETRAHEDRON = 71, VTK_BEZIER_TRIANGLE = 76 and VTK_BEZIER_TETRAHEDRON = 78)"
                )))
            }
        };
        let per_cell = offsets[0] as usize;
        let order = (1..=MAX_SIMPLEX_ORDER).find(|&n| shape.node_count(n) == per_cell).ok_or_else(|| {
            file(format!(
                "element 0: {per_cell} points is no Lagrange {shape:?} of order 1..={MAX_SIMPLEX_ORDER}"
            ))
        })?;
        for e in 0..cells {
            if types[e] != types[0] {
                return Err(file(format!(
                    "element {e}: cell type {} differs from element 0's ({}); one shape per file",
                    types[e], types[0]
                )));
            }
            if offsets[e] != ((e + 1) * per_cell) as f64 {
                return Err(file(format!(
                    "element {e}: offset {} (every cell has {per_cell} points, as element 0)",
                    offsets[e]
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
        let mut index = crate::limits::vec_for(cells * per_cell, "the cells' nodes").map_err(file)?;
        for (k, &c) in conn.values.iter().enumerate() {
            if !(c >= 0.0 && c < grid.points as f64 && c.fract() == 0.0) {
                return Err(file(format!(
                    "element {}: point index {c} is out of range ({} points)",
                    k / per_cell,
                    grid.points
                )));
            }
            index.push(c as usize);
        }
        let geometry: Vec<[f64; 3]> =
            index.iter().map(|&p| [points[3 * p], points[3 * p + 1], points[3 * p + 2]]).collect();
        if let Some(k) = geometry.iter().position(|x| x.iter().any(|v| !v.is_finite())) {
            return Err(file(format!("element {}: point {} is not finite", k / per_cell, k % per_cell)));
        }
        if let Some(w) = grid.optional("PointData", "RationalWeights", 1, grid.points)? {
            if let (true, Some(k)) = (bernstein, index.iter().position(|&p| w[p] != 1.0)) {
                return Err(file(format!(
                    "element {}: RationalWeights {} (rational Bézier simplices are not read)",
                    k / per_cell,
                    w[index[k]]
                )));
            }
        }
        let mut fields = Vec::new();
        for a in grid
            .arrays
            .iter()
            .filter(|a| a.section == "PointData" && a.components == 1 && a.name != "RationalWeights")
        {
            let all = grid.require("PointData", &a.name, 1, grid.points)?;
            let values: Vec<f64> = index.iter().map(|&p| all[p]).collect();
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                return Err(file(format!(
                    "array {}: element {}'s value {} is not finite",
                    a.name,
                    k / per_cell,
                    k % per_cell
                )));
            }
            let time = grid.time_value().unwrap_or(0.0);
            fields.push(Field { name: a.name.clone(), times: vec![time], steps: vec![values] });
        }
        Ok(Self { shape, order, nodes: vtk_nodes(shape, order)?, bernstein, points: geometry, fields })
    }

    /// Elements.
    pub fn len(&self) -> usize {
        self.points.len() / self.nodes.len().max(1)
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Every node's basis function at `r` with its gradient: Lagrange, or Bernstein for Bézier
    /// cells.
    fn basis(&self, r: &[f64; 3]) -> Vec<(f64, [f64; 3])> {
        match self.bernstein {
            false => basis(self.shape, self.order, &self.nodes, r),
            true => bernstein_basis(self.shape, self.order, &self.nodes, r),
        }
    }

    /// `x(r)` of element `e` and its Jacobian's columns `∂x/∂r_a` (d of them used).
    pub fn map(&self, e: usize, r: &[f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        let m = self.nodes.len();
        let (mut x, mut jac) = ([0.0; 3], [[0.0; 3]; 3]);
        for (i, (l, g)) in self.basis(r).into_iter().enumerate() {
            let p = self.points[e * m + i];
            for c in 0..3 {
                x[c] += l * p[c];
                for a in 0..3 {
                    jac[a][c] += g[a] * p[c];
                }
            }
        }
        (x, jac)
    }

    /// Field `field`'s value on element `e` at `r`.
    pub fn value(&self, e: usize, field: usize, r: &[f64; 3]) -> f64 {
        let m = self.nodes.len();
        let coefficients = &self.fields[field].steps[0][e * m..(e + 1) * m];
        self.basis(r).iter().zip(coefficients).map(|((l, _), f)| l * f).sum()
    }

    /// The reference point of element `e` that maps to `x` (planar triangles: its x and y),
    /// by Newton's method from the centroid with steps at most half the element long; `None`
    /// when it does not converge to 1e-13 of the element's size.
    pub fn inverse(&self, e: usize, x: &[f64; 3]) -> Option<[f64; 3]> {
        let d = self.shape.dim();
        let m = self.nodes.len();
        let (lo, hi) = super::mesh::bounds_of(&self.points[e * m..(e + 1) * m]);
        let size = (0..3).map(|c| hi[c] - lo[c]).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
        let mut r = [1.0 / (d + 1) as f64; 3];
        if d == 2 {
            r[2] = 0.0;
        }
        for _ in 0..NEWTON_ITERATIONS * 2 {
            let (y, jac) = self.map(e, &r);
            let mut res = [0.0; 3];
            for c in 0..d {
                res[c] = x[c] - y[c];
            }
            if res.iter().map(|v| v * v).sum::<f64>().sqrt() <= 1e-13 * size {
                return Some(r);
            }
            // Solve J s = res (J[c][a] = ∂x_c/∂r_a), the step at most half the element long.
            let mut jm = [[0.0; 3]; 3];
            for (c, row) in jm.iter_mut().enumerate().take(d) {
                for (k, v) in row.iter_mut().enumerate().take(d) {
                    *v = jac[k][c];
                }
            }
            let step = super::mesh::damped(crate::mesh::untangle::solve_small(d, jm, res)?);
            for k in 0..d {
                r[k] += step[k];
            }
        }
        None
    }
}
