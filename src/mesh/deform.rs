//! Harmonic (Laplacian) deformation of a mesh's interior from its boundary motion (seed 000
//! §6.1): the displacement d of the free vertices solves `L_FF d_F = −L_FB d_B`, with L the
//! cell-weighted graph Laplacian of the mesh edges. Its pattern and symbolic Cholesky
//! factorisation are computed once and reused for every frame.
//! Cells the solve squeezed below [`SMOOTH_BELOW`] of their base volume (or inverted) are
//! untangled and smoothed with the prescribed vertices frozen ([`super::untangle`], the
//! seed's modified Stellar without topology changes); if a cell is still inverted (or nearly
//! flat: at most [`FLAT_RATIO`] of its base volume), the cells
//! the solve squeezed get stiffer (their weight grows as `(vol₀ / vol)²`, clamped: the seed's
//! "increase the weights around inverted elements") and the solve and smoothing repeat. The
//! cheap repair comes first because a changed weight costs a numerical refactorisation, and
//! the weights are kept for the following frames (stiffening only grows), so a periodic
//! motion stops refactorising after its first period — at the price that a frame's interior
//! depends on which frames were deformed before it. A frame that still has an inverted cell
//! is refused, naming the frame and the cell.

use crate::tensor::{Factorisation, SparseSymmetricSolver, SymmetricPattern};

use super::{MeshError, SimplexMesh};

/// Stiffening rounds per frame (each a harmonic solve and a smoothing).
const STIFFEN_ROUNDS: usize = 8;

/// Volume ratio below which a frame's free vertices are smoothed ([`super::untangle`]).
pub const SMOOTH_BELOW: f64 = 0.2;

/// The ratio the smoothing raises squeezed cells to.
pub const SMOOTH_TARGET: f64 = 0.3;

/// A frame whose smallest volume ratio after smoothing is at or below this (valid but nearly
/// flat: costly for the fluid's stability bound and its projection) is stiffened and solved
/// again like a tangled one; after the stiffening rounds (8) the best round is kept, and refused
/// only if it has an inverted cell.
pub const FLAT_RATIO: f64 = 1e-3;

/// The largest cell weight stiffening reaches (the Laplacian stays well conditioned enough
/// for its Cholesky factorisation).
const MAX_WEIGHT: f64 = 1e6;

/// Smoothing sweeps per frame. The smoother raises volumes, not shapes: a tangle left after
/// these is better repaired by stiffening than by more sweeps. Measured on `bird.toml`
/// (302,679 cells): 200 sweeps took up to 0.3 s a frame and left meshes needing 16–24 RK4
/// substeps and about 90 CG steps (frames 1–14); 40 and then 160 more while tangled, 24
/// substeps and 135 CG steps (frames 9–13); 40 and then stiffening, 8 and about 70.
const SMOOTH_SWEEPS: usize = 40;

/// A base mesh prepared for harmonic deformation with a fixed set of prescribed vertices.
#[derive(Debug)]
pub struct HarmonicDeformation {
    base: SimplexMesh,
    base_volumes: Vec<f64>,
    /// Index of each vertex among the free ones (`u32::MAX` if prescribed).
    free_index: Vec<u32>,
    free: Vec<u32>,
    solver: SparseSymmetricSolver,
    /// Per (cell, edge) the pattern slots of (a,a), (b,b), (a,b) for free a, b (MAX if absent).
    edge_slots: Vec<[usize; 3]>,
    /// The cell weights of the current numerical factorisation (the uniform weights' factor
    /// is kept across frames: only stiffened frames refactorise).
    factored_weights: Option<Vec<f64>>,
    smoother: super::untangle::Smoother,
    factorisations: usize,
    /// The cell weights, kept from frame to frame: a cell stiffened once stays stiff, so a
    /// periodic motion stops refactorising after its first period.
    weights: Vec<f64>,
}

