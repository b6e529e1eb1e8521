//! The reduced time step (seed 000 Fig. 2, right), the Galerkin projection of exactly the step
//! [`crate::fluid::solver`] takes:
//!
//! 1. **flux combination** — [`FluxCombination::Separate`] (the default, §6.4 and our full
//!    solver): the rate's operator is `K̂ = Â ⊗₂ f̂ − Â_h ⊗₂ ĥ + μΔ̂`, where `Â_h` carries the
//!    solver's −V̇u term; [`FluxCombination::ProjectedOntoFlux`] (Fig. 2 as printed):
//!    `f̂' = f̂ − B_fᵀB_h ĥ`, `K̂ = Â ⊗₂ f̂' + μΔ̂` with no −V̇u term — `B_fᵀB_h` keeps only the
//!    divergence-free part of the induced flux, which is why Fig. 2 needs no −V̇u term and is
//!    energy-neutral on a moving mesh, at the price of dropping the flux the mesh motion
//!    pushes through the faces;
//! 2. **advection and diffusion by the matrix exponential**: `û' = exp[Δt V̂⁻¹(ĝ_t) K̂] û_t`,
//!    computed as `û' = L⁻ᵀ exp(Δt L⁻¹K̂L⁻ᵀ) Lᵀû` with `V̂(ĝ_t) = LLᵀ` (Cholesky), so the
//!    energy `E = ½ûᵀV̂û = ½‖Lᵀû‖²` is the Euclidean norm of what the exponential acts on:
//!    when the symmetric part of K̂ is negative semidefinite (a static mesh, or Fig. 2's
//!    combination: `Â ⊗₂ f̂` is skew because `B_u = B_p` and `div B_f = 0`, `Δ̂ ≤ 0`) the
//!    update never increases E for any Δt (§A.1–A.2), for the Krylov approximation as well
//!    (see [`crate::tensor::expm_krylov`]). With the separate induced flux the symmetric part
//!    is `B_uᵀ(−½ diag(div h) + μΔ)B_u`, exactly the full solver's frozen-volume rate;
//! 3. **reduced projection (Eq. 12)** at ĝ_{t+1}: minimise `½‖û' − V̂⁻¹(P̂ ⊗₂ ĝ)f̂‖²_V̂` subject
//!    to the reduced boundary constraint `D̂ f̂ = D̂_h ĥ` (B_d from constraint reduction, so it
//!    holds iff the full one does): `f̂ = f̂_c + Z y` with `f̂_c = D̂⁺ D̂_h ĥ` and `Z` the null
//!    space of `D̂` (both from one SVD of `D̂` when the model is loaded), then the SPD normal
//!    equations `Zᵀ(P̂ᵀV̂⁻¹P̂)Z y = Zᵀ(P̂ᵀû' − P̂ᵀV̂⁻¹P̂ f̂_c)` by Cholesky. With ĥ = 0 the result
//!    is the V̂-orthogonal projection of û' onto a subspace, so it never increases E;
//! 4. **conversion to velocity**: `û_{t+1} = V̂⁻¹(ĝ_{t+1})(P̂ ⊗₂ ĝ_{t+1}) f̂_{t+1}`.

use std::time::Instant;

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, Mat, Par};

use crate::fluid::FluidError;
use crate::tensor::expm_krylov;

use super::dense::{
    cholesky, cholesky_solve, fold_symmetric, matvec, matvec_f32_split, row_major, transpose_times,
};
use super::exact_projection::{ExactProjection, FluxVelocityGrams};
use super::model::ReducedFluidModel;

/// How the induced flux enters advection (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FluxCombination {
    /// `Â ⊗ f̂ − Â_h ⊗ ĥ` with the solver's −V̇u term (§6.4; the default).
    #[default]
    Separate,
    /// `Â ⊗ (f̂ − B_fᵀB_h ĥ)` (Fig. 2 as printed).
    ProjectedOntoFlux,
}

/// How the exponential is applied.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exponential {
    /// Arnoldi `exp(A)v` to this relative tolerance (the default, 1e-12).
    Krylov(f64),
    /// Scaling and squaring with Padé 13 on the whole matrix.
    Pade,
}

impl Default for Exponential {
    fn default() -> Self {
        Exponential::Krylov(1e-12)
    }
}

/// The default of [`ReducedFluid::with_seen_flux`]'s threshold: flux directions with less
/// than this fraction of their velocity energy inside `B_u` are left out of the projection
/// (chosen on the bird: BENCHMARKS.md, "Flux directions the velocity basis sees").
pub const SEEN_FLUX_THRESHOLD: f64 = 0.1;

/// What [`ReducedFluid::with_seen_flux`] kept.
#[derive(Clone, Debug, PartialEq)]
pub struct SeenFlux {
    /// The threshold.
    pub threshold: f64,
    /// Flux directions kept.
    pub kept: usize,
    /// The fraction of each free flux direction's velocity energy inside `B_u`, ascending.
    pub fractions: Vec<f64>,
}

impl SeenFlux {
    /// Free flux directions there were (the constraint's null space).
    pub fn of(&self) -> usize {
        self.fractions.len()
    }

