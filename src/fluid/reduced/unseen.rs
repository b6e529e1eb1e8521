//! The **unseen-velocity indicator**: a per-frame error estimate of a reduced fluid run computed
//! from reduced quantities alone, `O(m_f²)` a step — cheap enough to run on every step (and in
//! the viewer), where the residual indicator ([`super::indicator`]) takes one full step per
//! measured step.
//!
//! A reduced state carries two descriptions of one velocity (seed 000 §6, Eq. 12 and stage 4
//! of [`super::step`]): the flux `f̂`, whose full-space velocity is `u_f = V⁻¹(P ⊗ g) B_f f̂`
//! (divergence-free, the velocity the next step advects with), and `û = V̂⁻¹(P̂ ⊗ ĝ) f̂`, which
//! lifts to `B_u û = Π u_f`, the V-orthogonal projection of `u_f` onto `B_u` (`P̂ ⊗ ĝ` is
//! `B_uᵀ P(B_g ĝ) B_f` exactly, P being linear in g). What the reduced velocity lacks of its own
//! flux's velocity is therefore a quadratic form in `f̂`:
//!
//! ```text
//! σ(f̂)² = ‖u_f − Π u_f‖²_V = f̂ᵀ (M − N) f̂,   M = B_fᵀPᵀV⁻¹PB_f,   N = QᵀV̂⁻¹Q,  Q = B_uᵀPB_f
//! ```
//!
//! with `M` and `N` the flux velocity Gram matrices training measured
//! ([`super::exact_projection::FluxVelocityGrams`]: their means over training geometries, so on
//! a moving mesh σ is evaluated with the mean matrices, not the current geometry's; `M − N ≥ 0`
//! at every geometry, so at their mean too).
//!
//! The estimate at frame t has the shape of the residual indicator's (a truncation felt once,
//! plus per-step errors carried forward, damped as the steps' advection and diffusion damp the
//! state, [`super::indicator::damping`]):
//!
//! ```text
//! η_t = ( σ(f̂_t) + Σ_{k ≤ t} (Π_{k < j ≤ t} λ_j) σ(f̂_k − f̂_{k−1}) ) / ‖B_u û_t‖_V
//! ```
//!
//! — the velocity the current flux carries outside `B_u`, plus, for every step, the velocity
//! outside `B_u` of the flux change that step made: what the reduced dynamics moved without
//! seeing it, which the run then advects with. It is an indicator, not a bound: it cannot see
//! an error made inside `B_u` by a flux the basis represents (with `M = N` it is 0). Its
//! effectivity (η ÷ true error) on the held-out tunnel, the small cavity's drive and the
//! bird's replay: BENCHMARKS.md, "Trusting a reduced fluid run".

use std::time::Instant;

use faer::Mat;

use crate::fluid::FluidError;

use super::exact_projection::FluxVelocityGrams;
use super::indicator::{damping, IndicatorFrame};
use super::model::ReducedFluidModel;
use super::run::ReducedRun;
use super::step::{ReducedFluid, ReducedState, ReducedStepReport};

/// The quadratic form `σ(f̂)² = f̂ᵀ(M − N)f̂` of the module docs.
#[derive(Clone, Debug)]
pub struct UnseenVelocity {
    /// `M − N`, symmetric positive semidefinite, m_f × m_f.
    gap: Mat<f64>,
}

impl UnseenVelocity {
    /// The form of `model`'s flux velocity Gram matrices; an error naming what to do for a
    /// model trained before they were measured.
    pub fn of_model(model: &ReducedFluidModel) -> Result<Self, FluidError> {
        let grams = model.flux_grams.as_ref().ok_or_else(|| {
            FluidError::State(
                "the unseen-velocity indicator needs the model's flux velocity Gram matrices, which models \
                 trained before they were measured lack: train the model again, or use the residual \
                 indicator (--indicator-every K)"
                    .into(),
            )
        })?;
        Self::new(grams)
    }

    /// The form `M − N` of `grams` (symmetrised).
    pub fn new(grams: &FluxVelocityGrams) -> Result<Self, FluidError> {
        let (m, n) = grams.matrices();
        let k = m.nrows();
        if m.ncols() != k || n.nrows() != k || n.ncols() != k {
            return Err(FluidError::State(format!(
                "the flux velocity Gram matrices are {}×{} and {}×{}: both must be square and alike",
                m.nrows(),
                m.ncols(),
                n.nrows(),
                n.ncols()
            )));
        }
        let gap = Mat::from_fn(k, k, |i, j| 0.5 * ((m[(i, j)] - n[(i, j)]) + (m[(j, i)] - n[(j, i)])));
        Ok(Self { gap })
    }

    /// Flux coefficients the form takes (m_f).
    pub fn dim(&self) -> usize {
        self.gap.nrows()
    }

    /// `σ(f̂) = sqrt(max(0, f̂ᵀ(M − N)f̂))` in the energy norm's units (rounding can make the
    /// form a hair negative for a flux the basis holds whole; it is then 0). `f` has m_f
    /// coefficients ([`Self::dim`]; [`UnseenIndicator::observe`] checks it).
    pub fn sigma(&self, f: &[f64]) -> f64 {
        let k = self.dim().min(f.len());
        let mut q = 0.0;
        for i in 0..k {
            let row: f64 = (0..k).map(|j| self.gap[(i, j)] * f[j]).sum();
            q += f[i] * row;
        }
        q.max(0.0).sqrt()
    }
}

