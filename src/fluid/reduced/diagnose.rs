//! Where a reduced step loses what it loses: one frame of a recorded full run, split into
//! the step's two stages (seed 000 Fig. 2: advection–diffusion by the matrix exponential, then
//! the projection of Eq. 12), each stage of the reduced step against the same stage of the
//! full solver ([`crate::fluid::FluidSolver::advect`]; the full frame t + 1 for the
//! projection) from the same start — the full frame t projected into the bases.
//!
//! Per frame t → t + 1, with Π the V-orthogonal projection onto `B_u` (`û = V̂⁻¹B_uᵀV u`) and
//! every norm the energy norm at the stage's geometry:
//!
//! - **advection error** `‖Π u' − B_u û'‖ / ‖u'‖`: the reduced exponential against the full
//!   advection of the same start, both seen in `B_u`;
//! - **advected truncation** `‖u' − Π u'‖ / ‖u'‖`: how far the full advected velocity leaves
//!   `B_u` — the Galerkin step cannot follow what its basis cannot hold;
//! - **projection error** `‖u_{t+1} − B_u P̂(Π u')‖ / ‖u_{t+1}‖`: the reduced projection
//!   applied to the full advected velocity's best fit, against the full frame t + 1;
//! - **energies** of the start, of both advected velocities and of both results: which stage
//!   takes the energy a reduced run loses.

use crate::fluid::scene::FluidScene;
use crate::fluid::snapshots::SnapshotReader;
use crate::fluid::{FluidError, FluidSolver, FluidState};

use super::compare::{best_fit, kinetic_energy};
use super::model::ReducedFluidModel;
use super::step::{ReducedState, ReducedStepReport};

/// One frame's split ([`split_steps`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepSplit {
    /// The frame stepped to.
    pub frame: usize,
    /// The reduced advection against the full one, in `B_u`.
    pub advection_error: f64,
    /// The full advected velocity's distance from `B_u`.
    pub advected_truncation: f64,
    /// The reduced projection of the full advected velocity's best fit against frame t + 1.
    pub projection_error: f64,
    /// The whole reduced step from the projected frame t against frame t + 1 (§7.1's one-step
    /// error).
    pub step_error: f64,
    /// The whole reduced step against the full frame t + 1's best fit in `B_u`,
    /// `‖Π u_{t+1} − B_u û_{t+1}‖ / ‖u_{t+1}‖`: the part of the one-step error inside the
    /// basis, which a run carries on to the next step (the rest, the truncation, it does not
    /// accumulate).
    pub step_error_in_basis: f64,
    /// The whole reduced step's flux against the full frame t + 1's, `‖B_f f̂_{t+1} −
    /// f_{t+1}‖ / ‖f_{t+1}‖` (Euclidean over faces; compare the flux truncation in B_f).
    pub flux_error: f64,
    /// The advection error when the reduced advection starts from the flux the reduced step
    /// itself made for frame t (the previous frame's whole step) instead of `B_fᵀ f_t`: how
    /// much the flux a run carries, not the truth's, costs advection (0 at the first frame).
    pub advection_error_own_flux: f64,
    /// Energies: the full frame t, its projection (the reduced start), full advected, reduced
    /// advected, full frame t + 1, reduced step's result.
    pub energy: [f64; 6],
}

impl StepSplit {
    /// CSV header of [`Self::csv_row`].
    pub const CSV_HEADER: &'static str = "frame,advection_error,advected_truncation,projection_error,step_error,step_error_in_basis,flux_error,advection_error_own_flux,energy_full_start,energy_reduced_start,energy_full_advected,energy_reduced_advected,energy_full_next,energy_reduced_next";

    /// One CSV row.
    pub fn csv_row(&self) -> String {
        let e = self.energy;
        format!(
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            self.frame,
            self.advection_error,
            self.advected_truncation,
            self.projection_error,
            self.step_error,
            self.step_error_in_basis,
            self.flux_error,
            self.advection_error_own_flux,
            e[0],
            e[1],
            e[2],
            e[3],
            e[4],
            e[5]
        )
    }
}