impl HarmonicDeformation {
    /// Prepares `base` with `prescribed` vertices (the boundary) whose positions each frame
    /// supplies; every other vertex follows harmonically.
    pub fn new(base: &SimplexMesh, prescribed: &[u32]) -> Result<Self, MeshError> {
        let nv = base.vertex_count();
        let mut free_index = vec![0u32; nv];
        for &v in prescribed {
            if v as usize >= nv {
                return Err(MeshError::Structure(format!(
                    "prescribed vertex {v} of a mesh with {nv} vertices"
                )));
            }
            free_index[v as usize] = u32::MAX;
        }
        let mut free = Vec::new();
        for (v, slot) in free_index.iter_mut().enumerate() {
            if *slot != u32::MAX {
                *slot = free.len() as u32;
                free.push(v as u32);
            }
        }
        let dim = base.dim();
        let mut entries = Vec::new();
        for c in 0..base.cell_count() {
            let cell = base.cell(c);
            for i in 0..=dim {
                for j in i + 1..=dim {
                    let (a, b) = (free_index[cell[i] as usize], free_index[cell[j] as usize]);
                    if a != u32::MAX && b != u32::MAX {
                        entries.push((a as usize, b as usize));
                    }
                }
            }
        }
        let pattern = SymmetricPattern::new(free.len(), entries);
        let mut edge_slots = Vec::new();
        for c in 0..base.cell_count() {
            let cell = base.cell(c);
            for i in 0..=dim {
                for j in i + 1..=dim {
                    let (a, b) = (free_index[cell[i] as usize], free_index[cell[j] as usize]);
                    let slot = |r: u32, s: u32| {
                        if r == u32::MAX || s == u32::MAX {
                            usize::MAX
                        } else {
                            pattern.slot(r as usize, s as usize).expect("edge in pattern")
                        }
                    };
                    edge_slots.push([slot(a, a), slot(b, b), slot(a, b)]);
                }
            }
        }
        let solver = SparseSymmetricSolver::new(pattern, Factorisation::Llt)
            .map_err(|e| MeshError::Solve(format!("harmonic deformation: {e}")))?;
        let free_mask = free_index.iter().map(|&i| i != u32::MAX).collect();
        Ok(Self {
            base: base.clone(),
            base_volumes: base.volumes(),
            free_index,
            free,
            solver,
            edge_slots,
            factored_weights: None,
            smoother: super::untangle::Smoother::new(base, free_mask),
            factorisations: 0,
            weights: vec![1.0; base.cell_count()],
        })
    }

    /// Number of vertices that follow harmonically.
    pub fn free_count(&self) -> usize {
        self.free.len()
    }

    /// Numerical factorisations so far (the first, and one per stiffened solve).
    pub fn factorisations(&self) -> usize {
        self.factorisations
    }

    /// The deformed geometry vector for frame `frame`, with the prescribed vertices at their
    /// positions in `target` (a full geometry vector; its free entries are ignored). A frame
    /// that still has an inverted cell after the stiffening rounds is refused, naming it.
    pub fn deform(&mut self, target: &[f64], frame: usize) -> Result<Vec<f64>, MeshError> {
        self.base
            .check_coordinates(target)
            .map_err(|e| MeshError::Structure(format!("frame {frame}: {e}")))?;
        let mut weights = self.weights.clone();
        // The round whose smallest volume ratio is largest: (that ratio, geometry, ratios).
        let mut best: Option<(f64, Vec<f64>, Vec<f64>)> = None;
        for _ in 0..STIFFEN_ROUNDS {
            let mut g = self.solve(target, &weights, frame)?;
            let mut ratios: Vec<f64> =
                self.base.volumes_at(&g).iter().zip(&self.base_volumes).map(|(v, v0)| v / v0).collect();
            // The stiffening this solve's squeezed cells would get, should smoothing not do.
            let stiffen: Vec<(usize, f64)> = ratios
                .iter()
                .enumerate()
                .filter(|(_, &r)| r < 0.25)
                .map(|(c, &r)| (c, (0.25 / r.max(1e-3)).powi(2).min(1e4)))
                .collect();
            if ratios.iter().any(|&r| r < SMOOTH_BELOW) {
                let (mesh, vols) = (&self.base, &self.base_volumes);
                self.smoother.improve(mesh, vols, &mut g, &mut ratios, SMOOTH_TARGET, SMOOTH_SWEEPS);
            }
            let low = ratios.iter().copied().fold(f64::INFINITY, f64::min);
            if best.as_ref().is_none_or(|b| low > b.0) {
                best = Some((low, g, ratios));
            }
            if low > FLAT_RATIO {
                break;
            }
            // Tangled or nearly flat: stiffen the cells the harmonic solve squeezed, and solve
            // again.
            for (c, factor) in stiffen {
                weights[c] = (weights[c] * factor).min(MAX_WEIGHT);
            }
        }
        let (_, g, ratios) = best.expect("at least one round");
        let vols: Vec<f64> = ratios.iter().zip(&self.base_volumes).map(|(r, v0)| r * v0).collect();
        super::refuse_inverted(&vols, Some(frame))?;
        self.weights = weights;
        Ok(g)
    }

