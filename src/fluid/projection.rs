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
//! is computed once and reused every frame — and remove the regularisation's error by
//! iterative refinement against the exact system. C has one redundant row per connected
//! domain (the divergences sum to the boundary flux); the regularisation handles it and the
//! refinement leaves its component of λ alone. The constraints are consistent only if the
//! boundary flux sums to zero, which [`Projection::project`] checks.

use crate::mesh::Topology;
use crate::tensor::{Factorisation, SparseSymmetricSolver, SymmetricPattern};

use super::operators::{divergence, CellOperators};
use super::FluidError;

/// Relative size of the regularisation: ε = 1e-10 · mean diag K, δ = 1e-10 / mean diag K.
const REGULARISATION: f64 = 1e-10;
/// Refinement stops when the residual is below this fraction of the right-hand side.
const REFINEMENT_TOLERANCE: f64 = 1e-14;
const MAX_REFINEMENTS: usize = 30;

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
}

/// How a projection went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectionReport {
    /// Iterative-refinement steps taken.
    pub refinements: usize,
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
        Ok(Self { nf, nc, k_slots, diag_slots, solver, exact, regularised })
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
        let mean_diag = self.diag_slots[..nf].iter().map(|&s| self.exact[s]).sum::<f64>() / nf.max(1) as f64;
        let (eps, delta) = (REGULARISATION * mean_diag, REGULARISATION / mean_diag);
        self.regularised.copy_from_slice(&self.exact);
        for &s in &self.diag_slots[..nf] {
            self.regularised[s] += eps;
        }
        for &s in &self.diag_slots[nf..] {
            self.regularised[s] = -delta;
        }
        self.solver
            .factorise("projection", &self.regularised)
            .map_err(|e| FluidError::Projection(e.to_string()))?;
        // Right-hand side [Pᵀu; 0; h_b].
        let mut b = vec![0.0; nf + nc + nb];
        b[..nf].copy_from_slice(&ops.momentum_to_flux_transpose(topo, u));
        b[nf + nc..].copy_from_slice(boundary_flux);
        let b_norm = b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(f64::MIN_POSITIVE);
        let mut x = vec![0.0; b.len()];
        let mut r = b.clone();
        let mut refinements = 0;
        let mut last = f64::INFINITY;
        for _ in 0..MAX_REFINEMENTS {
            let mut dx = r.clone();
            self.solver.solve_in_place(&mut dx);
            for (xi, di) in x.iter_mut().zip(&dx) {
                *xi += di;
            }
            refinements += 1;
            let ax = self.solver.pattern().mul(&self.exact, &x);
            for ((ri, bi), ai) in r.iter_mut().zip(&b).zip(&ax) {
                *ri = bi - ai;
            }
            // The redundant constraint direction leaves a constant residual in λ's rows that
            // no flux can remove; judge convergence on the flux rows and the constraints
            // separately.
            let res = r.iter().fold(0.0f64, |m, v| m.max(v.abs())) / b_norm;
            if res <= REFINEMENT_TOLERANCE || res >= 0.5 * last {
                break;
            }
            last = res;
        }
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
        Ok((x, ProjectionReport { refinements, relative_divergence }))
    }
}