/// Splits the reduced step on every frame 1..=`frames` of the recorded full run `full` (a
/// snapshot directory of `scene`'s mesh) into its stages (see the module docs); `on_frame(t)`
/// hears the progress; `projection` as [`super::compare::compare_with`]. Costs one full
/// advection and projection per frame.
pub fn split_steps(
    model: &ReducedFluidModel,
    scene: &FluidScene,
    full: &std::path::Path,
    frames: usize,
    projection: super::compare::Projection,
    on_frame: &mut dyn FnMut(usize),
) -> Result<Vec<StepSplit>, FluidError> {
    let reader = SnapshotReader::open(full)?;
    // Refuses another mesh or pace, naming the directory.
    let traj = super::model::Trajectory::recorded(model, &reader, full)?;
    if frames > traj.frames() {
        return Err(FluidError::State(format!(
            "{}: {frames} frames asked, the run has {}",
            full.display(),
            traj.frames()
        )));
    }
    let fluid = super::compare::reduced_fluid(model, &projection)?;
    let basis =
        |n: &str| model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")));
    let (bu, bf, bg) = (basis("u")?, basis("f")?, basis("g")?);
    let bh = model.basis("h");
    let mut solver = FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params)?;
    let d = scene.mesh.dim();
    let mut out = Vec::with_capacity(frames);
    let mut own_flux: Option<Vec<f64>> = None;
    for t in 0..frames {
        let (u, f, g) = (reader.frame("u", t)?, reader.frame("f", t)?, reader.frame("g", t)?);
        let (u1, g1) = (reader.frame("u", t + 1)?, reader.frame("g", t + 1)?);
        let vols0 = scene.mesh.volumes_at(&g);
        let vols1 = scene.mesh.volumes_at(&g1);
        let energy = |u: &[f64], vols: &[f64]| kinetic_energy(u, vols, d);
        let distance = |a: &[f64], b: &[f64], vols: &[f64]| {
            let diff: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
            energy(&diff, vols)
        };
        let relative = |e: f64, of: f64| if of > 0.0 { (e / of).sqrt() } else { 0.0 };
        let best_fit = |u: &[f64], vols: &[f64], g_hat: &[f64]| best_fit(&fluid, bu, u, (d, vols), g_hat);
        let (g_hat, g1_hat) = (bg.project(&g), bg.project(&g1));
        let start = ReducedState { u: best_fit(&u, &vols0, &g_hat)?, f: bf.project(&f), g: g_hat.clone() };
        // The full stages from the full frame t.
        let advected = solver.advect(&FluidState { u: u.clone(), f: f.clone(), g: g.clone() }, &g1, t + 1)?;
        let h_hat = bh.map_or(Vec::new(), |b| b.project(&advected.h));
        // The reduced stages from its projection.
        let mut report = ReducedStepReport::default();
        let u_adv = fluid.advect(&start.u, &start.f, &start.g, &h_hat, model.frame_time, &mut report)?;
        // The full advection is at g_t's volumes (the RK4 rate's), so are its norms.
        let adv_fit = best_fit(&advected.u, &vols0, &g_hat)?;
        let ea = energy(&advected.u, &vols0);
        let advection_error = relative(distance(&bu.lift(&adv_fit), &bu.lift(&u_adv), &vols0), ea);
        let advected_truncation = relative(distance(&advected.u, &bu.lift(&adv_fit), &vols0), ea);
        let (u_proj, _) = fluid.project(&adv_fit, &g1_hat, &h_hat, &mut report)?;
        let e1 = energy(&u1, &vols1);
        let projection_error = relative(distance(&u1, &bu.lift(&u_proj), &vols1), e1);
        // The whole reduced step: its own advection, then its projection (what
        // `ReducedFluid::step` does).
        let (next_u, next_f) = fluid.project(&u_adv, &g1_hat, &h_hat, &mut report)?;
        let f1 = reader.frame("f", t + 1)?;
        let f1_norm = f1.iter().map(|x| x * x).sum::<f64>().sqrt();
        let flux_diff = bf.lift(&next_f).iter().zip(&f1).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let flux_error = if f1_norm > 0.0 { flux_diff / f1_norm } else { 0.0 };
        let advection_error_own_flux = match own_flux.replace(next_f) {
            Some(f_own) => {
                let u_own =
                    fluid.advect(&start.u, &f_own, &start.g, &h_hat, model.frame_time, &mut report)?;
                relative(distance(&bu.lift(&adv_fit), &bu.lift(&u_own), &vols0), ea)
            }
            None => 0.0,
        };
        let u_next = bu.lift(&next_u);
        let step_error = relative(distance(&u1, &u_next, &vols1), e1);
        let next_fit = bu.lift(&best_fit(&u1, &vols1, &g1_hat)?);
        let step_error_in_basis = relative(distance(&next_fit, &u_next, &vols1), e1);
        out.push(StepSplit {
            frame: t + 1,
            advection_error,
            advected_truncation,
            projection_error,
            step_error,
            step_error_in_basis,
            flux_error,
            advection_error_own_flux,
            energy: [
                energy(&u, &vols0),
                energy(&bu.lift(&start.u), &vols0),
                ea,
                energy(&bu.lift(&u_adv), &vols0),
                e1,
                energy(&u_next, &vols1),
            ],
        });
        on_frame(t + 1);
    }
    Ok(out)
}

/// Means over frames of each error of `splits` (advection, advected truncation, projection,
/// whole step, whole step inside the basis, the step's flux, advection from the step's own
/// flux — the last over the frames after the first).
pub fn split_means(splits: &[StepSplit]) -> [f64; 7] {
    let n = splits.len().max(1) as f64;
    let mut m = [0.0; 7];
    for s in splits {
        let errors = [
            s.advection_error,
            s.advected_truncation,
            s.projection_error,
            s.step_error,
            s.step_error_in_basis,
            s.flux_error,
        ];
        for (k, v) in errors.into_iter().enumerate() {
            m[k] += v / n;
        }
        m[6] += s.advection_error_own_flux / (n - 1.0).max(1.0);
    }
    m
}
