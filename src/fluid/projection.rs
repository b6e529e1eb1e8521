//! Pressure projection (seed 000 Eq. 10): the flux f closest to a velocity u in the energy
//! norm, `min ½‖u − V⁻¹(P⊗g)f‖²_V` subject to `div f = 0` and `D(f − h) = 0` (no flow
//! through a moving wall relative to the wall).
//!
//! Its optimality conditions are the saddle-point system
//!
//! ```text
//! [ K  Cᵀ ] [f]   [Pᵀu]        K = PᵀV⁻¹P,  C = [div; D],  c = [0; D h]
//! [ C  0  ] [λ] = [ c ]
//! ```
//!
//! Plain Uzawa iterations do not converge here: K can be singular (a checkerboard flux mode
//! on bipartite dual graphs). We factorise the quasi-definite regularisation
//! `[K + εI, Cᵀ; C, −δI]` by sparse LDLᵀ — no pivoting needed, the symbolic factorisation
//! is computed once and reused every frame — and solve the exact system by GMRES
//! preconditioned with that factorisation, which removes the regularisation's error. The
//! numerical factorisation is kept across frames: the next frame's system (the mesh has moved
//! a little) is solved by GMRES preconditioned with the old factor, which typically converges
//! in a few steps; only when it does not within [`GMRES_MAX`] steps is the system refactorised.
//!
//! C has one redundant row per connected domain (the divergences sum to the boundary flux):
//! the exact system is singular but consistent when the boundary fluxes sum to zero, which
//! [`Projection::project`] checks (refusing a net volume change) and then enforces to
//! rounding; the regularised preconditioner and GMRES leave λ's free component alone.

use crate::mesh::Topology;
use crate::tensor::{Factorisation, SparseSymmetricSolver, SymmetricPattern};

use super::operators::{divergence, CellOperators};
use super::FluidError;

/// Relative size of the regularisation: ε = 1e-10 · mean diag K, δ = 1e-10 / mean diag K.
const REGULARISATION: f64 = 1e-10;
/// GMRES stops when the residual is below this fraction of the right-hand side (2-norm). The
/// exact system's own rounding floor is about 3e-12 at 10⁵ cells (measured), so this leaves
/// a margin; the divergence it leaves is far smaller (it is checked in the tests to 1e-10
/// relative, measured 1e-14).
pub const GMRES_TOLERANCE: f64 = 1e-10;
/// GMRES restart length.
pub const GMRES_RESTART: usize = 20;
/// Most GMRES steps before the factorisation is refreshed.
pub const GMRES_MAX: usize = 20;

/// The projection's pattern, factorisation and assembly slots, fixed for a topology.
#[derive(Debug)]
pub struct Projection {
    nf: usize,
    nc: usize,
    /// Slots of K's entries, (d+1)² per cell (local faces l1 ≤ l2 only; others MAX).
    k_slots: Vec<usize>,
    diag_slots: Vec<usize>,
    solver: SparseSymmetricSolver,
    /// Exact-system values (constraint diagonal 0), and the regularised ones.
    exact: Vec<f64>,
    regularised: Vec<f64>,
    /// Whether `solver` holds a factorisation (of some earlier frame's values).
    factored: bool,
}

/// How a projection went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionReport {
    /// GMRES steps taken (each one solve with the factorisation).
    pub gmres_steps: usize,
    /// Whether this frame refactorised (else the previous frame's factorisation served as
    /// the preconditioner).
    pub refactorised: bool,
    /// max |div f| / max over cells of Σ |f| through its faces.
    pub relative_divergence: f64,
}

impl Projection {
    /// Prepares the pattern and symbolic factorisation for `topo`.
    pub fn new(topo: &Topology) -> Result<Self, FluidError> {
        let d = topo.dim();
        let (nf, nc) = (topo.face_count(), topo.cell_count());
        let nb = topo.boundary_faces().len();
        let n = nf + nc + nb;
        let mut entries = Vec::new();
        for c in 0..nc {
            for l1 in 0..=d {
                for l2 in l1..=d {
                    entries.push((topo.cell_face(c, l1), topo.cell_face(c, l2)));
                }
                entries.push((topo.cell_face(c, l1), nf + c));
            }
        }
        for (b, &f) in topo.boundary_faces().iter().enumerate() {
            entries.push((f as usize, nf + nc + b));
        }
        let pattern = SymmetricPattern::new(n, entries);
        let mut k_slots = Vec::with_capacity(nc * (d + 1) * (d + 1));
        for c in 0..nc {
            for l1 in 0..=d {
                for l2 in 0..=d {
                    k_slots.push(if l2 < l1 {
                        usize::MAX
                    } else {
                        pattern.slot(topo.cell_face(c, l1), topo.cell_face(c, l2)).expect("K entry")
                    });
                }
            }
        }
        let diag_slots: Vec<usize> = (0..n).map(|i| pattern.slot(i, i).expect("diagonal")).collect();
        // The constant part: C's entries.
        let mut exact = vec![0.0; pattern.nnz()];
        for c in 0..nc {
            for l in 0..=d {
                exact[pattern.slot(topo.cell_face(c, l), nf + c).expect("div entry")] += topo.sign(c, l);
            }
        }
        for (b, &f) in topo.boundary_faces().iter().enumerate() {
            exact[pattern.slot(f as usize, nf + nc + b).expect("D entry")] = 1.0;
        }
        let regularised = exact.clone();
        let solver = SparseSymmetricSolver::new(pattern, Factorisation::Ldlt)
            .map_err(|e| FluidError::Projection(e.to_string()))?;
        Ok(Self { nf, nc, k_slots, diag_slots, solver, exact, regularised, factored: false })
    }