    /// One line for a log: what was kept and why.
    pub fn line(&self) -> String {
        let median = self.fractions.get(self.fractions.len() / 2).copied().unwrap_or(0.0);
        format!(
            "the projection solves for {} of {} free flux directions, those with at least {:.0} % of their velocity energy inside B_u (median over all {:.1} %; --seen-flux sets the threshold)",
            self.kept,
            self.of(),
            100.0 * self.threshold,
            100.0 * median
        )
    }
}

/// The reduced state: velocity, flux and geometry coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct ReducedState {
    /// û (m_u).
    pub u: Vec<f64>,
    /// f̂ (m_f).
    pub f: Vec<f64>,
    /// ĝ (m_g).
    pub g: Vec<f64>,
}

/// Seconds per stage of one reduced step, and the exponential's work.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ReducedStepReport {
    /// Assembling K̂ (the contractions of Â, Â_h, Δ̂).
    pub assemble_seconds: f64,
    /// Contracting V̂ with ĝ (both geometries) and factorising.
    pub volume_seconds: f64,
    /// The exponential.
    pub exponential_seconds: f64,
    /// The projection and the conversion to velocity.
    pub projection_seconds: f64,
    /// Matrix–vector products of the Krylov exponential.
    pub krylov_products: usize,
    /// `‖D̂ f̂ − D̂_h ĥ‖` after the projection (0 without constraints): 0 to rounding when the
    /// flux basis can carry the boundary flux of the motion (every replayed training motion),
    /// otherwise the least-squares remainder of a motion it was not trained for.
    pub constraint_residual: f64,
    /// `‖D̂_h ĥ‖`, the scale of that residual.
    pub constraint_target: f64,
    /// The energy `½ûᵀV̂û` at the step's start, after advection and diffusion (both at ĝ_t),
    /// and after the projection (at ĝ_{t+1}): where a reduced run's energy goes (read off the
    /// factors the step computes anyway, `½‖Lᵀû‖²`).
    pub energy: [f64; 3],
    /// Wall seconds of the whole step ([`ReducedFluid::step`]; the stage times above are each
    /// stage's own, and two of them run at once).
    pub seconds: f64,
}

impl ReducedStepReport {
    /// The step's wall seconds (the stages' sum when they were timed one by one).
    pub fn total_seconds(&self) -> f64 {
        if self.seconds > 0.0 {
            self.seconds
        } else {
            self.assemble_seconds + self.volume_seconds + self.exponential_seconds + self.projection_seconds
        }
    }
}

/// The reduced boundary constraint prepared from one SVD of `D̂`.
#[derive(Clone, Debug)]
struct Constraint {
    /// `D̂⁺` (m_f × m_d).
    pinv: Mat<f64>,
    /// Null space of `D̂` (m_f × (m_f − rank)).
    null: Mat<f64>,
    /// `D̂` (m_d × m_f).
    d: Mat<f64>,
    /// `D̂_h` (m_d × m_h), if the model has B_h.
    dh: Option<Mat<f64>>,
}

/// The reduced fluid at run time: the model's tensors laid out for the step.
#[derive(Clone, Debug)]
pub struct ReducedFluid {
    dim: usize,
    mu: usize,
    mf: usize,
    mg: usize,
    mh: usize,
    viscosity: f64,
    frame_time: f64,
    /// Â, row-major, in f32 (see [`matvec_f32_split`]): when every `Â[:, :, j]` is skew (B_f
    /// divergence-free, B_u = B_p: §A.2) only its strict upper triangle, `m_u(m_u−1)/2 × m_f`
    /// (half the memory traffic, and K̂'s advective part skew whatever the rounding);
    /// otherwise all of it, `(m_u·m_u) × m_f`.
    a: Vec<f32>,
    /// Whether `a` holds the skew upper triangle.
    a_skew: bool,
    /// Â_h as (m_u·m_u) × m_h, in f32.
    ah: Vec<f32>,
    /// Δ̂ (m_u·m_u).
    lap: Vec<f64>,
    /// P̂ as (m_u·m_f) × m_g.
    p: Vec<f64>,
    /// V̂'s upper triangle (p ≤ u: V̂ is symmetric) against its distinct geometry monomials,
    /// `m_u(m_u+1)/2 × monomials`, multiplicities folded in.
    v: Vec<f64>,
    /// The monomials' geometry indices.
    monomials: Vec<Vec<usize>>,
    /// Ĥ against the distinct monomials of γ̂ = [ĝ_t; ĝ_{t+1}]: m_h × monomials, multiplicities
    /// folded in ([`super::induced`]); empty without B_h.
    induced: Vec<f64>,
    /// The monomials' γ̂ indices.
    induced_monomials: Vec<Vec<usize>>,
    /// B_fᵀ B_h (m_f × m_h) for [`FluxCombination::ProjectedOntoFlux`].
    bf_bh: Option<Mat<f64>>,
    constraint: Option<Constraint>,
    /// How the induced flux enters.
    pub combination: FluxCombination,
    /// How the exponential is applied.
    pub exponential: Exponential,
    /// The projection's normal matrix from the full space ([`super::exact_projection`])
    /// instead of `P̂ᵀV̂⁻¹P̂`.
    exact: Option<std::sync::Arc<ExactProjection>>,
    /// The flux directions the projection solves for, when narrowed to those whose velocity
    /// the velocity basis sees ([`Self::with_seen_flux`]): m_f × r orthonormal columns inside
    /// the constraint's null space.
    seen_flux: Option<std::sync::Arc<Mat<f64>>>,
    /// What [`Self::with_seen_flux`] kept.
    seen_report: Option<SeenFlux>,
    /// The last Cholesky factor of V̂(ĝ) and its ĝ: a step's end geometry is the next step's
    /// start.
    factor: FactorCache,
}

