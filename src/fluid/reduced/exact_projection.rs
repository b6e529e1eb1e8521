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
        let g = self.bg.lift(g_hat);
        let ops = CellOperators::new(&self.mesh, &self.topo, &g);
        crate::mesh::refuse_inverted(&ops.volumes, None)?;
        let mf = self.bf.reduced_dim();
        let d = self.mesh.dim();
        // Column j: flux mode j's momentum P B_f e_j scaled by V^{-1/2}, so that M = ΣᵀΣ.
        let scale: Vec<f64> = ops.volumes.iter().map(|v| v.sqrt().recip()).collect();
        let mut sigma = Mat::<f64>::zeros(d * ops.volumes.len(), mf);
        for j in 0..mf {
            let mut e = vec![0.0; mf];
            e[j] = 1.0;
            let p = ops.flux_to_momentum(&self.topo, &self.bf.lift(&e));
            for (i, x) in p.iter().enumerate() {
                sigma[(i, j)] = x * scale[i / d];
            }
        }
        let m = sigma.transpose() * &sigma;
        if let Ok(mut cache) = self.cache.lock() {
            *cache = Some((g_hat.to_vec(), m.clone()));
        }
        if let Ok(mut c) = self.computed.lock() {
            *c += 1;
        }
        Ok(m)
    }
}
