//! The reduced radiosity's error estimate and trust check (issue 53; seed 000 §8.2–8.3,
//! Eq. 16–17).
//!
//! **Where the error comes from.** The reduced radiosity solves `M̂ b̂ = ê` in the span of
//! `B_b`, with `M̂` Table 2's reduced operator corrected at the training configurations and
//! blended between them by Eq. 17's weights `x` ([`super::operator_correction`]). Its error
//! against the full solve has two parts: radiosity `B_b` cannot hold (the basis's floor,
//! `‖b − B_b B_bᵀ b‖`), and the reduced operator's error away from the training
//! configurations, where the blended correction and the learned visibility only interpolate.
//! Measured on the small scene with 40 samples (tests/radiosity_estimate.rs), the second
//! dominates: 1.1–4.3 % true error where the floor is 0.4–0.8 %.
//!
//! **Why not the residual.** Reduced-basis practice estimates the error from the full
//! equation's residual at the lifted solution, `R = e − (I − ρF) B_b b̂`, decomposed
//! offline/online where `F` is affine in the parameters. Here the only affine form of `F` at
//! run time is the chain's own, `F̃ = F(B_p p̂)`: a residual against it cannot see the chain's
//! error, which is the dominant part, and misses the exact near field the model is trained
//! for (`ΔF_t` exists only at the training configurations). Built and measured (the Gram
//! matrix of `[e | B_b | E ⊗₁ B_b ⊗₂ B_p]`, exact to 1e-9): on centroid models it
//! overestimated 1.7–4.5×, on exact-near-field models it read 6–7 % at every configuration
//! whatever the true error (1.1–4.3 %) — the near field's own residual. So the estimate is
//! a cross-validated one instead, whose online cost is a few dozen multiply–adds.
//!
//! **The estimate.** Training evaluates every sample `t` with itself left out of Eq. 17
//! (its geometry's weights over the other samples, so its visibility and its operator
//! correction are interpolated as at a configuration never trained on) and records that
//! error against its own full solve, `ε_t`, beside the basis's floor there, `φ_t`, and the
//! distance in reduced geometry from `ĝ_t` to its nearest other sample, `h_t`. At run time,
//!
//! ```text
//! η(ĝ) = Σ_t x_t [ φ_t + ε_t · min(2, √(‖ĝ − ĝ_t‖ / h_t)) ]
//! ```
//!
//! — the blended samples' left-out errors, scaled by how far `ĝ` is from each relative to the
//! samples' spacing (the interpolation error grows from the floor at a sample to the
//! left-out error a spacing away, and on beyond it up to twice that), over the receiving
//! surfaces. The scaling is measured, not derived: of the forms compared on 1,000 random
//! configurations of the small scene (`examples/radiosity_estimate_study.rs`), `min(1, d/h)`
//! had 6 below the band's 0.5 and `d/h` uncapped one above its 10; this one had neither above
//! and one below (0.39). Its cost is `O(K m_g)` for
//! the `K` samples Eq. 17 weights, independent of the face count. It is an indicator, not a
//! bound: its effectivity (estimate ÷ true error) is validated on configurations drawn at
//! random from a seed unrelated to training (tests/radiosity_estimate.rs, `radiosity
//! compare --random`, BENCHMARKS.md).
//!
//! **Trust.** A configuration is untrusted when the reduced operator's margin (the least real
//! part of `M̂`'s eigenvalues; the full operator's is at least `1 − ρ_max > 0`) is not
//! positive, or its estimate exceeds the threshold the user chose ([`DEFAULT_THRESHOLD`]).

use faer::Mat;

use super::error::RadiosityError;
use crate::tensor::Tensor;

/// The estimated relative error above which a configuration is reported untrusted by default
/// (receiving surfaces; `--trust-threshold`).
pub const DEFAULT_THRESHOLD: f64 = 0.05;

/// What training measured for the estimate, per training configuration (see the module
/// documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct CrossValidation {
    /// `ε_t`: the relative error over the receiving surfaces at sample `t` with `t` left out of
    /// Eq. 17.
    pub left_out: Vec<f64>,
    /// `φ_t`: the radiosity basis's floor at `t`, `‖b_t − B_b B_bᵀ b_t‖ / ‖b_t‖` over the
    /// receiving surfaces.
    pub floor: Vec<f64>,
    /// `h_t`: the distance from `ĝ_t` to the nearest other sample's reduced geometry.
    pub spacing: Vec<f64>,
}