/// One cached factor (a clone starts empty).
#[derive(Debug, Default)]
struct FactorCache(std::sync::Mutex<Option<(Vec<f64>, Mat<f64>)>>);

impl Clone for FactorCache {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// `Â` counts as skew when `max|Â[p,u,j] + Â[u,p,j]|` is at most this fraction of `max|Â|`
/// (a divergence-free B_f makes it skew to rounding, ~1e-14).
const SKEW_TOLERANCE: f64 = 1e-10;

/// Singular values of `D̂` at or below this (relative to the largest, at least 1) are zero.
const CONSTRAINT_SVD_TOLERANCE: f64 = 1e-10;

fn state_err(m: String) -> FluidError {
    FluidError::State(m)
}

impl ReducedFluid {
    /// Lays out `model`'s tensors for the step, its projection narrowed to the flux
    /// directions the velocity basis sees when the model carries their measure
    /// ([`Self::with_seen_flux`] at [`SEEN_FLUX_THRESHOLD`]).
    pub fn new(model: &ReducedFluidModel) -> Result<Self, FluidError> {
        Self::with_seen_flux_threshold(model, SEEN_FLUX_THRESHOLD)
    }

    /// [`Self::new`] with the seen-flux threshold `threshold` (used where the model carries
    /// the measure).
    pub fn with_seen_flux_threshold(model: &ReducedFluidModel, threshold: f64) -> Result<Self, FluidError> {
        let (mu, mf, mg, mh, md) =
            (model.dim_of("u"), model.dim_of("f"), model.dim_of("g"), model.dim_of("h"), model.dim_of("d"));
        let t = |n: &str| model.tensor(n).ok_or_else(|| state_err(format!("the model has no tensor {n}")));
        let dim = model.dim;
        // V̂[p, u, a, b(, c)] over the distinct sorted geometry monomials, its upper triangle
        // in (p, u) (V̂ is symmetric; the two halves averaged).
        let (full_v, monomials) = fold_symmetric(t("V")?.data(), mu * mu, mg, dim);
        let nm = monomials.len();
        let mut v = Vec::with_capacity(mu * (mu + 1) / 2 * nm);
        for p in 0..mu {
            for u in p..mu {
                let (a, b) = (&full_v[(p * mu + u) * nm..][..nm], &full_v[(u * mu + p) * nm..][..nm]);
                v.extend(a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)));
            }
        }
        // Â's slices are skew when its flux basis is divergence-free (uᵀ(A⊗f)u = −½Σ|u|² div f).
        let at = t("A")?.data();
        let scale = at.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let mut skew_err = 0.0f64;
        for p in 0..mu {
            for u in p..mu {
                for j in 0..mf {
                    skew_err = skew_err.max((at[(p * mu + u) * mf + j] + at[(u * mu + p) * mf + j]).abs());
                }
            }
        }
        let a_skew = skew_err <= SKEW_TOLERANCE * scale.max(f64::MIN_POSITIVE);
        let a = if a_skew {
            let mut packed = Vec::with_capacity(mu * (mu - 1) / 2 * mf);
            for p in 0..mu {
                for u in p + 1..mu {
                    for j in 0..mf {
                        packed.push((0.5 * (at[(p * mu + u) * mf + j] - at[(u * mu + p) * mf + j])) as f32);
                    }
                }
            }
            packed
        } else {
            at.iter().map(|&x| x as f32).collect()
        };
        let (induced, induced_monomials) = match model.tensor("H") {
            Some(ht) if mh > 0 => fold_symmetric(ht.data(), mh, 2 * mg, dim),
            _ => (Vec::new(), Vec::new()),
        };
        let bf_bh = match (model.basis("f"), model.basis("h")) {
            (Some(bf), Some(bh)) => Some(transpose_times(bf.matrix(), bh.matrix())),
            _ => None,
        };
        let constraint = if md > 0 {
            let d = row_major(t("D")?, md, mf);
            let dh = if mh > 0 { Some(row_major(t("Dh")?, md, mh)) } else { None };
            Some(prepare_constraint(d, dh)?)
        } else {
            None
        };
        Ok(Self {
            dim,
            mu,
            mf,
            mg,
            mh,
            viscosity: model.viscosity,
            frame_time: model.frame_time,
            a,
            a_skew,
            ah: if mh > 0 { t("Ah")?.data().iter().map(|&x| x as f32).collect() } else { Vec::new() },
            lap: t("L")?.data().to_vec(),
            p: t("P")?.data().to_vec(),
            v,
            monomials,
            induced,
            induced_monomials,
            bf_bh,
            constraint,
            combination: FluxCombination::default(),
            exponential: Exponential::default(),
            exact: None,
            seen_flux: None,
            seen_report: None,
            factor: FactorCache::default(),
        })
        .and_then(|fluid| match &model.flux_grams {
            Some(grams) => fluid.with_seen_flux(grams, threshold),
            None => Ok(fluid),
        })
    }

    /// The step with the projection's normal matrix computed in the full space, `M(g)`
    /// ([`super::exact_projection`]): once per run on a static mesh, every frame on a moving one.
    pub fn with_exact_projection(mut self, model: &ReducedFluidModel) -> Result<Self, FluidError> {
        self.exact = Some(std::sync::Arc::new(ExactProjection::new(model)?));
        Ok(self)
    }

    /// The step with the projection's free flux directions narrowed to those whose velocity
    /// the velocity basis sees: with `M` and `N` the model's [`FluxVelocityGrams`] (the flux
    /// modes' velocity Gram matrix in the full space and its part inside `B_u`), the
    /// generalized eigenvectors of `Zᵀ N Z v = λ Zᵀ M Z v` (Z the boundary constraint's null
    /// space, or I) with `λ ≥ threshold` — λ ∈ [0, 1] is the fraction of the direction's
    /// velocity energy inside `B_u`. Directions below it are ones Eq. 12's reduced projection
    /// cannot identify from a velocity in `B_u`: it gives them coefficients that barely change
    /// the velocity but advect with their whole flux (docs/fluids.md, "Flux directions the
    /// velocity basis sees"). Restricting `f̂` to a subspace keeps §A's energy argument (with
    /// `ĥ = 0` the result is still the V̂-orthogonal projection onto a subspace). A threshold
    /// of 0 keeps every direction (the projection as without narrowing).
    pub fn with_seen_flux(mut self, grams: &FluxVelocityGrams, threshold: f64) -> Result<Self, FluidError> {
        if !(0.0..=1.0).contains(&threshold) {
            return Err(state_err(format!("the seen-flux threshold {threshold}: give 0 to 1")));
        }
        let (m, n) = grams.matrices();
        if m.nrows() != self.mf || n.nrows() != self.mf {
            return Err(state_err(format!(
                "the flux velocity Gram matrices are {}×{}, the flux basis has {} modes",
                m.nrows(),
                m.ncols(),
                self.mf
            )));
        }
        let base = match &self.constraint {
            Some(con) => con.null.clone(),
            None => Mat::<f64>::identity(self.mf, self.mf),
        };
        let k = base.ncols();
        let sym = |a: Mat<f64>| Mat::from_fn(k, k, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
        let mz = sym(base.transpose() * &m * &base);
        let nz = sym(base.transpose() * &n * &base);
        let l = cholesky(
            &mz,
            "the flux modes' velocity Gram matrix ZᵀMZ (--seen-flux 0 turns the narrowing off)",
        )?;
        // C = L⁻¹ (ZᵀNZ) L⁻ᵀ: its eigenvalues are the generalized ones.
        let mut c = nz;
        solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), Par::Seq);
        let mut c = c.transpose().to_owned();
        solve_lower_triangular_in_place(l.as_ref(), c.as_mut(), Par::Seq);
        let eig = sym(c)
            .self_adjoint_eigen(faer::Side::Lower)
            .map_err(|e| state_err(format!("the seen flux directions' eigenvalues: {e:?}")))?;
        let (u, values) = (eig.U(), eig.S());
        let fractions: Vec<f64> = (0..k).map(|i| values[i]).collect();
        let keep: Vec<usize> = (0..k).filter(|&i| fractions[i] >= threshold).collect();
        // v = L⁻ᵀ (eigenvectors kept), then orthonormal columns spanning Z v.
        let mut v = Mat::from_fn(k, keep.len(), |i, j| u[(i, keep[j])]);
        solve_upper_triangular_in_place(l.transpose(), v.as_mut(), Par::Seq);
        let w = (&base * &v).qr().compute_thin_Q();
        self.seen_flux = Some(std::sync::Arc::new(w));
        self.seen_report = Some(SeenFlux { threshold, kept: keep.len(), fractions });
        Ok(self)
    }

    /// The narrowing [`Self::with_seen_flux`] applied, if any.
    pub fn seen_flux(&self) -> Option<&SeenFlux> {
        self.seen_report.as_ref()
    }

    /// The full-space projection, when on.
    pub fn exact_projection(&self) -> Option<&ExactProjection> {
        self.exact.as_deref()
    }

    /// Bytes the step holds: its tensors as laid out here — `V̂` over its symmetric axes
    /// folded to distinct monomials, `Â` (f32) to its skew upper triangle when it is skew,
    /// `Â_h` (f32), `Ĥ` folded likewise, `Δ̂`, `P̂` — and the constraint's matrices. Table 1's memory
    /// column counts the same thing, the reduced tensors the run-time simulation reads (not
    /// the bases the particles read: see [`super::particles::ReducedParticles`]).
    pub fn bytes(&self) -> usize {
        let mat = |m: &Mat<f64>| m.nrows() * m.ncols();
        let constraint = self
            .constraint
            .as_ref()
            .map_or(0, |c| mat(&c.pinv) + mat(&c.null) + mat(&c.d) + c.dh.as_ref().map_or(0, mat));
        let values = self.lap.len()
            + self.p.len()
            + self.v.len()
            + self.induced.len()
            + self.bf_bh.as_ref().map_or(0, mat)
            + constraint;
        4 * (self.a.len() + self.ah.len()) + 8 * values
    }

    /// Reduced dimensions (m_u, m_f, m_g, m_h).
    pub fn dims(&self) -> (usize, usize, usize, usize) {
        (self.mu, self.mf, self.mg, self.mh)
    }

    /// The model's frame time.
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }

    /// The spatial dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// `V̂(ĝ)` (m_u × m_u).
    pub fn volume_matrix(&self, g: &[f64]) -> Mat<f64> {
        let nm = self.monomials.len();
        let w: Vec<f64> = self.monomials.iter().map(|idx| idx.iter().map(|&i| g[i]).product()).collect();
        let mu = self.mu;
        let packed = matvec(&self.v, mu * (mu + 1) / 2, nm, &w);
        let mut out = Mat::<f64>::zeros(mu, mu);
        let mut row = 0;
        for p in 0..mu {
            for u in p..mu {
                out[(p, u)] = packed[row];
                out[(u, p)] = packed[row];
                row += 1;
            }
        }
        out
    }

    /// Refuses a reduced geometry ĝ whose volume matrix `V̂(ĝ)` is not positive definite
    /// (the step could not invert it), `what` naming ĝ in the error.
    pub fn check_geometry(&self, g: &[f64], what: &str) -> Result<(), FluidError> {
        cholesky(&self.volume_matrix(g), what).map(|_| ())
    }

    /// The Cholesky factor of `V̂(ĝ)`, from the cache when ĝ is the last one factorised.
    fn volume_factor(&self, g: &[f64], what: &str) -> Result<Mat<f64>, FluidError> {
        if let Ok(cache) = self.factor.0.lock() {
            if let Some((cg, l)) = cache.as_ref() {
                if cg.as_slice() == g {
                    return Ok(l.clone());
                }
            }
        }
        let l = cholesky(&self.volume_matrix(g), what)?;
        if let Ok(mut cache) = self.factor.0.lock() {
            *cache = Some((g.to_vec(), l.clone()));
        }
        Ok(l)
    }

    /// `ĥ = Ĥ ⊗ γ̂ ⋯ ⊗ γ̂` with `γ̂ = [ĝ_t; ĝ_{t+1}]`: the reduced induced flux of the motion
    /// ĝ_t → ĝ_{t+1} ([`super::induced`]); `None` when the model has no induced-flux tensor.
    pub fn induced_flux(&self, g0: &[f64], g1: &[f64]) -> Option<Vec<f64>> {
        if self.induced_monomials.is_empty() || g0.len() != self.mg || g1.len() != self.mg {
            return None;
        }
        let gamma: Vec<f64> = g0.iter().chain(g1).copied().collect();
        let w: Vec<f64> =
            self.induced_monomials.iter().map(|idx| idx.iter().map(|&i| gamma[i]).product()).collect();
        Some(matvec(&self.induced, self.mh, w.len(), &w))
    }

    /// `P̂ ⊗₂ ĝ` (m_u × m_f).
    pub fn flux_to_momentum(&self, g: &[f64]) -> Mat<f64> {
        let flat = matvec(&self.p, self.mu * self.mf, self.mg, g);
        Mat::from_fn(self.mu, self.mf, |i, j| flat[i * self.mf + j])
    }

    /// `K̂` of the advection–diffusion rate `V̂⁻¹K̂` (see the module docs).
    pub fn rate_operator(&self, f: &[f64], h: &[f64]) -> Mat<f64> {
        let mu = self.mu;
        let fp = match (self.combination, &self.bf_bh) {
            (FluxCombination::ProjectedOntoFlux, Some(bfbh)) if self.mh > 0 => {
                let mut fp = f.to_vec();
                for i in 0..self.mf {
                    fp[i] -= (0..self.mh).map(|j| bfbh[(i, j)] * h[j]).sum::<f64>();
                }
                fp
            }
            _ => f.to_vec(),
        };
        let mut k = Mat::from_fn(mu, mu, |i, j| self.viscosity * self.lap[i * mu + j]);
        if self.a_skew {
            let packed = matvec_f32_split(&self.a, mu * (mu - 1) / 2, self.mf, &fp);
            let mut row = 0;
            for p in 0..mu {
                for u in p + 1..mu {
                    k[(p, u)] += packed[row];
                    k[(u, p)] -= packed[row];
                    row += 1;
                }
            }
        } else {
            let flat = matvec_f32_split(&self.a, mu * mu, self.mf, &fp);
            for p in 0..mu {
                for u in 0..mu {
                    k[(p, u)] += flat[p * mu + u];
                }
            }
        }
        if self.mh > 0 && self.combination == FluxCombination::Separate {
            let kh = matvec_f32_split(&self.ah, mu * mu, self.mh, h);
            for p in 0..mu {
                for u in 0..mu {
                    k[(p, u)] -= kh[p * mu + u];
                }
            }
        }
        k
    }

    /// The energy `½ ûᵀ V̂(ĝ) û`.
    pub fn energy(&self, u: &[f64], g: &[f64]) -> f64 {
        let v = self.volume_matrix(g);
        0.5 * (0..self.mu).map(|i| u[i] * (0..self.mu).map(|j| v[(i, j)] * u[j]).sum::<f64>()).sum::<f64>()
    }

    /// Checks the lengths of a state and a motion.
    fn check(&self, s: &ReducedState, g_next: &[f64], h: &[f64]) -> Result<(), FluidError> {
        for (what, got, want) in [
            ("û", s.u.len(), self.mu),
            ("f̂", s.f.len(), self.mf),
            ("ĝ_t", s.g.len(), self.mg),
            ("ĝ_{t+1}", g_next.len(), self.mg),
            ("ĥ", h.len(), self.mh),
        ] {
            if got != want {
                return Err(state_err(format!(
                    "reduced step: {what} has {got} entries, the model needs {want}"
                )));
            }
        }
        if s.u.iter().chain(&s.f).chain(&s.g).chain(g_next).chain(h).any(|v| !v.is_finite()) {
            return Err(state_err("reduced step: the state or motion is not finite".into()));
        }
        Ok(())
    }

    /// Advection and diffusion over `dt` from `u` at geometry `g` (stage 2 of the module docs).
    pub fn advect(
        &self,
        u: &[f64],
        f: &[f64],
        g: &[f64],
        h: &[f64],
        dt: f64,
        report: &mut ReducedStepReport,
    ) -> Result<Vec<f64>, FluidError> {
        let t0 = Instant::now();
        let k = self.rate_operator(f, h);
        report.assemble_seconds += t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let l = self.volume_factor(g, "V̂(ĝ_t)")?;
        report.volume_seconds += t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        // w = Lᵀ u.
        let mut w = vec![0.0; self.mu];
        for i in 0..self.mu {
            w[i] = (i..self.mu).map(|j| l[(j, i)] * u[j]).sum();
        }
        let half_square = |v: &[f64]| 0.5 * v.iter().map(|x| x * x).sum::<f64>();
        report.energy[0] = half_square(&w);
        // M = L⁻¹ K L⁻ᵀ. The Krylov exponential applies it as two triangular solves and a
        // product per vector (3 m_u² multiply–adds, about ten products a step) instead of
        // forming it (two triangular solves with m_u right-hand sides, m_u³); Padé needs it
        // formed.
        let w1 = match self.exponential {
            Exponential::Krylov(tol) => {
                let mut x = Mat::<f64>::zeros(self.mu, 1);
                let mut apply = |v: &[f64], y: &mut [f64]| {
                    x.col_mut(0).iter_mut().zip(v).for_each(|(a, b)| *a = *b);
                    solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
                    let mut out = faer::MatMut::from_column_major_slice_mut(y, self.mu, 1);
                    matmul(out.as_mut(), Accum::Replace, k.as_ref(), x.as_ref(), 1.0, Par::Seq);
                    solve_lower_triangular_in_place(l.as_ref(), out, Par::Seq);
                };
                let (w1, kr) = expm_krylov("reduced advection", &mut apply, &w, dt, tol)
                    .map_err(|e| state_err(e.to_string()))?;
                report.krylov_products += kr.products;
                w1
            }
            Exponential::Pade => {
                let mut m = k;
                solve_lower_triangular_in_place(l.as_ref(), m.as_mut(), Par::Seq);
                let mut mt = m.transpose().to_owned();
                solve_lower_triangular_in_place(l.as_ref(), mt.as_mut(), Par::Seq);
                let m = mt.transpose().to_owned();
                let e = crate::tensor::expm_faer("reduced advection", &(m * faer::Scale(dt)))
                    .map_err(|e| state_err(e.to_string()))?;
                (0..self.mu).map(|i| (0..self.mu).map(|j| e[(i, j)] * w[j]).sum()).collect()
            }
        };
        report.energy[1] = half_square(&w1);
        // u' = L⁻ᵀ w'.
        let mut x = Mat::from_fn(self.mu, 1, |i, _| w1[i]);
        solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
        report.exponential_seconds += t2.elapsed().as_secs_f64();
        let u1: Vec<f64> = (0..self.mu).map(|i| x[(i, 0)]).collect();
        if u1.iter().any(|v| !v.is_finite()) {
            return Err(state_err("reduced advection: the velocity is not finite".into()));
        }
        Ok(u1)
    }

    /// The reduced projection (Eq. 12) of `u` at geometry `g` with induced flux `h`, and the
    /// conversion to velocity (stages 3–4): returns (û, f̂).
    pub fn project(
        &self,
        u: &[f64],
        g: &[f64],
        h: &[f64],
        report: &mut ReducedStepReport,
    ) -> Result<(Vec<f64>, Vec<f64>), FluidError> {
        let t1 = Instant::now();
        let l = self.volume_factor(g, "V̂(ĝ_{t+1})")?;
        report.volume_seconds += t1.elapsed().as_secs_f64();
        let t = Instant::now();
        let p = self.flux_to_momentum(g);
        // Y = L⁻¹ P, so Pᵀ V̂⁻¹ P = YᵀY.
        let mut y = p.clone();
        solve_lower_triangular_in_place(l.as_ref(), y.as_mut(), Par::Seq);
        let n = match &self.exact {
            // M(g), the flux modes' velocities' Gram matrix in the full space.
            Some(exact) => exact.gram(g)?,
            None => {
                let mut n = Mat::<f64>::zeros(self.mf, self.mf);
                matmul(n.as_mut(), Accum::Replace, y.transpose(), y.as_ref(), 1.0, Par::Seq);
                n
            }
        };
        let uc = Mat::from_fn(self.mu, 1, |i, _| u[i]);
        let rhs = p.transpose() * &uc;
        // f̂ = f̂_c + W y: f̂_c meets the boundary constraint, W spans the free directions
        // (the constraint's null space, or the part of it the velocity basis sees).
        let target = self.constraint.as_ref().map(|con| match &con.dh {
            Some(dh) if self.mh > 0 => dh * Mat::from_fn(self.mh, 1, |i, _| h[i]),
            _ => Mat::zeros(con.d.nrows(), 1),
        });
        let fc = match (&self.constraint, &target) {
            (Some(con), Some(target)) => &con.pinv * target,
            _ => Mat::zeros(self.mf, 1),
        };
        let free = self.seen_flux.as_deref().or(self.constraint.as_ref().map(|c| &c.null));
        let f = match free {
            None => {
                let c = cholesky(&n, "the reduced projection PᵀV̂⁻¹P (basis f)")?;
                cholesky_solve(&c, &rhs)
            }
            Some(w) if w.ncols() > 0 => {
                let nz = w.transpose() * &n * w;
                let bz = w.transpose() * (&rhs - &n * &fc);
                let c = cholesky(&nz, "the reduced projection Zᵀ PᵀV̂⁻¹P Z (basis f, constrained)")?;
                &fc + w * cholesky_solve(&c, &bz)
            }
            Some(_) => fc,
        };
        if let (Some(con), Some(target)) = (&self.constraint, &target) {
            let r = &con.d * &f - target;
            let norm = |m: &Mat<f64>| (0..m.nrows()).map(|i| m[(i, 0)].powi(2)).sum::<f64>().sqrt();
            report.constraint_residual = norm(&r);
            report.constraint_target = norm(target);
        }
        // û = L⁻ᵀ (Y f), and Y f = Lᵀû gives its energy.
        let mut x = &y * &f;
        report.energy[2] = 0.5 * (0..x.nrows()).map(|i| x[(i, 0)].powi(2)).sum::<f64>();
        solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
        report.projection_seconds += t.elapsed().as_secs_f64();
        let u1: Vec<f64> = (0..self.mu).map(|i| x[(i, 0)]).collect();
        let f1: Vec<f64> = (0..self.mf).map(|i| f[(i, 0)]).collect();
        if u1.iter().chain(&f1).any(|v| !v.is_finite()) {
            return Err(state_err("reduced projection: the result is not finite".into()));
        }
        Ok((u1, f1))
    }

    /// One reduced frame from `s` (at ĝ_t) to ĝ_{t+1} = `g_next` with reduced induced flux `h`
    /// (Fig. 2 right).
    pub fn step(
        &self,
        s: &ReducedState,
        g_next: &[f64],
        h: &[f64],
    ) -> Result<(ReducedState, ReducedStepReport), FluidError> {
        self.check(s, g_next, h)?;
        let start = Instant::now();
        let mut report = ReducedStepReport::default();
        // V̂(ĝ_{t+1}) is contracted and factorised on the other core while advection runs.
        let (u1, next) = rayon::join(
            || self.advect(&s.u, &s.f, &s.g, h, self.frame_time, &mut report),
            || {
                let t = Instant::now();
                let l = cholesky(&self.volume_matrix(g_next), "V̂(ĝ_{t+1})");
                (l, t.elapsed().as_secs_f64())
            },
        );
        let u1 = u1?;
        let (l1, seconds) = next;
        report.volume_seconds += seconds;
        if let Ok(mut cache) = self.factor.0.lock() {
            *cache = Some((g_next.to_vec(), l1?));
        }
        let (u, f) = self.project(&u1, g_next, h, &mut report)?;
        report.seconds = start.elapsed().as_secs_f64();
        Ok((ReducedState { u, f, g: g_next.to_vec() }, report))
    }

    /// The reduced velocity of a flux: `V̂⁻¹(ĝ)(P̂ ⊗₂ ĝ) f̂`.
    pub fn flux_to_velocity(&self, f: &[f64], g: &[f64]) -> Result<Vec<f64>, FluidError> {
        let l = self.volume_factor(g, "V̂(ĝ)")?;
        let p = self.flux_to_momentum(g);
        let mut x = &p * Mat::from_fn(self.mf, 1, |i, _| f[i]);
        solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
        solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
        Ok((0..self.mu).map(|i| x[(i, 0)]).collect())
    }

    /// The energy-norm projection of a full velocity (§7.1 footnote 2, with the reduced
    /// volume matrix): `r = V̂(ĝ)⁻¹ B_uᵀ p` for the momentum `p = V(g) u`.
    pub fn project_velocity(&self, momentum_reduced: &[f64], g: &[f64]) -> Result<Vec<f64>, FluidError> {
        let l = self.volume_factor(g, "V̂(ĝ)")?;
        let mut x = Mat::from_fn(self.mu, 1, |i, _| momentum_reduced[i]);
        solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
        solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
        Ok((0..self.mu).map(|i| x[(i, 0)]).collect())
    }
}