/// The running estimate `η_t` of the module docs, fed a run's states in order.
#[derive(Clone, Debug)]
pub struct UnseenIndicator {
    form: UnseenVelocity,
    /// `Σ_k σ(f̂_k − f̂_{k−1})` in energy-norm units.
    accumulated: f64,
    /// The last state's flux.
    last: Option<Vec<f64>>,
}

impl UnseenIndicator {
    /// An indicator for `model` (see [`UnseenVelocity::of_model`]).
    pub fn new(model: &ReducedFluidModel) -> Result<Self, FluidError> {
        Ok(Self::with_form(UnseenVelocity::of_model(model)?))
    }

    /// An indicator with the form `form`.
    pub fn with_form(form: UnseenVelocity) -> Self {
        Self { form, accumulated: 0.0, last: None }
    }

    /// Starts a new run: nothing carried, no previous flux.
    pub fn restart(&mut self) {
        self.accumulated = 0.0;
        self.last = None;
    }

    /// The estimate at frame `frame`, reached by the reduced step `from` → `to` that reported
    /// `report` (its energy after the projection and its damping,
    /// [`super::indicator::damping`]); on a run's first step `from` starts the run first.
    pub fn observe_step(
        &mut self,
        fluid: &ReducedFluid,
        from: &ReducedState,
        to: &ReducedState,
        report: &ReducedStepReport,
        frame: usize,
    ) -> Result<IndicatorFrame, FluidError> {
        if self.last.is_none() {
            self.observe(&from.f, fluid.energy(&from.u, &from.g), 1.0, frame.saturating_sub(1))?;
        }
        self.observe(&to.f, report.energy[2], damping(report), frame)
    }

    /// The estimate at frame `frame` for the flux `f` of the state reached there and the
    /// state's energy `energy = ½ ûᵀV̂û` (what the step reports after its projection,
    /// [`super::step::ReducedStepReport::energy`]), the errors carried so far first multiplied
    /// by `damping` ([`super::indicator::damping`]; 1 carries them undamped). The first call
    /// starts the run (its estimate is σ of the initial flux alone).
    pub fn observe(
        &mut self,
        f: &[f64],
        energy: f64,
        damping: f64,
        frame: usize,
    ) -> Result<IndicatorFrame, FluidError> {
        if f.len() != self.form.dim() {
            return Err(FluidError::State(format!(
                "the unseen-velocity indicator at frame {frame}: the flux has {} coefficients, the model {}",
                f.len(),
                self.form.dim()
            )));
        }
        self.accumulated *= damping.clamp(0.0, 1.0);
        let increment = match &self.last {
            Some(prev) => {
                let delta: Vec<f64> = f.iter().zip(prev).map(|(a, b)| a - b).collect();
                self.form.sigma(&delta)
            }
            None => 0.0,
        };
        self.accumulated += increment;
        self.last = Some(f.to_vec());
        let sigma = self.form.sigma(f);
        let scale = (2.0 * energy.max(0.0)).sqrt();
        let relative = |x: f64| if scale > 0.0 { x / scale } else { 0.0 };
        let out = IndicatorFrame {
            frame,
            measured: true,
            truncation: relative(sigma),
            in_basis: relative(increment),
            estimate: relative(sigma + self.accumulated),
        };
        if !out.estimate.is_finite() {
            return Err(FluidError::State(format!(
                "the unseen-velocity indicator at frame {frame} is not finite"
            )));
        }
        Ok(out)
    }
}

/// The unseen-velocity indicator of every frame of `run` (frame 0 first), and the median
/// seconds it took per frame; `on_frame(t)` hears the progress.
pub fn indicate_unseen(
    model: &ReducedFluidModel,
    fluid: &ReducedFluid,
    run: &ReducedRun,
    on_frame: &mut dyn FnMut(usize),
) -> Result<(Vec<IndicatorFrame>, f64), FluidError> {
    let mut indicator = UnseenIndicator::new(model)?;
    let mut out = Vec::with_capacity(run.states.len());
    let mut seconds = Vec::with_capacity(run.states.len());
    if let Some(first) = run.states.first() {
        out.push(indicator.observe(&first.f, fluid.energy(&first.u, &first.g), 1.0, 0)?);
        on_frame(0);
    }
    for (t, (pair, report)) in run.states.windows(2).zip(&run.reports).enumerate() {
        let start = Instant::now();
        out.push(indicator.observe_step(fluid, &pair[0], &pair[1], report, t + 1)?);
        seconds.push(start.elapsed().as_secs_f64());
        on_frame(t + 1);
    }
    Ok((out, crate::bench::median_f64(&mut seconds)))
}

/// The unseen-velocity indicator as CSV with a header (frame; σ of the flux and of the step's
/// flux change, relative to the reduced velocity's energy norm; the estimate).
pub fn unseen_csv(frames: &[IndicatorFrame]) -> String {
    let mut out = String::from("frame,unseen_velocity,step_unseen_velocity,error_estimate\n");
    for f in frames {
        out += &format!("{},{:e},{:e},{:e}\n", f.frame, f.truncation, f.in_basis, f.estimate);
    }
    out
}
