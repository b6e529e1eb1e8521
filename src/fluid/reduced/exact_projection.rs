//! The reduced projection's normal matrix computed in the full space: `M(g) = (V⁻¹P B_f)ᵀ V
//! (V⁻¹P B_f) = B_fᵀ Pᵀ(g) V(g)⁻¹ P(g) B_f`, the energy Gram matrix of the velocities of the
//! flux modes, in place of its Galerkin image `P̂ᵀV̂⁻¹P̂` (seed 000 Eq. 12 as reduced in §6.2).
//!
//! Why: Eq. 12 projects the advected velocity onto the velocities of the flux modes in the
//! energy norm. Reduced with `V̂ = B_uᵀVB_u`, a flux mode's velocity is seen only through its
//! image in `B_u`, so `P̂ᵀV̂⁻¹P̂ ≤ M` (the gap is the part of each mode's velocity outside `B_u`):
//! modes whose velocity leaves `B_u` look cheaper than they are, and the projection leans on
//! them every step. With `M`, the projection is the exact energy projection of the lifted
//! advected velocity `B_u û'` onto the flux modes' velocities, so the energy argument of §A
//! holds as before (`½ f̂ᵀP̂ᵀV̂⁻¹P̂ f̂ ≤ ½ f̂ᵀM f̂ = ½‖Π_Q B_u û'‖²_V ≤ ½ û'ᵀV̂û'` without
//! induced flux). Measured effect on the tunnel's held-out obstacle and the cavity:
//! BENCHMARKS.md.
//!
//! `M` is not polynomial in ĝ (V⁻¹ is a cell-wise reciprocal of the volumes), so it is not a
//! premultiplied tensor: it is computed from the lifted geometry `B_g ĝ` (m_f full momentum
//! fields, `O(m_f² d N)`), once per distinct ĝ and kept — once per run on a mesh that does not
//! move (the tunnel, any static scene), every frame on a moving one, at full-space cost.

use std::sync::Mutex;

use faer::Mat;

use crate::fluid::operators::CellOperators;
use crate::fluid::FluidError;
use crate::mesh::{SimplexMesh, Topology};
use crate::reduce::Basis;

use super::model::ReducedFluidModel;

/// The full-space normal matrix of the reduced projection (see the module docs).
pub struct ExactProjection {
    mesh: SimplexMesh,
    topo: Topology,
    bf: Basis,
    bg: Basis,
    /// The last ĝ and its `M`.
    cache: Mutex<Option<(Vec<f64>, Mat<f64>)>>,
    /// How many times `M` was computed.
    computed: Mutex<usize>,
}

impl std::fmt::Debug for ExactProjection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ExactProjection(m_f {})", self.bf.reduced_dim())
    }
}

impl ExactProjection {
    /// Prepares `M(g)` for `model`'s mesh and bases.
    pub fn new(model: &ReducedFluidModel) -> Result<Self, FluidError> {
        let basis = |n: &str| {
            model.basis(n).cloned().ok_or_else(|| FluidError::State(format!("the model has no basis {n}")))
        };
        let (mesh, topo) = model.mesh_and_topology()?;
        Ok(Self {
            mesh,
            topo,
            bf: basis("f")?,
            bg: basis("g")?,
            cache: Mutex::new(None),
            computed: Mutex::new(0),
        })
    }

    /// How many times `M` has been computed (a static mesh: once).
    pub fn computed(&self) -> usize {
        self.computed.lock().map_or(0, |c| *c)
    }

    /// `M(B_g ĝ)` (m_f × m_f), from the cache when ĝ is the last one asked for.
    pub fn gram(&self, g_hat: &[f64]) -> Result<Mat<f64>, FluidError> {
        if let Ok(cache) = self.cache.lock() {
            if let Some((g, m)) = cache.as_ref() {
                if g.as_slice() == g_hat {
                    return Ok(m.clone());
                }
            }
        }
        let m = self.gram_of_geometry(&self.bg.lift(g_hat))?;
        if let Ok(mut cache) = self.cache.lock() {
            *cache = Some((g_hat.to_vec(), m.clone()));
        }
        if let Ok(mut c) = self.computed.lock() {
            *c += 1;
        }
        Ok(m)
    }

