//! Untangling and smoothing with the boundary frozen (seed 000 §6.1: after stiffened
//! Laplacian deformation "we improve the quality of the mesh by running Stellar, which we
//! modified to leave surface vertices unchanged"). Stellar also changes the topology; the
//! seed's meshes must keep theirs, so this moves free vertices only.
//!
//! Each cell's volume ratio `r_c = V_c(g) / V_c(g₀)` against the base mesh measures how far
//! the deformation squeezed it (negative: inverted). A free vertex v of a cell with
//! `r_c < t` moves to reduce `Σ_{c ∋ v} max(0, t − r_c)²`; since a simplex's volume is
//! affine in any one of its vertices (`∂V/∂x_v = −n_v / d`, the outward area normal of the
//! opposite face), that sum is a convex piecewise quadratic of v's position, and one
//! Gauss–Newton step `s = (Σ a aᵀ + λI)⁻¹ Σ (t − r_c) a_c` (`a_c = ∂r_c/∂x_v`, the sums over
//! the cells below t) minimises its active part; the step is halved until the star's sum
//! decreases and no cell of the star that was positive becomes non-positive. Sweeps repeat
//! over the vertices of the cells still below t (Gauss–Seidel), so squeezing spreads out
//! from the worst cells into their neighbours, and inverted cells are pulled positive
//! (the same objective untangles: it is defined for negative ratios too).

use super::geometry::{face_area_normal, signed_volume};
use super::{Point, SimplexMesh};

/// Vertex-to-cell incidence and which vertices may move.
#[derive(Clone, Debug)]
pub struct Smoother {
    star_start: Vec<usize>,
    star: Vec<(u32, u8)>,
    free: Vec<bool>,
}

