//! A per-frame error indicator for reduced fluid runs: how far a reduced run is from the full
//! run of the same motion, estimated without the full run (the a-posteriori residual estimate
//! of reduced-basis practice, for the seed 000 §6 step).
//!
//! The **residual** of a reduced step: the full solver's step
//! ([`crate::fluid::FluidSolver::step`]) from the full state the reduced flux stands for —
//! flux `B_f f̂_t`, its velocity `V⁻¹(P ⊗ g_t) B_f f̂_t`, geometry `g_t = B_g ĝ_t` — to
//! `B_g ĝ_{t+1}`, `s_{t+1}`, against the lifted reduced result `u_r = B_u û_{t+1}`. It splits, with Π the V-orthogonal projection onto `B_u`, into
//!
//! - the **truncation** `τ = ‖s − Π s‖_V`: what the full step does outside the basis, which no
//!   reduced state can hold — the truth's distance from the basis, felt once, not accumulated;
//! - the **in-basis residual** `ρ = ‖Π s − u_r‖_V`: what the reduced step gets wrong inside the
//!   basis, which the run carries on to every later step.
//!
//! The estimate at frame t is `(τ_t + Σ_{k ≤ t} (Π_{k < j ≤ t} λ_j) ρ_k) / ‖u_r,t‖_V` — the
//! error a stable step would accumulate, the truncation of the latest step added: each step's
//! error is carried forward, shrunk by the factor `λ_j` ≤ 1 by which step j's advection and
//! diffusion shrank the reduced state's energy norm ([`damping`]; advection alone keeps the
//! energy, so λ is the viscous loss, and 1 where there is none). A full step costs what the
//! full solver costs, so the residual is measured every `every`-th step only and the last
//! measured `ρ` and `τ` stand for the steps between; `every = 1` measures every step.
//! Effectivity (estimate ÷ true error) on the tunnel, the cavities and the bird: BENCHMARKS.md.

use crate::fluid::snapshots::SnapshotReader;
use crate::fluid::{FluidError, FluidParams, FluidSolver, FluidState};
use crate::mesh::SimplexMesh;
use crate::reduce::Basis;

use super::compare::{best_fit, kinetic_energy};
use super::model::ReducedFluidModel;
use super::run::ReducedRun;
use super::step::{ReducedFluid, ReducedState, ReducedStepReport};

/// The factor `λ = sqrt(E_advected / E_start)` (at most 1) by which a step's advection and
/// diffusion shrank the reduced state's energy norm (`ReducedStepReport::energy`'s first two):
/// both indicators carry earlier steps' errors forward shrunk by it — advection keeps the
/// energy, so it is the viscous loss, which damps a carried error as it damps the state. 1
/// where the step reports no energy.
pub fn damping(report: &ReducedStepReport) -> f64 {
    let [start, advected, _] = report.energy;
    if start > 0.0 && advected.is_finite() {
        (advected / start).clamp(0.0, 1.0).sqrt()
    } else {
        1.0
    }
}

/// Most steps between two measured residuals.
pub const MAX_EVERY: usize = 1_000_000;

/// One frame's indicator.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IndicatorFrame {
    /// The frame.
    pub frame: usize,
    /// Whether this step's residual was measured (otherwise the last measured one stands).
    pub measured: bool,
    /// The step's truncation `τ`, relative to `‖u_r‖_V`.
    pub truncation: f64,
    /// The step's in-basis residual `ρ`, relative to `‖u_r‖_V`.
    pub in_basis: f64,
    /// The estimated relative error of the reduced run at this frame.
    pub estimate: f64,
}

/// The indicator of one reduced run, fed its states in order ([`Self::observe`]).
pub struct ErrorIndicator<'a> {
    model: &'a ReducedFluidModel,
    fluid: &'a ReducedFluid,
    solver: FluidSolver,
    mesh: SimplexMesh,
    every: usize,
    steps: usize,
    /// Σ ρ_k in absolute energy-norm units, and the last measured (τ, ρ) in the same units.
    accumulated: f64,
    last: Option<(f64, f64)>,
}

impl<'a> ErrorIndicator<'a> {
    /// An indicator measuring the residual every `every`-th step (1 to [`MAX_EVERY`]) with a
    /// full solver on the model's mesh (its viscosity and frame time; no body force, as the
    /// reduced step has none).
    pub fn new(
        model: &'a ReducedFluidModel,
        fluid: &'a ReducedFluid,
        every: usize,
    ) -> Result<Self, FluidError> {
        if every == 0 || every > MAX_EVERY {
            return Err(FluidError::State(format!(
                "the indicator's residual every {every} steps: give 1 to {MAX_EVERY}"
            )));
        }
        let (mesh, topo) = model.mesh_and_topology()?;
        let params =
            FluidParams { viscosity: model.viscosity, forcing: [0.0; 3], frame_time: model.frame_time };
        let solver = FluidSolver::new(mesh.clone(), topo, params)?;
        Ok(Self { model, fluid, solver, mesh, every, steps: 0, accumulated: 0.0, last: None })
    }