impl CrossValidation {
    /// Checks the three series: one value per sample each, finite and not negative.
    pub fn new(left_out: Vec<f64>, floor: Vec<f64>, spacing: Vec<f64>) -> Result<Self, String> {
        let t = left_out.len();
        if floor.len() != t || spacing.len() != t || t == 0 {
            return Err(format!(
                "the error estimate's series have {t}, {} and {} values; one per sample each, at least one",
                floor.len(),
                spacing.len()
            ));
        }
        for (name, series) in
            [("left_out_error", &left_out), ("basis_floor", &floor), ("sample_spacing", &spacing)]
        {
            if let Some((k, v)) = series.iter().enumerate().find(|(_, v)| !(v.is_finite() && **v >= 0.0)) {
                return Err(format!("{name}[{k}] is {v}: expected a finite value ≥ 0"));
            }
        }
        Ok(Self { left_out, floor, spacing })
    }

    /// Number of samples.
    pub fn samples(&self) -> usize {
        self.left_out.len()
    }

    /// The median left-out error (for the training log).
    pub fn median_left_out(&self) -> f64 {
        let mut v = self.left_out.clone();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    /// `η(ĝ)` of the module documentation, for reduced geometry `ghat`, Eq. 17's weights `x`
    /// and the samples' reduced geometries `geometry` (`B_gᵀ G`, `m_g × T`).
    pub fn estimate(&self, ghat: &[f64], x: &[f64], geometry: &Tensor) -> f64 {
        let (m, t) = (geometry.shape()[0], geometry.shape()[1]);
        let g = geometry.data();
        let mut eta = 0.0;
        for (s, &w) in x.iter().enumerate().take(t.min(self.samples())) {
            if w == 0.0 {
                continue;
            }
            let distance = (0..m).map(|i| (ghat[i] - g[i * t + s]).powi(2)).sum::<f64>().sqrt();
            let reach =
                if self.spacing[s] > 0.0 { (distance / self.spacing[s]).sqrt().min(2.0) } else { 1.0 };
            eta += w * (self.floor[s] + self.left_out[s] * reach);
        }
        eta
    }
}

/// The distance from each sample's reduced geometry to its nearest other sample's (`B_gᵀ G`,
/// `m_g × T`); 0 for a lone sample.
pub fn sample_spacing(geometry: &Tensor) -> Vec<f64> {
    let (m, t) = (geometry.shape()[0], geometry.shape()[1]);
    let g = geometry.data();
    (0..t)
        .map(|s| {
            let nearest = (0..t)
                .filter(|&r| r != s)
                .map(|r| (0..m).map(|i| (g[i * t + s] - g[i * t + r]).powi(2)).sum::<f64>())
                .fold(f64::INFINITY, f64::min);
            if nearest.is_finite() {
                nearest.sqrt()
            } else {
                0.0
            }
        })
        .collect()
}

/// What the estimate and the stability check found at one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The estimated relative error over the receiving surfaces (`NaN` for a model trained
    /// without the estimate).
    pub error: f64,
    /// `σ_min(M̂)`, the reduced operator's least singular value.
    pub stability: f64,
    /// The least real part of `M̂`'s eigenvalues.
    pub margin: f64,
}

impl Estimate {
    /// Why this configuration is not to be trusted at `threshold` (estimated relative error),
    /// or `None`.
    pub fn untrusted(&self, threshold: f64) -> Option<String> {
        if self.margin.is_nan() || self.margin <= 0.0 {
            return Some(format!(
                "the reduced operator has left the physics (its least eigenvalue's real part is {:.3}; the full operator's is positive)",
                self.margin
            ));
        }
        if self.error > threshold {
            return Some(format!(
                "the estimated error {:.1} % is above the threshold {:.1} %",
                100.0 * self.error,
                100.0 * threshold
            ));
        }
        None
    }
}

/// `σ_min` and the least real part of the eigenvalues of a square row-major `operator`.
pub fn stability(operator: &Tensor) -> Result<(f64, f64), RadiosityError> {
    let m = operator.shape()[0];
    let a = Mat::<f64>::from_fn(m, m, |i, j| operator.data()[i * m + j]);
    let fail = |what: &str, e: String| RadiosityError::Solve(format!("the reduced operator's {what}: {e}"));
    let sigma = a.singular_values().map_err(|e| fail("singular values", format!("{e:?}")))?;
    let values = a.eigenvalues().map_err(|e| fail("eigenvalues", format!("{e:?}")))?;
    Ok((
        sigma.iter().copied().fold(f64::INFINITY, f64::min),
        values.iter().map(|z| z.re).fold(f64::INFINITY, f64::min),
    ))
}