    /// `M(g)` (m_f × m_f) at a full-space geometry `g` (vertex positions).
    pub fn gram_of_geometry(&self, g: &[f64]) -> Result<Mat<f64>, FluidError> {
        let ops = CellOperators::new(&self.mesh, &self.topo, g);
        crate::mesh::refuse_inverted(&ops.volumes, None)?;
        Ok(self.gram_of_momenta(&self.flux_momenta(&ops), &ops.volumes))
    }

    /// The flux modes' momenta `P(g) B_f` (d·cells × m_f) under the operators `ops`.
    fn flux_momenta(&self, ops: &CellOperators) -> Mat<f64> {
        let mf = self.bf.reduced_dim();
        let mut p = Mat::<f64>::zeros(self.mesh.dim() * ops.volumes.len(), mf);
        for j in 0..mf {
            let mut e = vec![0.0; mf];
            e[j] = 1.0;
            for (i, x) in ops.flux_to_momentum(&self.topo, &self.bf.lift(&e)).iter().enumerate() {
                p[(i, j)] = *x;
            }
        }
        p
    }

    /// `M = Pᵀ V⁻¹ P` of the momenta `p` (from [`Self::flux_momenta`]) with cell volumes
    /// `volumes`: `ΣᵀΣ` with `Σ = V^{-1/2} P`.
    fn gram_of_momenta(&self, p: &Mat<f64>, volumes: &[f64]) -> Mat<f64> {
        let d = self.mesh.dim();
        let sigma = Mat::from_fn(p.nrows(), p.ncols(), |i, j| p[(i, j)] / volumes[i / d].sqrt());
        sigma.transpose() * &sigma
    }
}

/// How much of each flux direction's velocity the velocity basis sees, measured on full-space
/// geometries at training: the mean over the geometries `g_k` of `M(g_k)` (the flux modes'
/// velocity Gram matrix, [`ExactProjection`]) and of its part inside `B_u`,
/// `N(g_k) = Qᵀ V̂(g_k)⁻¹ Q` with `Q = B_uᵀ P(g_k) B_f` and `V̂(g_k) = B_uᵀ V(g_k) B_u` — the
/// Gram matrix the reduced projection `P̂ᵀV̂⁻¹P̂` stands for. Both m_f × m_f; `N ≤ M`.
///
/// The generalized eigenvalues of `(N, M)` lie in [0, 1]: the fraction of a flux direction's
/// velocity energy inside `B_u`. A direction with a small one is one the reduced projection
/// cannot identify from a velocity in `B_u`, and the step narrows its projection to the
/// others ([`super::step::ReducedFluid::with_seen_flux`]; why: docs/fluids.md, "Flux
/// directions the velocity basis sees").
#[derive(Clone, Debug, PartialEq)]
pub struct FluxVelocityGrams {
    /// `M`, m_f × m_f.
    pub full: crate::tensor::Tensor,
    /// `N`, m_f × m_f.
    pub seen: crate::tensor::Tensor,
}

impl FluxVelocityGrams {
    /// Measures both matrices on the full-space geometries `geometries` (each the mesh's
    /// vertex positions, with a name for errors) for `model`'s bases.
    pub fn measure(model: &ReducedFluidModel, geometries: &[(String, Vec<f64>)]) -> Result<Self, FluidError> {
        let (m, n) = Self::grams(model, geometries)?;
        let mf = m.nrows();
        let tensor = |a: &Mat<f64>| {
            crate::tensor::Tensor::from_vec(
                &[mf, mf],
                (0..mf * mf).map(|k| 0.5 * (a[(k / mf, k % mf)] + a[(k % mf, k / mf)])).collect(),
            )
            .map_err(|e| FluidError::State(e.to_string()))
        };
        Ok(Self { full: tensor(&m)?, seen: tensor(&n)? })
    }