    /// Entries of the LDLᵀ factor (fill included): the projection's memory.
    pub fn factor_len(&self) -> usize {
        self.solver.factor_len()
    }

    /// The flux minimising Eq. 10 for velocity `u` under geometry `ops`, with the boundary
    /// faces' fluxes set to `boundary_flux` (h on the boundary, in `topo.boundary_faces()`
    /// order). `frame` names the frame in errors.
    pub fn project(
        &mut self,
        topo: &Topology,
        ops: &CellOperators,
        u: &[f64],
        boundary_flux: &[f64],
        frame: usize,
    ) -> Result<(Vec<f64>, ProjectionReport), FluidError> {
        let d = topo.dim();
        let (nf, nc) = (self.nf, self.nc);
        let nb = boundary_flux.len();
        assert_eq!(nb, topo.boundary_faces().len(), "one flux per boundary face");
        // Consistency: the boundary fluxes must carry no net volume.
        let mut net = 0.0;
        let mut total = 0.0;
        for (b, &f) in topo.boundary_faces().iter().enumerate() {
            let [c, _] = topo.face_cells(f as usize);
            let l = topo.face_local(f as usize)[0] as usize;
            net += topo.sign(c as usize, l) * boundary_flux[b];
            total += boundary_flux[b].abs();
        }
        if net.abs() > 1e-9 * total.max(f64::MIN_POSITIVE) && net.abs() > 1e-300 {
            return Err(FluidError::VolumeChange { frame, net, relative: net / total });
        }
        // Assemble K = PᵀV⁻¹P.
        for &s in &self.diag_slots[..nf] {
            self.exact[s] = 0.0;
        }
        for s in self.k_slots.iter().filter(|&&s| s != usize::MAX) {
            self.exact[*s] = 0.0;
        }
        for c in 0..nc {
            let inv = 1.0 / ops.volumes[c];
            for l1 in 0..=d {
                for l2 in l1..=d {
                    let s = self.k_slots[(c * (d + 1) + l1) * (d + 1) + l2];
                    let dot: f64 = (0..d).map(|k| ops.lever(c, l1, k) * ops.lever(c, l2, k)).sum();
                    self.exact[s] += dot * inv;
                }
            }
        }
        // Right-hand side [Pᵀu; 0; h_b].
        let mut b = vec![0.0; nf + nc + nb];
        b[..nf].copy_from_slice(&ops.momentum_to_flux_transpose(topo, u));
        b[nf + nc..].copy_from_slice(boundary_flux);
        // Remove the rounding-level net flux (checked small above) so that the singular
        // system is exactly consistent: Σ_c div_c − Σ_b σ_b D_b = 0.
        let signs: Vec<f64> = topo
            .boundary_faces()
            .iter()
            .map(|&f| {
                topo.sign(topo.face_cells(f as usize)[0] as usize, topo.face_local(f as usize)[0] as usize)
            })
            .collect();
        if nb > 0 {
            for (bi, s) in b[nf + nc..].iter_mut().zip(&signs) {
                *bi -= s * net / nb as f64;
            }
        }
        // The last frame's factorisation preconditions GMRES on this frame's exact system; it
        // is refreshed when it no longer converges quickly (the mesh moved too far) or when
        // there is none yet.
        let mut refactorised = false;
        if !self.factored {
            self.refactorise(nf)?;
            refactorised = true;
        }
        let mut x = vec![0.0; b.len()];
        let mut iterations = self.gmres(&b, &mut x);
        if iterations.is_none() && !refactorised {
            self.refactorise(nf)?;
            refactorised = true;
            iterations = self.gmres(&b, &mut x);
        }
        let Some(gmres_steps) = iterations else {
            return Err(FluidError::Projection(format!(
                "frame {frame}: GMRES preconditioned by a fresh LDLᵀ did not reach {GMRES_TOLERANCE:e}"
            )));
        };
        x.truncate(nf);
        let div = divergence(topo, &x);
        let mut scale = 0.0f64;
        for c in 0..nc {
            scale = scale.max((0..=d).map(|l| x[topo.cell_face(c, l)].abs()).sum());
        }
        let max_div = div.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let relative_divergence = if scale > 0.0 { max_div / scale } else { max_div };
        if x.iter().any(|v| !v.is_finite()) {
            return Err(FluidError::Projection(format!("frame {frame}: the flux is not finite")));
        }
        Ok((x, ProjectionReport { gmres_steps, relative_divergence, refactorised }))
    }

