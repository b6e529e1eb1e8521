//! The reduced operator corrected at the training configurations (issue 28; seed 000 §8.2–8.3,
//! Eq. 16, Table 2).
//!
//! Eq. 16 inverts the reduced operator `M̂ = Î − Ê ⊗₂ p̂`, where `p̂` are Table 2's reduced
//! form factors. Lifted, `Ê ⊗₂ p̂ = B_bᵀ ρ F̃ B_b` with `F̃ = B_p p̂` the chain's form factors,
//! so `M̂` *is* the Galerkin projection of `I − ρF̃` on `B_b`. But the chain's truncated
//! bases and its reduced inverse square root (§4.2) leave `F̃` a little off the true `F`:
//! measured on the 496-face scene, `M̂` is 0.5 % (Frobenius) off the exact projection
//! `B_bᵀ (I − ρF) B_b` at every configuration, training ones included, and since the
//! radiosity system amplifies operator errors by its conditioning, that 0.5 % is a 3 % error in
//! the radiosity — four times what `B_b` itself loses. At one corner of the paper-sized scene
//! the chain's operator even has a negative eigenvalue.
//!
//! The correction: at every training configuration `t` the exact projection is known (its
//! full solve's form factors `F_t` are regenerated from its geometry and visibility bits), so
//! training stores the chain's discrepancy there,
//!
//! ```text
//! Q̂[:, :, t] = B_bᵀ ρ F_t B_b − Ê ⊗₂ p̂(ĝ_t, v̂_t)        (m_b × m_b per configuration)
//! M̂(x) = Î − Ê ⊗₂ p̂ − Q̂ ⊗₂ x                             (x: Eq. 17's weights)
//! ```
//!
//! and the run time blends it with Eq. 17's weights `x` — the convex blend of training
//! configurations the learned visibility already computes. At a training configuration `x` is
//! its indicator and `M̂` is the exact projection; between them the correction is the blend of
//! the chain's errors at the nearest training configurations.
//!
//! **Why this is still a Galerkin projection.** Each slice is itself a projection:
//! `Q̂[:, :, t] = B_bᵀ ρ (F_t − F̃_t) B_b`, so `M̂(x) = B_bᵀ (I − ρ F̂(x)) B_b` with
//! `F̂(x) = F̃(x) + Σₜ xₜ (F_t − F̃_t)`: the projection of the operator whose form factors
//! are the chain's, corrected by the blend of its errors at the training configurations. The
//! radiosity is solved in the span of `B_b` as before. `x` has the identity basis (its axis is
//! never truncated).
//!
//! The training solves' form factors include the exact near field when training asks for it
//! ([`super::near_correction`]), so the correction carries the exact near field into the model
//! too. `Q̂` is `m_b² × T` (0.2 MB at `m_b` 20, 540 configurations); computing it costs one
//! regeneration of each configuration's `F` and a product `F B_b` — no premultiplication.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

use super::chain::reflection;
use super::error::RadiosityError;
use super::form_factor::{unoccluded_form_factor, FormFactors, NearField};
use super::near_correction::apply;
use super::solve::Rgb;
use super::train::Configuration;
use super::visibility::LearnedVisibility;
use crate::reduce::{Communicator, ReducedModel};
use crate::tensor::Tensor;

/// The form factors configuration `c`'s training solve used: centroid form factors under
/// `near` where its visibility bit is set (the bits were taken from `F > 0`), plus its
/// near-field correction.
pub fn training_form_factors(c: &Configuration, near: NearField) -> FormFactors {
    let g = &c.geometry;
    let n = g.areas.len();
    let mut values = vec![0.0; n * n];
    values.par_chunks_mut(n.max(1)).enumerate().for_each(|(i, row)| {
        for (j, v) in row.iter_mut().enumerate() {
            if i != j && c.visible(n * i + j) {
                *v = unoccluded_form_factor(g, i, j, near);
            }
        }
    });
    let mut f = FormFactors { n, values };
    apply(&mut f, &c.near_correction, &g.areas);
    f
}

