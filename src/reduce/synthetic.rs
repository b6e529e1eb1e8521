//! Synthetic inputs of realistic shape for tests and benchmarks, until the fluid module
//! supplies its own: the fluid *volume tensor* of a tetrahedral grid (§5, §6.2).
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

/// The six Kuhn tetrahedra of a cube, as corner indices (bit 0 = x, bit 1 = y, bit 2 = z),
/// each a path 0 → … → 7 along one permutation of the axes.
const KUHN: [[usize; 4]; 6] =
    [[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]];

impl TetGrid {
    /// At least `cells` tetrahedra: the smallest near-cubic box of unit cubes holding them,
    /// truncated to exactly `cells` (cells are numbered cube by cube, so truncation keeps
    /// locality).
    pub fn with_cells(cells: usize) -> Self {
        let cubes = cells.div_ceil(6).max(1);
        let mut n = (cubes as f64).cbrt().floor().max(1.0) as usize;
        while n * n * n < cubes {
            n += 1;
        }
        let (nx, ny) = (n, n);
        let nz = cubes.div_ceil(nx * ny);
        let vid = |x: usize, y: usize, z: usize| (z * (ny + 1) + y) * (nx + 1) + x;
        let mut vertices = Vec::with_capacity((nx + 1) * (ny + 1) * (nz + 1));
        for z in 0..=nz {
            for y in 0..=ny {
                for x in 0..=nx {
                    vertices.push([x as f64, y as f64, z as f64]);
                }
            }
        }
        let mut out = Vec::with_capacity(cells);
        'cubes: for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    for tet in KUHN {
                        if out.len() == cells {
                            break 'cubes;
                        }
                        let corner =
                            |c: usize| vid(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1)) as u32;
                        let mut t = tet.map(corner);
                        if signed_volume6(&vertices, &t) < 0.0 {
                            t.swap(2, 3);
                        }
                        out.push(t);
                    }
                }
            }
        }
        Self { vertices, cells: out }
    }

    /// Vertex coordinates flattened: `g[3v + k]` is coordinate `k` of vertex `v`.
    pub fn coordinates(&self) -> Vec<f64> {
        self.vertices.iter().flatten().copied().collect()
    }
}

/// `det[v₁ − v₀, v₂ − v₀, v₃ − v₀] = 6·vol`.
pub fn signed_volume6(vertices: &[[f64; 3]], t: &[u32; 4]) -> f64 {
    let p = |i: usize| vertices[t[i] as usize];
    let d = |i: usize, k: usize| p(i)[k] - p(0)[k];
    d(1, 0) * (d(2, 1) * d(3, 2) - d(2, 2) * d(3, 1)) - d(1, 1) * (d(2, 0) * d(3, 2) - d(2, 2) * d(3, 0))
        + d(1, 2) * (d(2, 0) * d(3, 1) - d(2, 1) * d(3, 0))
}

/// The volume tensor of `grid` (see the module docs): shape
/// `[3·cells, 3·cells, 3·vertices, 3·vertices, 3·vertices]`, axes 2–4 symmetric, so that
/// `V ⊗₁ u ⊗₂ g ⊗₃ g ⊗₄ g` is `vol(c)·u` in every cell `c`.
pub fn volume_tensor(grid: &TetGrid) -> SparseTensor {
    let (nc, nv) = (grid.cells.len(), grid.vertices.len());
    let mut v = SparseTensor::new(&[3 * nc, 3 * nc, 3 * nv, 3 * nv, 3 * nv])
        .with_symmetric_axes(&[2, 3, 4])
        .expect("three equal geometry axes");
    // det[v1 − v0, v2 − v0, v3 − v0] expanded: Σ over distinct (a, b, c) in 0..4 of
    // sign · x_a y_b z_c (see `permutation_sign`).
    let mut monomials: Vec<(f64, [usize; 3])> = Vec::new();
    for a in 0..4 {
        for b in 0..4 {
            for c in 0..4 {
                if a == b || b == c || a == c {
                    continue;
                }
                let d = 6 - a - b - c; // the vertex left out
                monomials.push((permutation_sign([a, b, c, d]), [a, b, c]));
            }
        }
    }
    for (cell, t) in grid.cells.iter().enumerate() {
        for k in 0..3 {
            let dof = 3 * cell + k;
            for &(sign, [a, b, c]) in &monomials {
                let g = [3 * t[a] as usize, 3 * t[b] as usize + 1, 3 * t[c] as usize + 2];
                v.push(&[dof, dof, g[0], g[1], g[2]], sign / 36.0);
            }
        }
    }
    v
}

/// Coefficient of `x_a y_b z_c` (with `d` the vertex left out, `perm = [a, b, c, d]`) in the
/// determinant of the 4×4 matrix with rows `[1, x_i, y_i, z_i]`, which is Σ_σ sign(σ)·x_σ₁ y_σ₂ z_σ₃.
fn permutation_sign(perm: [usize; 4]) -> f64 {
    // det[[1, x0, y0, z0], …, [1, x3, y3, z3]] = Σ_σ sign(σ) Π_i M[σ(i)][i] with column 0 the
    // ones: the monomial x_a y_b z_c comes with σ = (d, a, b, c).
    let sigma = [perm[3], perm[0], perm[1], perm[2]];
    let mut inversions = 0;
    for i in 0..4 {
        for j in i + 1..4 {
            if sigma[i] > sigma[j] {
                inversions += 1;
            }
        }
    }
    // det[v1 − v0, v2 − v0, v3 − v0] = det[[1, v0], [1, v1], [1, v2], [1, v3]] (subtract the
    // first row from the others).
    if inversions % 2 == 0 {
        1.0
    } else {
        -1.0
    }
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
