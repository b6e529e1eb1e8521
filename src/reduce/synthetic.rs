//! Synthetic inputs of realistic shape for the reduction core's tests and benchmarks: the
//! fluid *volume tensor* (§5, §6.2; built by [`crate::mesh::volume`], the same code the fluid
//! uses) of a plain tetrahedral grid, sized by cell count.
//!
//! The grid is the Freudenthal (Kuhn) subdivision of a box of unit cubes into six tetrahedra
//! each. For cell `c` with vertices `v₀…v₃`, `6·vol(c) = det[v₁ − v₀, v₂ − v₀, v₃ − v₀]` is a
//! cubic in the 12 vertex coordinates with 24 monomials `±x_i y_j z_k` (i, j, k distinct
//! vertices). The volume tensor `V[p, u, g, g, g]` maps velocity `u` to momentum `p = vol·u`
//! cell by cell: the result and velocity axes are diagonal in the cell, the three geometry
//! axes symmetric — stored once per monomial with its indices sorted, coefficient
//! `±1/(6·6)` (the 6 permutations add up to the monomial, and `vol = det/6`).

use crate::tensor::SparseTensor;

/// A Freudenthal tetrahedral grid: vertex positions and, per cell, its four vertex ids.
#[derive(Clone, Debug)]
pub struct TetGrid {
    /// Vertex positions.
    pub vertices: Vec<[f64; 3]>,
    /// Cells (positively oriented).
    pub cells: Vec<[u32; 4]>,
}

impl TetGrid {
    /// At least `cells` tetrahedra: the smallest near-cubic box of unit cubes holding them,
    /// truncated to exactly `cells` (cells are numbered cube by cube, so truncation keeps
    /// locality) — [`crate::mesh::kuhn::kuhn_tets_with_cells`].
    pub fn with_cells(cells: usize) -> Self {
        let mesh = crate::mesh::kuhn::kuhn_tets_with_cells(cells).expect("a positive number of unit cubes");
        let vertices = (0..mesh.vertex_count()).map(|v| mesh.point(v)).collect();
        let cells = mesh.cells().chunks(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        Self { vertices, cells }
    }

    /// Vertex coordinates flattened: `g[3v + k]` is coordinate `k` of vertex `v`.
    pub fn coordinates(&self) -> Vec<f64> {
        self.vertices.iter().flatten().copied().collect()
    }
}

/// `det[v₁ − v₀, v₂ − v₀, v₃ − v₀] = 6·vol`.
pub fn signed_volume6(vertices: &[[f64; 3]], t: &[u32; 4]) -> f64 {
    let p: Vec<[f64; 3]> = t.iter().map(|&v| vertices[v as usize]).collect();
    6.0 * crate::mesh::geometry::signed_volume(3, &p)
}

/// The volume tensor of `grid` ([`crate::mesh::volume::volume_tensor`]): shape
/// `[3·cells, 3·cells, 3·vertices, 3·vertices, 3·vertices]`, axes 2–4 symmetric, so that
/// `V ⊗₁ u ⊗₂ g ⊗₃ g ⊗₄ g` is `vol(c)·u` in every cell `c`.
pub fn volume_tensor(grid: &TetGrid) -> SparseTensor {
    let cells: Vec<u32> = grid.cells.iter().flatten().copied().collect();
    let mesh =
        crate::mesh::SimplexMesh::new(3, grid.coordinates(), cells).expect("a Kuhn grid is a valid mesh");
    crate::mesh::volume::volume_tensor(&mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_volume_tensor_gives_cell_volumes() {
        let grid = TetGrid::with_cells(40);
        assert_eq!(grid.cells.len(), 40);
        let v = volume_tensor(&grid);
        let g = grid.coordinates();
        let u: Vec<f64> = (0..3 * 40).map(|i| 1.0 + i as f64).collect();
        let p = v.contract_axes("V", &[(1, &u), (2, &g), (3, &g), (4, &g)]).unwrap();
        for (c, t) in grid.cells.iter().enumerate() {
            let vol = signed_volume6(&grid.vertices, t) / 6.0;
            assert!((vol - 1.0 / 6.0).abs() < 1e-15, "Kuhn tetrahedra of unit cubes have volume 1/6");
            for k in 0..3 {
                let want = vol * u[3 * c + k];
                assert!((p.data()[3 * c + k] - want).abs() < 1e-12, "cell {c} component {k}");
            }
        }
        // Moving one vertex changes the volumes of its cells only, as the cubic says.
        let mut moved = grid.clone();
        moved.vertices[grid.cells[0][3] as usize][2] += 0.5;
        let p2 = v
            .contract_axes(
                "V",
                &[(1, &u), (2, &moved.coordinates()), (3, &moved.coordinates()), (4, &moved.coordinates())],
            )
            .unwrap();
        let vol0 = signed_volume6(&moved.vertices, &moved.cells[0]) / 6.0;
        assert!((p2.data()[0] - vol0 * u[0]).abs() < 1e-12);
        assert!((vol0 - 1.0 / 6.0).abs() > 1e-3);
    }
}