/// `B_bᵀ ρ F B_b` (`m × m`, row-major) for a radiosity basis `basis` (`3n × m`, the channels
/// stacked: row `c·n + i`) — the reflected part of the exact operator `I − ρF` projected on
/// `B_b`, channel by channel.
pub fn projected_reflection(f: &FormFactors, albedo: &[Rgb], basis: &Tensor) -> Vec<f64> {
    let n = f.n;
    let m = basis.shape()[1];
    let b = basis.data();
    // Y = F [B_0 B_1 B_2] (n × 3m), B_c the rows of channel c.
    let mut stacked = vec![0.0; n * 3 * m];
    for i in 0..n {
        for c in 0..3 {
            stacked[(i * 3 + c) * m..(i * 3 + c + 1) * m]
                .copy_from_slice(&b[(c * n + i) * m..(c * n + i + 1) * m]);
        }
    }
    let mut y = vec![0.0; n * 3 * m];
    matmul(
        MatMut::from_row_major_slice_mut(&mut y, n, 3 * m),
        Accum::Replace,
        MatRef::from_row_major_slice(&f.values, n, n),
        MatRef::from_row_major_slice(&stacked, n, 3 * m),
        1.0,
        Par::rayon(0),
    );
    // Σ_c B_cᵀ diag(ρ_c) Y_c.
    for i in 0..n {
        for c in 0..3 {
            let rho = albedo[i][c];
            for v in &mut y[(i * 3 + c) * m..(i * 3 + c + 1) * m] {
                *v *= rho;
            }
        }
    }
    let mut out = vec![0.0; m * m];
    matmul(
        MatMut::from_row_major_slice_mut(&mut out, m, m),
        Accum::Replace,
        MatRef::from_row_major_slice(&stacked, 3 * n, m).transpose(),
        MatRef::from_row_major_slice(&y, 3 * n, m),
        1.0,
        Par::rayon(0),
    );
    out
}

/// What the correction found at the training configurations.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CorrectionReport {
    /// Mean over the configurations of `‖Q̂_t‖ / ‖B_bᵀ (I − ρF_t) B_b‖` (Frobenius): how far
    /// the chain's reduced operator is from the exact projection before the correction.
    pub mean_discrepancy: f64,
    /// The largest such ratio.
    pub worst_discrepancy: f64,
    /// The configuration with the largest.
    pub worst_configuration: usize,
}

/// `Q̂` of the module documentation (`m_b × m_b × T`, row-major) for `model` (Table 2's
/// reduced tensors without a correction), its learned visibility and the training
/// `configurations` (faces of albedo `albedo`, centroid form factors under `near`).
/// Configurations are shared over `ranks` and summed in one allreduce; `progress` is called
/// with (configurations done, this rank's share).
pub fn operator_corrections(
    model: &ReducedModel,
    visibility: &LearnedVisibility,
    configurations: &[Configuration],
    albedo: &[Rgb],
    near: NearField,
    progress: &(dyn Fn(usize, usize) + Sync),
    ranks: &dyn Communicator,
) -> Result<(Tensor, CorrectionReport), RadiosityError> {
    let fail = |e: String| RadiosityError::Solve(format!("the operator correction: {e}"));
    let basis = model.basis("b").ok_or_else(|| fail("the model has no radiosity basis `b`".into()))?.matrix();
    let (m, t_count) = (basis.shape()[1], configurations.len());
    if let Some(c) = configurations.iter().find(|c| c.radiosity.len() * 3 != basis.shape()[0]) {
        return Err(fail(format!(
            "a configuration has {} faces, the radiosity basis {} rows",
            c.radiosity.len(),
            basis.shape()[0]
        )));
    }
    let chain = reflection();
    let mut q = vec![0.0; m * m * t_count];
    let mut ratios = vec![0.0; t_count];
    let share = ranks.share(t_count);
    for (done, t) in share.clone().enumerate() {
        let c = &configurations[t];
        let ghat = model.project_input("g", &c.g).map_err(|e| fail(e.to_string()))?;
        let (vhat, _) = visibility.predict(&ghat);
        let inputs = [("g", ghat.as_slice()), ("v", vhat.as_slice())].into();
        let reduced = model.evaluate_expression(&chain, &inputs).map_err(|e| fail(e.to_string()))?;
        let exact = projected_reflection(&training_form_factors(c, near), albedo, basis);
        let (mut num, mut den) = (0.0, 0.0);
        for a in 0..m {
            for b in 0..m {
                let k = a * m + b;
                let d = exact[k] - reduced.data()[k];
                q[k * t_count + t] = d;
                num += d * d;
                den += (f64::from(u8::from(a == b)) - exact[k]).powi(2);
            }
        }
        ratios[t] = (num / den.max(1e-300)).sqrt();
        progress(done + 1, share.len());
    }
    ranks.allreduce_sum(&mut q).map_err(|e| fail(e.to_string()))?;
    ranks.allreduce_sum(&mut ratios).map_err(|e| fail(e.to_string()))?;
    let (worst_configuration, worst) =
        ratios.iter().copied().enumerate().fold((0, 0.0f64), |w, (t, r)| if r > w.1 { (t, r) } else { w });
    let report = CorrectionReport {
        mean_discrepancy: ratios.iter().sum::<f64>() / t_count.max(1) as f64,
        worst_discrepancy: worst,
        worst_configuration,
    };
    let q = Tensor::from_vec(&[m, m, t_count], q).map_err(|e| fail(e.to_string()))?;
    Ok((q, report))
}