    /// Factorises the regularised system `[K + εI, Cᵀ; C, −δI]` of the current values.
    fn refactorise(&mut self, nf: usize) -> Result<(), FluidError> {
        let mean_diag = self.diag_slots[..nf].iter().map(|&s| self.exact[s]).sum::<f64>() / nf.max(1) as f64;
        let (eps, delta) = (REGULARISATION * mean_diag, REGULARISATION / mean_diag);
        self.regularised.copy_from_slice(&self.exact);
        for &s in &self.diag_slots[..nf] {
            self.regularised[s] += eps;
        }
        for &s in &self.diag_slots[nf..] {
            self.regularised[s] = -delta;
        }
        self.factored = false;
        self.solver
            .factorise("projection", &self.regularised)
            .map_err(|e| FluidError::Projection(e.to_string()))?;
        self.factored = true;
        Ok(())
    }

    /// Right-preconditioned GMRES on the exact system from `x`, the factorisation as the
    /// preconditioner, restarted every [`GMRES_RESTART`] steps; the number of steps, or
    /// `None` if the residual did not fall below [`GMRES_TOLERANCE`] of `‖b‖` within
    /// [`GMRES_MAX`] steps.
    fn gmres(&self, b: &[f64], x: &mut [f64]) -> Option<usize> {
        let dot = |a: &[f64], c: &[f64]| a.iter().zip(c).map(|(p, q)| p * q).sum::<f64>();
        let b_norm = dot(b, b).sqrt().max(f64::MIN_POSITIVE);
        let mut steps = 0;
        while steps < GMRES_MAX {
            let ax = self.solver.pattern().mul(&self.exact, x);
            let r: Vec<f64> = b.iter().zip(&ax).map(|(p, q)| p - q).collect();
            let beta = dot(&r, &r).sqrt();
            if beta <= GMRES_TOLERANCE * b_norm {
                return Some(steps);
            }
            let m = GMRES_RESTART;
            let mut v: Vec<Vec<f64>> = vec![r.iter().map(|q| q / beta).collect()];
            let mut z: Vec<Vec<f64>> = Vec::new();
            let mut h = vec![vec![0.0; m]; m + 1];
            let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
            let mut g = vec![0.0; m + 1];
            g[0] = beta;
            let mut k_done = 0;
            for k in 0..m {
                let mut zk = v[k].clone();
                self.solver.solve_in_place(&mut zk);
                let mut w = self.solver.pattern().mul(&self.exact, &zk);
                z.push(zk);
                for (i, vi) in v.iter().enumerate() {
                    h[i][k] = dot(&w, vi);
                    for (wj, vj) in w.iter_mut().zip(vi) {
                        *wj -= h[i][k] * vj;
                    }
                }
                h[k + 1][k] = dot(&w, &w).sqrt();
                for i in 0..k {
                    let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
                    h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
                    h[i][k] = t;
                }
                let rho = (h[k][k] * h[k][k] + h[k + 1][k] * h[k + 1][k]).sqrt();
                if rho == 0.0 {
                    k_done = k;
                    break;
                }
                cs[k] = h[k][k] / rho;
                sn[k] = h[k + 1][k] / rho;
                h[k][k] = rho;
                h[k + 1][k] = 0.0;
                g[k + 1] = -sn[k] * g[k];
                g[k] *= cs[k];
                steps += 1;
                k_done = k + 1;
                let norm_w = dot(&w, &w).sqrt();
                if g[k + 1].abs() <= 0.1 * GMRES_TOLERANCE * b_norm || norm_w == 0.0 || steps >= GMRES_MAX {
                    break;
                }
                v.push(w.iter().map(|q| q / norm_w).collect());
            }
            // x += Z y with H y = g (upper triangular).
            let mut y = vec![0.0; k_done];
            for i in (0..k_done).rev() {
                let s: f64 = (i + 1..k_done).map(|j| h[i][j] * y[j]).sum();
                y[i] = (g[i] - s) / h[i][i];
            }
            for (yi, zi) in y.iter().zip(&z) {
                for (xj, zj) in x.iter_mut().zip(zi) {
                    *xj += yi * zj;
                }
            }
            if k_done == 0 {
                break;
            }
        }
        let ax = self.solver.pattern().mul(&self.exact, x);
        let r: Vec<f64> = b.iter().zip(&ax).map(|(p, q)| p - q).collect();
        (dot(&r, &r).sqrt() <= GMRES_TOLERANCE * b_norm).then_some(steps)
    }
}