impl Smoother {
    /// Prepares `mesh`; `free[v]` says whether vertex v may move (boundary vertices frozen).
    pub fn new(mesh: &SimplexMesh, free: Vec<bool>) -> Self {
        let n = mesh.vertex_count();
        let mut count = vec![0usize; n + 1];
        for &v in mesh.cells() {
            count[v as usize + 1] += 1;
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let mut fill = count.clone();
        let mut star = vec![(0u32, 0u8); mesh.cells().len()];
        let k = mesh.dim() + 1;
        for (c, cell) in mesh.cells().chunks_exact(k).enumerate() {
            for (l, &v) in cell.iter().enumerate() {
                star[fill[v as usize]] = (c as u32, l as u8);
                fill[v as usize] += 1;
            }
        }
        Self { star_start: count, star, free }
    }

    /// Moves free vertices of `g` (geometry of `mesh`'s topology; `base_volumes` the base
    /// mesh's cell volumes; `ratios` every cell's volume ratio at `g`, kept up to date) until
    /// every cell's volume ratio is at least `target` or `sweeps` sweeps have passed; returns
    /// the smallest ratio reached.
    pub fn improve(
        &self,
        mesh: &SimplexMesh,
        base_volumes: &[f64],
        g: &mut [f64],
        ratios: &mut [f64],
        target: f64,
        sweeps: usize,
    ) -> f64 {
        // The cells below target; after a sweep only the stars of the moved vertices can have
        // changed, so the next sweep's list is found among them.
        let mut low: Vec<u32> =
            (0..mesh.cell_count() as u32).filter(|&c| ratios[c as usize] < target).collect();
        for _ in 0..sweeps {
            let mut active: Vec<u32> = Vec::new();
            for &c in &low {
                active.extend(mesh.cell(c as usize).iter().filter(|&&v| self.free[v as usize]));
            }
            if active.is_empty() {
                break;
            }
            active.sort_unstable();
            active.dedup();
            for &v in &active {
                self.relax(mesh, base_volumes, g, ratios, v as usize, target);
            }
            low = active
                .iter()
                .flat_map(|&v| &self.star[self.star_start[v as usize]..self.star_start[v as usize + 1]])
                .map(|&(c, _)| c)
                .filter(|&c| ratios[c as usize] < target)
                .collect();
            low.sort_unstable();
            low.dedup();
        }
        ratios.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// One Gauss–Newton step with halving for vertex `v` (see the module docs).
    fn relax(
        &self,
        mesh: &SimplexMesh,
        base_volumes: &[f64],
        g: &mut [f64],
        ratios: &mut [f64],
        v: usize,
        t: f64,
    ) {
        let d = mesh.dim();
        let star = &self.star[self.star_start[v]..self.star_start[v + 1]];
        let penalty = |rs: &[f64]| rs.iter().map(|r| (t - r).max(0.0).powi(2)).sum::<f64>();
        let mut trial: Vec<f64> = star.iter().map(|&(c, _)| ratios[c as usize]).collect();
        let before = penalty(&trial);
        // Gauss–Newton normal equations over the star's cells below t.
        let mut h = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        for &(c, l) in star {
            let r = ratios[c as usize];
            if r >= t {
                continue;
            }
            let n = face_area_normal(d, &corners(mesh, g, c as usize)[..=d], l as usize);
            let a: [f64; 3] =
                std::array::from_fn(
                    |k| if k < d { -n[k] / d as f64 / base_volumes[c as usize] } else { 0.0 },
                );
            for i in 0..d {
                b[i] += (t - r) * a[i];
                for j in 0..d {
                    h[i][j] += a[i] * a[j];
                }
            }
        }
        let trace: f64 = (0..d).map(|i| h[i][i]).sum();
        if trace <= 0.0 || trace.is_nan() {
            return;
        }
        for i in 0..d {
            h[i][i] += 1e-6 * trace;
        }
        let Some(step) = solve_small(d, h, b) else { return };
        let mut old = [0.0; 3];
        old[..d].copy_from_slice(&g[d * v..d * v + d]);
        let mut scale = 1.0;
        for _ in 0..12 {
            for k in 0..d {
                g[d * v + k] = old[k] + scale * step[k];
            }
            for (r, &(c, _)) in trial.iter_mut().zip(star) {
                *r = signed_volume(d, &corners(mesh, g, c as usize)[..=d]) / base_volumes[c as usize];
            }
            let keeps_valid =
                star.iter().zip(&trial).all(|(&(c, _), &r)| ratios[c as usize] <= 0.0 || r > 0.0);
            if keeps_valid && penalty(&trial) < before {
                for (&(c, _), &r) in star.iter().zip(&trial) {
                    ratios[c as usize] = r;
                }
                return;
            }
            scale *= 0.5;
        }
        g[d * v..d * v + d].copy_from_slice(&old[..d]);
    }
}

/// The corners of cell `c` at geometry `g` (on the stack; unused ones zero).
fn corners(mesh: &SimplexMesh, g: &[f64], c: usize) -> [Point; 4] {
    let d = mesh.dim();
    let mut p = [[0.0; 3]; 4];
    for (i, &v) in mesh.cell(c).iter().enumerate() {
        p[i][..d].copy_from_slice(&g[d * v as usize..d * v as usize + d]);
    }
    p
}

/// Solves the d×d system (d ≤ 3) by Gaussian elimination with partial pivoting (`None` when
/// singular).
pub(crate) fn solve_small(d: usize, mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..d {
        let pivot = (col..d).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..d {
            let f = a[row][col] / a[col][col];
            for k in col..d {
                a[row][k] -= f * a[col][k];
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..d).rev() {
        let s: f64 = (row + 1..d).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::kuhn::kuhn_box;

    #[test]
    fn a_tangled_interior_is_untangled_with_the_boundary_frozen() {
        // A 4×4 Kuhn square; its interior vertices are pushed far right, inverting cells.
        let mesh = kuhn_box(2, [4, 4, 0], [1.0, 1.0, 0.0]).expect("box");
        let n = mesh.vertex_count();
        let on_boundary = |v: usize| {
            let p = mesh.point(v);
            p.iter().take(2).any(|&x| x.abs() < 1e-12 || (x - 1.0).abs() < 1e-12)
        };
        let free: Vec<bool> = (0..n).map(|v| !on_boundary(v)).collect();
        let mut g = mesh.g().to_vec();
        for v in 0..n {
            if free[v] {
                g[2 * v] += 0.4;
            }
        }
        let base = mesh.volumes();
        let before = mesh.volumes_at(&g).iter().zip(&base).map(|(a, b)| a / b).fold(f64::INFINITY, f64::min);
        assert!(before < 0.0, "the test must start tangled: {before}");
        let smoother = Smoother::new(&mesh, free.clone());
        let mut ratios: Vec<f64> = mesh.volumes_at(&g).iter().zip(&base).map(|(v, v0)| v / v0).collect();
        let after = smoother.improve(&mesh, &base, &mut g, &mut ratios, 0.3, 50);
        let recomputed =
            mesh.volumes_at(&g).iter().zip(&base).map(|(v, v0)| v / v0).fold(f64::INFINITY, f64::min);
        assert!(
            (recomputed - after).abs() < 1e-12,
            "the kept ratios are the geometry's: {after} vs {recomputed}"
        );
        // Each Gauss–Newton step lands its active cells on the target up to the
        // regularisation and the neighbours it moves: within 1 % after 50 sweeps.
        assert!(after >= 0.99 * 0.3, "smallest ratio after untangling {after}");
        for v in (0..n).filter(|&v| !free[v]) {
            assert_eq!([g[2 * v], g[2 * v + 1]], [mesh.g()[2 * v], mesh.g()[2 * v + 1]], "vertex {v} moved");
        }
        // The area is the square's whatever the interior does.
        let area: f64 = mesh.volumes_at(&g).iter().sum();
        assert!((area - 1.0).abs() < 1e-12);
    }
}