fn prepare_constraint(d: Mat<f64>, dh: Option<Mat<f64>>) -> Result<Constraint, FluidError> {
    let (md, mf) = (d.nrows(), d.ncols());
    let svd = d.svd().map_err(|e| state_err(format!("SVD of D̂ failed: {e:?}")))?;
    let s = svd.S().column_vector();
    let smax = (0..s.nrows()).map(|i| s[i]).fold(1.0f64, f64::max);
    let rank = (0..s.nrows()).filter(|&i| s[i] > CONSTRAINT_SVD_TOLERANCE * smax).count();
    let (u, v) = (svd.U(), svd.V());
    let pinv = Mat::from_fn(mf, md, |i, j| (0..rank).map(|k| v[(i, k)] * u[(j, k)] / s[k]).sum());
    let null = Mat::from_fn(mf, mf - rank, |i, j| v[(i, rank + j)]);
    Ok(Constraint { pinv, null, d, dh })
}

#[cfg(test)]
mod tests {
    use super::super::induced::sorted_tuples;
    use super::*;

    /// m_u = 2, m_f = 2, m_g = 1 (2D), no constraint: V̂(ĝ) = ĝ² I, P̂ ⊗ ĝ = ĝ `p` (row-major).
    fn two_mode_fluid(p: [f64; 4]) -> ReducedFluid {
        let (mu, mf, mg) = (2, 2, 1);
        ReducedFluid {
            dim: 2,
            mu,
            mf,
            mg,
            mh: 0,
            viscosity: 0.0,
            frame_time: 0.1,
            a: vec![0.0; mu * (mu - 1) / 2 * mf],
            a_skew: true,
            ah: Vec::new(),
            lap: vec![0.0; mu * mu],
            p: p.to_vec(),
            v: vec![1.0, 0.0, 1.0],
            monomials: sorted_tuples(mg, 2),
            induced: Vec::new(),
            induced_monomials: Vec::new(),
            bf_bh: None,
            constraint: None,
            combination: FluxCombination::Separate,
            exponential: Exponential::default(),
            exact: None,
            seen_flux: None,
            seen_report: None,
            factor: FactorCache::default(),
        }
    }