    /// `M` and `N` as matrices.
    pub fn matrices(&self) -> (Mat<f64>, Mat<f64>) {
        let mat = |t: &crate::tensor::Tensor| {
            let n = t.shape()[0];
            Mat::from_fn(n, n, |i, j| t.data()[i * n + j])
        };
        (mat(&self.full), mat(&self.seen))
    }

    /// The leading `m_f × m_f` blocks (the flux basis cut to its first `m_f` modes, the
    /// velocity basis unchanged).
    pub fn leading(&self, m_f: usize) -> Result<Self, FluidError> {
        let cut =
            |t: &crate::tensor::Tensor| t.leading(&[m_f, m_f]).map_err(|e| FluidError::State(e.to_string()));
        Ok(Self { full: cut(&self.full)?, seen: cut(&self.seen)? })
    }

    /// The mean over `geometries` of `M(g)` and of its part inside `B_u`, `Qᵀ V̂(g)⁻¹ Q`.
    fn grams(
        model: &ReducedFluidModel,
        geometries: &[(String, Vec<f64>)],
    ) -> Result<(Mat<f64>, Mat<f64>), FluidError> {
        use faer::linalg::matmul::matmul;
        use faer::{Accum, MatRef, Par};
        if geometries.is_empty() {
            return Err(FluidError::State(
                "the flux velocity Gram matrices need at least one geometry".into(),
            ));
        }
        let exact = ExactProjection::new(model)?;
        let bu = model.basis("u").ok_or_else(|| FluidError::State("the model has no basis u".into()))?;
        let (rows, mu) = (bu.full_dim(), bu.reduced_dim());
        let bu = MatRef::from_row_major_slice(bu.matrix().data(), rows, mu);
        let (mf, d) = (exact.bf.reduced_dim(), exact.mesh.dim());
        let mut m_mean = Mat::<f64>::zeros(mf, mf);
        let mut n_mean = Mat::<f64>::zeros(mf, mf);
        for (name, g) in geometries {
            let ops = CellOperators::new(&exact.mesh, &exact.topo, g);
            crate::mesh::refuse_inverted(&ops.volumes, None)
                .map_err(|e| FluidError::State(format!("the flux velocities at {name}: {e}")))?;
            if ops.volumes.len() * d != rows {
                return Err(FluidError::State(format!(
                    "the flux velocity Gram matrices: B_u has {rows} rows, the mesh {} velocity values",
                    ops.volumes.len() * d
                )));
            }
            // M = Pᵀ V⁻¹ P of the flux modes' momenta P = P(g) B_f; Q = B_uᵀ P; V̂ = B_uᵀ V B_u.
            let p = exact.flux_momenta(&ops);
            let m = exact.gram_of_momenta(&p, &ops.volumes);
            let v_bu = Mat::from_fn(rows, mu, |i, j| bu[(i, j)] * ops.volumes[i / d]);
            let mut q = Mat::<f64>::zeros(mu, mf);
            matmul(q.as_mut(), Accum::Replace, bu.transpose(), p.as_ref(), 1.0, Par::rayon(0));
            let mut vhat = Mat::<f64>::zeros(mu, mu);
            matmul(vhat.as_mut(), Accum::Replace, bu.transpose(), v_bu.as_ref(), 1.0, Par::rayon(0));
            let l = super::dense::cholesky(&vhat, "V̂(g) of the flux velocity Gram matrices")?;
            // N = Qᵀ V̂⁻¹ Q = YᵀY with Y = L⁻¹Q.
            let mut y = q;
            faer::linalg::triangular_solve::solve_lower_triangular_in_place(l.as_ref(), y.as_mut(), Par::Seq);
            let n = y.transpose() * &y;
            m_mean += m * faer::Scale(1.0 / geometries.len() as f64);
            n_mean += n * faer::Scale(1.0 / geometries.len() as f64);
        }
        Ok((m_mean, n_mean))
    }
}