    fn solve(&mut self, target: &[f64], weights: &[f64], frame: usize) -> Result<Vec<f64>, MeshError> {
        let dim = self.base.dim();
        let g0 = self.base.g();
        let nf = self.free.len();
        let mut values = vec![0.0; self.solver.pattern().nnz()];
        let mut rhs = vec![0.0; nf * dim];
        let mut e = 0;
        for c in 0..self.base.cell_count() {
            let cell = self.base.cell(c);
            let w = weights[c];
            for i in 0..=dim {
                for j in i + 1..=dim {
                    let [aa, bb, ab] = self.edge_slots[e];
                    e += 1;
                    let (va, vb) = (cell[i] as usize, cell[j] as usize);
                    if aa != usize::MAX {
                        values[aa] += w;
                    }
                    if bb != usize::MAX {
                        values[bb] += w;
                    }
                    if ab != usize::MAX {
                        values[ab] -= w;
                    }
                    // A prescribed neighbour moves the free vertex: −L_FB d_B = +w d_B.
                    for (free_v, other) in [(va, vb), (vb, va)] {
                        let fi = self.free_index[free_v];
                        if fi != u32::MAX && self.free_index[other] == u32::MAX {
                            for k in 0..dim {
                                rhs[k * nf + fi as usize] +=
                                    w * (target[dim * other + k] - g0[dim * other + k]);
                            }
                        }
                    }
                }
            }
        }
        if self.factored_weights.as_deref() != Some(weights) {
            self.factored_weights = None;
            self.solver.factorise("harmonic deformation", &values).map_err(|e| {
                MeshError::Solve(format!("frame {frame}: {e} (a free vertex with no prescribed path?)"))
            })?;
            self.factored_weights = Some(weights.to_vec());
            self.factorisations += 1;
        }
        let mut g = target.to_vec();
        self.solver.solve_columns_in_place(&mut rhs, dim);
        for k in 0..dim {
            let col = &rhs[k * nf..(k + 1) * nf];
            for (i, &v) in self.free.iter().enumerate() {
                g[dim * v as usize + k] = g0[dim * v as usize + k] + col[i];
            }
        }
        Ok(g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::tunnel::{tunnel, TunnelSpec};

    #[test]
    fn scaling_the_obstacle_moves_the_interior_smoothly_and_keeps_the_walls() {
        let t = tunnel(
            &TunnelSpec { cell: 0.1, ..Default::default() },
            &crate::mesh::budget::CellBudget::machine(),
        )
        .expect("tunnel");
        let prescribed: Vec<u32> = t.obstacle.iter().chain(&t.outer).copied().collect();
        let mut h = HarmonicDeformation::new(&t.mesh, &prescribed).expect("prepare");
        // No boundary motion: no motion at all.
        let same = h.deform(t.mesh.g(), 0).expect("identity");
        assert!(same.iter().zip(t.mesh.g()).all(|(a, b)| (a - b).abs() < 1e-12));
        for (frame, scale) in [0.5, 1.6].into_iter().enumerate() {
            let mut target = t.mesh.g().to_vec();
            let c = t.spec.centre;
            for &v in &t.obstacle {
                for k in 0..2 {
                    let i = 2 * v as usize + k;
                    target[i] = c[k] + scale * (target[i] - c[k]);
                }
            }
            let m = t.mesh.with_g(h.deform(&target, frame).expect("deformed"), None).expect("valid");
            let area: f64 = m.volumes().iter().sum();
            let obstacle = 3.0 * 3f64.sqrt() / 4.0 * (scale * t.spec.radius).powi(2);
            assert!((area - (t.spec.length * t.spec.height - obstacle)).abs() < 1e-12);
            for &v in &t.outer {
                assert_eq!(m.point(v as usize), t.mesh.point(v as usize));
            }
        }
        // Far too large: the obstacle leaves the tunnel and cells invert; refused with the frame.
        let mut target = t.mesh.g().to_vec();
        for &v in &t.obstacle {
            target[2 * v as usize + 1] += 2.0;
        }
        match h.deform(&target, 7) {
            Err(MeshError::Inverted { frame: Some(7), .. }) => {}
            other => panic!("expected an inverted cell in frame 7, got {other:?}"),
        }
    }
}