    /// Flux mode 2 carries unit velocity energy in the full space (M = I) but only 10⁻⁴ of it
    /// inside B_u (N = diag(1, 10⁻⁴), P̂ = diag(1, 10⁻²)): the unnarrowed projection gives it
    /// coefficient 1 to make a velocity component of 10⁻²; narrowed at 0.1 it keeps mode 1
    /// only (coefficient 0 on mode 2, mode 1's coefficient unchanged), and at 0 both, as
    /// without narrowing. The kept fractions are the generalized eigenvalues, 10⁻⁴ and 1.
    #[test]
    fn the_projection_leaves_out_flux_directions_the_velocity_basis_barely_sees() {
        let fluid = two_mode_fluid([1.0, 0.0, 0.0, 1e-2]);
        let tensor = |d: [f64; 4]| crate::tensor::Tensor::from_vec(&[2, 2], d.to_vec()).unwrap();
        let grams =
            FluxVelocityGrams { full: tensor([1.0, 0.0, 0.0, 1.0]), seen: tensor([1.0, 0.0, 0.0, 1e-4]) };
        let (u, g) = ([1.0, 1e-2], [1.0]);
        let mut report = ReducedStepReport::default();
        let (_, f_all) = fluid.project(&u, &g, &[], &mut report).unwrap();
        assert!((f_all[0] - 1.0).abs() < 1e-12 && (f_all[1] - 1.0).abs() < 1e-9, "{f_all:?}");
        let narrowed = fluid.clone().with_seen_flux(&grams, 0.1).unwrap();
        let seen = narrowed.seen_flux().unwrap();
        assert_eq!((seen.kept, seen.of()), (1, 2));
        assert!((seen.fractions[0] - 1e-4).abs() < 1e-15 && (seen.fractions[1] - 1.0).abs() < 1e-15);
        let (u1, f) = narrowed.project(&u, &g, &[], &mut report).unwrap();
        assert!((f[0] - 1.0).abs() < 1e-12 && f[1].abs() < 1e-12, "{f:?}");
        assert!(narrowed.energy(&u1, &g) <= narrowed.energy(&u, &g));
        let all = fluid.clone().with_seen_flux(&grams, 0.0).unwrap();
        let (_, f0) = all.project(&u, &g, &[], &mut report).unwrap();
        assert!(f0.iter().zip(&f_all).all(|(a, b)| (a - b).abs() < 1e-9), "{f0:?} vs {f_all:?}");
        // Matrices of another flux basis, or a threshold outside [0, 1], are refused.
        let small = FluxVelocityGrams {
            full: crate::tensor::Tensor::from_vec(&[1, 1], vec![1.0]).unwrap(),
            seen: crate::tensor::Tensor::from_vec(&[1, 1], vec![1.0]).unwrap(),
        };
        assert!(fluid.clone().with_seen_flux(&small, 0.1).unwrap_err().to_string().contains("2 modes"));
        assert!(fluid.clone().with_seen_flux(&grams, 1.5).unwrap_err().to_string().contains("0 to 1"));
    }

    /// A flux basis whose two columns carry the same momentum makes the reduced projection's
    /// normal matrix singular: refused naming the flux basis, not solved into NaN.
    #[test]
    fn a_singular_reduced_projection_is_refused_naming_the_flux_basis() {
        // m_u = 2, m_f = 2, m_g = 1 (2D): V̂(ĝ) = ĝ² I, P̂ ⊗ ĝ = ĝ [[1, 1], [0, 0]].
        let fluid = two_mode_fluid([1.0, 1.0, 0.0, 0.0]);
        let state = ReducedState { u: vec![1.0, 0.5], f: vec![0.0, 0.0], g: vec![1.0] };
        let err = fluid.step(&state, &[1.0], &[]).unwrap_err().to_string();
        assert!(err.contains("reduced projection") && err.contains("basis f"), "{err}");
    }
}