    fn basis(&self, n: &str) -> Result<&'a Basis, FluidError> {
        self.model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")))
    }

    /// Whether the next [`Self::observe`] measures the residual (every `every`-th step).
    pub fn measures_next(&self) -> bool {
        self.steps.is_multiple_of(self.every)
    }

    /// The indicator at frame `frame`, reached by the reduced step `from` → `to`; the full
    /// step runs between the full-space geometries `geometry` where the motion's are known (a
    /// recorded run's), else between the lifted `B_g ĝ` (which a small geometry basis may
    /// leave unable to hold the fluid's volume: the bird's, BENCHMARKS.md).
    /// The carried errors are first multiplied by `damping` ([`damping`]; 1: undamped).
    pub fn observe(
        &mut self,
        from: &ReducedState,
        to: &ReducedState,
        frame: usize,
        geometry: Option<(Vec<f64>, Vec<f64>)>,
        damping: f64,
    ) -> Result<IndicatorFrame, FluidError> {
        self.accumulated *= damping.clamp(0.0, 1.0);
        let (bu, bf, bg) = (self.basis("u")?, self.basis("f")?, self.basis("g")?);
        let d = self.mesh.dim();
        let (g0, g1) = match geometry {
            Some((g0, g1)) => (Some(g0), g1),
            None => (None, bg.lift(&to.g)),
        };
        let vols = self.mesh.volumes_at(&g1);
        let energy_norm = |u: &[f64]| (2.0 * kinetic_energy(u, &vols, d)).sqrt();
        let u_r = bu.lift(&to.u);
        let scale = energy_norm(&u_r);
        let measured = self.measures_next();
        self.steps += 1;
        if measured {
            let (f0, g0) = (bf.lift(&from.f), g0.unwrap_or_else(|| bg.lift(&from.g)));
            // The full state the reduced flux stands for: its velocity `V⁻¹(P ⊗ g) B_f f̂`,
            // divergence-free as the full solver's states are (`B_u û` is that velocity's
            // Galerkin image, which the full projection would first have to repair: lifting
            // it doubles the measured residual on the tunnel, BENCHMARKS.md).
            let topo = self.solver.topology();
            let u0 = crate::fluid::operators::CellOperators::new(&self.mesh, topo, &g0)
                .flux_to_velocity(topo, &f0);
            let start = FluidState { u: u0, f: f0, g: g0 };
            let s = self.solver.step(&start, &g1, frame)?.0.u;
            let fit = bu.lift(&best_fit(self.fluid, bu, &s, (d, &vols), &to.g)?);
            let diff = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x - y).collect() };
            let tau = energy_norm(&diff(&s, &fit));
            let rho = energy_norm(&diff(&fit, &u_r));
            self.last = Some((tau, rho));
        }
        let (tau, rho) = self.last.unwrap_or((0.0, 0.0));
        self.accumulated += rho;
        let relative = |x: f64| if scale > 0.0 { x / scale } else { 0.0 };
        let out = IndicatorFrame {
            frame,
            measured,
            truncation: relative(tau),
            in_basis: relative(rho),
            estimate: relative(tau + self.accumulated),
        };
        if !out.estimate.is_finite() {
            return Err(FluidError::State(format!("the error indicator at frame {frame} is not finite")));
        }
        Ok(out)
    }
}

/// The indicator of every frame of `run` (frame 0 first, estimate 0 there: the run starts
/// from the motion's own initial state), measuring the residual every `every`-th step;
/// `motion` is the recorded run whose geometry the reduced run followed, when it did (its
/// full-space geometry per frame is then the full step's; only `g` is read, never the run's
/// velocities). `on_frame(t)` hears the progress.
pub fn indicate(
    model: &ReducedFluidModel,
    fluid: &ReducedFluid,
    run: &ReducedRun,
    every: usize,
    motion: Option<&SnapshotReader>,
    on_frame: &mut dyn FnMut(usize),
) -> Result<Vec<IndicatorFrame>, FluidError> {
    let mut indicator = ErrorIndicator::new(model, fluid, every)?;
    let mut out = vec![IndicatorFrame { measured: true, ..IndicatorFrame::default() }];
    for (t, pair) in run.states.windows(2).enumerate() {
        let geometry = match motion {
            Some(reader) if indicator.measures_next() => {
                Some((reader.frame("g", t)?, reader.frame("g", t + 1)?))
            }
            _ => None,
        };
        let carried = run.reports.get(t).map_or(1.0, damping);
        out.push(indicator.observe(&pair[0], &pair[1], t + 1, geometry, carried)?);
        on_frame(t + 1);
    }
    Ok(out)
}

/// The indicator as CSV with a header (frame, measured, truncation, in-basis residual,
/// estimate).
pub fn indicator_csv(frames: &[IndicatorFrame]) -> String {
    let mut out = String::from("frame,measured,truncation,in_basis_residual,error_estimate\n");
    for f in frames {
        out += &format!(
            "{},{},{:e},{:e},{:e}\n",
            f.frame,
            u8::from(f.measured),
            f.truncation,
            f.in_basis,
            f.estimate
        );
    }
    out
}
