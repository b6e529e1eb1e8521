//! A reduced run against the full run of the same motion (seed 000 §7.2, its video's
//! comparisons): both start from rest and follow the same geometry — a training run replayed,
//! or the cavity driven by compressions no training run made — the full solver stepping in the
//! full space, the reduced model in its own, lifted `u = B_u û` to be compared. Per frame: the
//! kinetic energy of both, `E(u) = ½ Σ_c vol_c(g) |u_c|²` at the full run's geometry, and the
//! relative velocity error in that energy norm, `‖u_full − u_reduced‖_V / ‖u_full‖_V`; at the
//! last frame, the error of every cell (where it sits), for a picture.
//!
//! Two measures say where the error comes from. The **one-step error** (§7.1, Fig. 5's measure
//! as a norm): one reduced step from the full run's previous frame projected into the bases
//! (û by the energy projection of its momentum, f̂ = B_fᵀf, ĝ, ĥ), against the full run's frame
//! — what a single step loses, before errors accumulate over the run. The **flux truncation**:
//! `‖f − B_f B_fᵀ f‖ / ‖f‖` of the full run's flux — the reduced velocity after the projection
//! (Eq. 12) is `V̂⁻¹(P̂ ⊗ ĝ) f̂`, so it lies in an m_f-dimensional subspace of `B_u`, and the
//! flux basis, not `B_u`, bounds how close a reduced state can come.
//!
//! The full run is simulated again (the cavity, whose motion is a function of its
//! compressions) or read back from the snapshot directory a training wrote (any scene — the
//! bird — without simulating it again).

use std::path::PathBuf;
use std::time::Instant;

use crate::fluid::scene::{FluidScene, Motion};
use crate::fluid::{FluidError, FluidSolver};

use super::cavity_motion::CompressionSchedule;
use super::model::ReducedFluidModel;
use super::run::{follow, run_driven, run_reduced, ReducedMotion, ReducedRun};
use super::step::{ReducedFluid, ReducedState};
use crate::fluid::snapshots::SnapshotReader;
use crate::reduce::Basis;

/// Most a simulated full run's substeps may be refined.
pub const MAX_REFINE: usize = 64;

/// The motion both runs follow.
#[derive(Clone, Debug)]
pub enum ComparedMotion {
    /// Training run K of the cavity (the full run simulated again; the reduced run replays
    /// its ĝ and ĥ).
    Training(usize),
    /// The cavity driven by compressions (the reduced run's ĥ from the induced-flux tensor).
    Driven(CompressionSchedule),
    /// Any recorded full run of the model's mesh, read from its snapshot directory — a training
    /// run (`run-00` of the training's work directory), a held-out obstacle, a driven cavity
    /// (`fluid simulate --drive`) — the reduced run following the geometry and induced flux
    /// of that run's own files ([`super::model::Trajectory::recorded`]), never a training
    /// run's.
    Recorded {
        /// The full run's snapshot directory.
        full: PathBuf,
    },
}

/// What [`compare`] measured.
#[derive(Clone, Debug, Default)]
pub struct Comparison {
    /// Time between frames.
    pub frame_time: f64,
    /// Kinetic energy of the full run per frame (frame 0 first).
    pub energy_full: Vec<f64>,
    /// Kinetic energy of the lifted reduced run per frame.
    pub energy_reduced: Vec<f64>,
    /// Relative velocity error in the energy norm per frame (0 where the full run is at rest).
    pub error: Vec<f64>,
    /// The same error of the full run's best fit in the velocity basis, `B_u B_uᵀ u_full`:
    /// what truncating the velocity alone costs, whatever the reduced dynamics do.
    pub projection_error: Vec<f64>,
    /// The one-step error per frame (0 at frame 0; see the module docs).
    pub one_step_error: Vec<f64>,
    /// The full run's flux truncation in `B_f` per frame, `‖f − B_f B_fᵀ f‖ / ‖f‖` (0 where
    /// the flux is 0).
    pub flux_projection_error: Vec<f64>,
    /// Each cell's error |u_full − u_reduced| at the last frame.
    pub cell_error: Vec<f64>,
    /// The full run's geometry at the last frame.
    pub last_geometry: Vec<f64>,
    /// The reduced run's energy lost per step in advection and diffusion, and in the
    /// projection (index t − 1 for the step to frame t; [`super::step::ReducedStepReport::energy`]).
    pub reduced_energy_loss: Vec<[f64; 2]>,
    /// The error indicator per frame ([`super::indicator`]; empty until
    /// [`Self::add_indicator`]).
    pub estimate: Vec<f64>,
    /// The reduced run compared.
    pub reduced: Option<ReducedRun>,
    /// The recorded full run whose motion the reduced run followed, if it was one (the
    /// residual indicator takes its full-space geometry).
    pub recorded: Option<PathBuf>,
    /// How its step projected.
    pub projection: Projection,
    /// The flux directions its projection kept, where the model narrows it.
    pub seen_flux: Option<super::step::SeenFlux>,
    /// Median seconds of a full frame (NaN where the full run was read back, not simulated)
    /// and of a reduced step.
    pub seconds: (f64, f64),
}

impl Comparison {
    /// Frame, time, both energies, the error, the best fit's, the one-step error and the flux
    /// truncation, as CSV with a header.
    pub fn csv(&self) -> String {
        let mut out = String::from(
            "frame,time,energy_full,energy_reduced,relative_error,projection_error,one_step_error,flux_projection_error",
        );
        out += if self.estimate.is_empty() { "\n" } else { ",error_estimate,effectivity\n" };
        let effectivity = self.effectivity();
        for k in 0..self.error.len() {
            let at = |v: &[f64]| v.get(k).copied().unwrap_or(0.0);
            out += &format!(
                "{k},{},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                k as f64 * self.frame_time,
                at(&self.energy_full),
                at(&self.energy_reduced),
                at(&self.error),
                at(&self.projection_error),
                at(&self.one_step_error),
                at(&self.flux_projection_error)
            );
            if !self.estimate.is_empty() {
                out.pop();
                out += &format!(",{:e},{:e}\n", at(&self.estimate), at(&effectivity));
            }
        }
        out
    }

    /// Computes the error indicator of the reduced run ([`super::indicator::indicate`], the
    /// residual measured every `every`-th step) into [`Self::estimate`].
    pub fn add_indicator(
        &mut self,
        model: &ReducedFluidModel,
        every: usize,
        on_frame: &mut dyn FnMut(usize),
    ) -> Result<Vec<super::indicator::IndicatorFrame>, FluidError> {
        let run =
            self.reduced.as_ref().ok_or_else(|| FluidError::State("no reduced run to indicate".into()))?;
        let fluid = reduced_fluid(model, &self.projection)?;
        let reader = self.recorded.as_deref().map(SnapshotReader::open).transpose()?;
        let frames = super::indicator::indicate(model, &fluid, run, every, reader.as_ref(), on_frame)?;
        self.estimate = frames.iter().map(|f| f.estimate).collect();
        Ok(frames)
    }

    /// Computes the unseen-velocity indicator of the reduced run ([`super::unseen`], from
    /// reduced quantities alone) into [`Self::estimate`]; returns its frames and the median
    /// seconds it took per frame.
    pub fn add_unseen_indicator(
        &mut self,
        model: &ReducedFluidModel,
        on_frame: &mut dyn FnMut(usize),
    ) -> Result<(Vec<super::indicator::IndicatorFrame>, f64), FluidError> {
        let run =
            self.reduced.as_ref().ok_or_else(|| FluidError::State("no reduced run to indicate".into()))?;
        let fluid = reduced_fluid(model, &self.projection)?;
        let (frames, seconds) = super::unseen::indicate_unseen(model, &fluid, run, on_frame)?;
        self.estimate = frames.iter().map(|f| f.estimate).collect();
        Ok((frames, seconds))
    }

    /// Estimate ÷ true error per frame (0 where the true error is 0, and at frame 0).
    pub fn effectivity(&self) -> Vec<f64> {
        self.estimate
            .iter()
            .zip(&self.error)
            .enumerate()
            .map(|(k, (e, t))| if k > 0 && *t > 0.0 { e / t } else { 0.0 })
            .collect()
    }

    /// The smallest and largest effectivity over the frames after the first.
    pub fn effectivity_range(&self) -> (f64, f64) {
        let eff = self.effectivity();
        eff.iter().skip(1).fold((f64::INFINITY, 0.0f64), |(lo, hi), e| (lo.min(*e), hi.max(*e)))
    }

    /// The mean and largest relative error over the frames after the first.
    pub fn error_summary(&self) -> (f64, f64) {
        summary(&self.error)
    }

    /// The colour range of [`error_section`]: 0 to the largest cell error.
    pub fn cell_error_range(&self) -> (f64, f64) {
        (0.0, self.cell_error.iter().fold(0.0f64, |m, v| m.max(*v)).max(1e-300))
    }

    /// [`Self::error_summary`] of the best fit in `B_u` ([`Self::projection_error`]).
    pub fn projection_summary(&self) -> (f64, f64) {
        summary(&self.projection_error)
    }

    /// [`Self::error_summary`] of the one-step error ([`Self::one_step_error`]).
    pub fn one_step_summary(&self) -> (f64, f64) {
        summary(&self.one_step_error)
    }

    /// [`Self::error_summary`] of the flux truncation ([`Self::flux_projection_error`]).
    pub fn flux_projection_summary(&self) -> (f64, f64) {
        summary(&self.flux_projection_error)
    }
}

fn summary(errors: &[f64]) -> (f64, f64) {
    let moving = &errors[errors.len().min(1)..];
    let mean = moving.iter().sum::<f64>() / moving.len().max(1) as f64;
    (mean, moving.iter().copied().fold(0.0, f64::max))
}

/// Runs both `frames` frames on `scene` (the model's cavity) under `motion` and compares them;
/// `on_frame(k)` hears the full run's progress. A simulated full run takes `refine` times the
/// RK4 substeps its stability needs (1: the solver as it trains; more separates the full
/// solver's own time-integration error from the reduced model's); a recorded one is as it was
/// simulated, so `refine` must be 1 there.
pub fn compare(
    model: &ReducedFluidModel,
    scene: &FluidScene,
    motion: &ComparedMotion,
    frames: usize,
    refine: usize,
    on_frame: &mut dyn FnMut(usize),
) -> Result<Comparison, FluidError> {
    compare_with(model, scene, motion, (frames, refine, Projection::default()), on_frame)
}

/// [`compare`] with the reduced step's projection as `projection` says.
pub fn compare_with(
    model: &ReducedFluidModel,
    scene: &FluidScene,
    motion: &ComparedMotion,
    (frames, refine, projection): (usize, usize, Projection),
    on_frame: &mut dyn FnMut(usize),
) -> Result<Comparison, FluidError> {
    if refine == 0 || refine > MAX_REFINE {
        return Err(FluidError::State(format!("refine {refine}: give 1 to {MAX_REFINE}")));
    }
    if refine > 1 && matches!(motion, ComparedMotion::Recorded { .. }) {
        return Err(FluidError::State(
            "a recorded full run cannot be refined: it was simulated as it was (leave out --full)".into(),
        ));
    }
    let fingerprint = super::model::MeshFingerprint::of(&scene.mesh, &scene.topology, scene.periodic_axis);
    model.check_mesh(&fingerprint)?;
    let fluid = reduced_fluid(model, &projection)?;
    let reduced = match motion {
        ComparedMotion::Training(k) => {
            run_reduced(model, &fluid, ReducedMotion::Replay(*k), frames, &mut |_| {})?
        }
        ComparedMotion::Recorded { full } => {
            let reader = SnapshotReader::open(full)?;
            let traj = super::model::Trajectory::recorded(model, &reader, full)?;
            follow(&fluid, &traj, true, frames, &full.display().to_string(), &mut |_| {})?
        }
        ComparedMotion::Driven(schedule) => run_driven(model, &fluid, schedule, frames, &mut |_| {})?,
    };
    let basis =
        |n: &str| model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")));
    let (bu, bf, bg) = (basis("u")?, basis("f")?, basis("g")?);
    let bh = model.basis("h");
    let mut full = FullRun::new(scene, model, motion, frames, refine, bh.is_some())?;
    let d = scene.mesh.dim();
    let mut out = Comparison {
        frame_time: model.frame_time,
        projection,
        seen_flux: fluid.seen_flux().cloned(),
        recorded: match motion {
            ComparedMotion::Recorded { full } => Some(full.clone()),
            _ => None,
        },
        ..Comparison::default()
    };
    let mut full_seconds = Vec::new();
    // The previous full frame projected into the bases: the one-step error's start.
    let mut previous: Option<ReducedState> = None;
    for t in 0..=frames {
        let start = Instant::now();
        let frame = full.frame(t)?;
        if t > 0 {
            if !full.is_recorded() {
                full_seconds.push(start.elapsed().as_secs_f64());
            }
            on_frame(t);
        }
        let vols = scene.mesh.volumes_at(&frame.g);
        let u_full = &frame.u;
        let u_reduced = bu.lift(&reduced.states[t].u);
        let energy = |u: &[f64]| kinetic_energy(u, &vols, d);
        let error_of = |u: &[f64]| -> f64 {
            let diff: Vec<f64> = u_full.iter().zip(u).map(|(a, b)| a - b).collect();
            energy(&diff)
        };
        let ef = energy(u_full);
        let relative = |e: f64| if ef > 0.0 { (e / ef).sqrt() } else { 0.0 };
        out.energy_full.push(ef);
        out.energy_reduced.push(energy(&u_reduced));
        out.error.push(relative(error_of(&u_reduced)));
        out.projection_error.push(relative(error_of(&bu.lift(&bu.project(u_full)))));
        let g_hat = bg.project(&frame.g);
        let one_step = match &previous {
            Some(start) => {
                let h = match (bh, &frame.h) {
                    (Some(b), Some(h)) => b.project(h),
                    _ => Vec::new(),
                };
                relative(error_of(&bu.lift(&fluid.step(start, &g_hat, &h)?.0.u)))
            }
            None => 0.0,
        };
        out.one_step_error.push(one_step);
        let f_norm = frame.f.iter().map(|x| x * x).sum::<f64>().sqrt();
        let f_fit = bf.lift(&bf.project(&frame.f));
        let f_err = frame.f.iter().zip(&f_fit).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        out.flux_projection_error.push(if f_norm > 0.0 { f_err / f_norm } else { 0.0 });
        if t == frames {
            out.cell_error = u_full
                .chunks(d)
                .zip(u_reduced.chunks(d))
                .map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt())
                .collect();
            out.last_geometry = frame.g.clone();
        }
        if t < frames {
            previous = Some(projected(&fluid, &frame, (d, &vols), g_hat, bu, bf)?);
        }
    }
    out.reduced_energy_loss =
        reduced.reports.iter().map(|r| [r.energy[0] - r.energy[1], r.energy[1] - r.energy[2]]).collect();
    let mut reduced_seconds: Vec<f64> = reduced.reports.iter().map(|r| r.total_seconds()).collect();
    out.seconds =
        (crate::bench::median_f64(&mut full_seconds), crate::bench::median_f64(&mut reduced_seconds));
    out.reduced = Some(reduced);
    Ok(out)
}

/// How the reduced step's projection (Eq. 12) is made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Its normal matrix from the full space ([`super::exact_projection::ExactProjection`]).
    pub exact: bool,
    /// The seen-flux threshold ([`ReducedFluid::with_seen_flux`]; used where the model
    /// carries the measure).
    pub seen_flux: f64,
}

impl Default for Projection {
    fn default() -> Self {
        Self { exact: false, seen_flux: super::step::SEEN_FLUX_THRESHOLD }
    }
}

/// The reduced step of `model`, its projection made as `projection` says.
pub fn reduced_fluid(model: &ReducedFluidModel, projection: &Projection) -> Result<ReducedFluid, FluidError> {
    let fluid = ReducedFluid::with_seen_flux_threshold(model, projection.seen_flux)?;
    if projection.exact {
        fluid.with_exact_projection(model)
    } else {
        Ok(fluid)
    }
}

/// A frame of the full run: velocity, geometry, flux, and the induced flux of the motion into
/// it (when the model has `B_h`).
struct FullFrame {
    u: Vec<f64>,
    g: Vec<f64>,
    f: Vec<f64>,
    h: Option<Vec<f64>>,
}

/// The full frame `frame` (`d`-dimensional, cell volumes `vols`, reduced geometry `g`) projected into the
/// bases: û by the energy projection of its momentum `V(g)u`, f̂ = B_fᵀf — where the one-step
/// error's reduced step starts.
fn projected(
    fluid: &ReducedFluid,
    frame: &FullFrame,
    (d, vols): (usize, &[f64]),
    g: Vec<f64>,
    bu: &Basis,
    bf: &Basis,
) -> Result<ReducedState, FluidError> {
    Ok(ReducedState { u: best_fit(fluid, bu, &frame.u, (d, vols), &g)?, f: bf.project(&frame.f), g })
}

/// The kinetic energy `½ Σ_c vol_c |u_c|²` of a field of `d`-vectors per cell (§7.1): the
/// energy norm every comparison, split and indicator measures in.
pub fn kinetic_energy(u: &[f64], vols: &[f64], d: usize) -> f64 {
    0.5 * u.chunks(d).zip(vols).map(|(v, w)| w * v.iter().map(|x| x * x).sum::<f64>()).sum::<f64>()
}

/// `û` of the best fit `Π u` of a full velocity in `B_u` (cell volumes `vols`) at reduced
/// geometry `g_hat`: the energy projection of its momentum `V(g)u` (§7.1 footnote 2).
pub fn best_fit(
    fluid: &ReducedFluid,
    bu: &Basis,
    u: &[f64],
    (d, vols): (usize, &[f64]),
    g_hat: &[f64],
) -> Result<Vec<f64>, FluidError> {
    let momentum: Vec<f64> = u.iter().enumerate().map(|(i, x)| vols[i / d] * x).collect();
    fluid.project_velocity(&bu.project(&momentum), g_hat)
}

/// The full side of a comparison, frame by frame: simulated (the cavity) or read back.
enum FullRun<'a> {
    Simulated {
        scene: &'a FluidScene,
        cavity: &'a crate::fluid::cavity::Cavity,
        solver: Box<FluidSolver>,
        state: Option<crate::fluid::FluidState>,
        schedule: Box<dyn Fn(usize) -> Result<[f64; 3], FluidError> + 'a>,
        with_h: bool,
    },
    Recorded(SnapshotReader, bool),
}

impl<'a> FullRun<'a> {
    fn new(
        scene: &'a FluidScene,
        model: &ReducedFluidModel,
        motion: &'a ComparedMotion,
        frames: usize,
        refine: usize,
        with_h: bool,
    ) -> Result<Self, FluidError> {
        if let ComparedMotion::Recorded { full, .. } = motion {
            return Self::recorded(full, scene, frames, with_h);
        }
        let Motion::Cavity { cavity, .. } = &scene.motion else {
            return Err(FluidError::State(
                "only the cavity's full run is simulated again; give the full run's snapshot directory (--full)"
                    .into(),
            ));
        };
        let schedule: Box<dyn Fn(usize) -> Result<[f64; 3], FluidError>> = match motion {
            ComparedMotion::Training(k) => {
                let amounts = crate::fluid::cavity::training_run(*k).ok_or_else(|| {
                    FluidError::State(format!("training run {k}: the cavity has runs 0 to 13"))
                })?;
                // The compressions at the pace the model's run was trained at (its own frame
                // count, which `train-scene --frames` may have set), not the scene's.
                let total = model.trajectories.get(*k).map_or(scene.frames, |t| t.frames());
                Box::new(move |t| Ok(crate::fluid::cavity::Cavity::compression(amounts, t, total)))
            }
            ComparedMotion::Driven(schedule) => Box::new(move |t| Ok(schedule.at(t))),
            ComparedMotion::Recorded { full, .. } => return Self::recorded(full, scene, frames, with_h),
        };
        let solver = FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params)?
            .with_substep_refinement(refine);
        Ok(Self::Simulated { scene, cavity, solver: Box::new(solver), state: None, schedule, with_h })
    }

    /// The full run read from the snapshot directory `full`, checked against the scene's mesh
    /// and the frames compared.
    fn recorded(
        full: &std::path::Path,
        scene: &FluidScene,
        frames: usize,
        with_h: bool,
    ) -> Result<Self, FluidError> {
        let reader = SnapshotReader::open(full)?;
        let (meta, mesh) = (reader.meta(), &scene.mesh);
        if meta.cells != mesh.cell_count() || meta.dim != mesh.dim() {
            return Err(FluidError::State(format!(
                "{}: a run of {} cells in {}D, the scene has {} in {}D",
                full.display(),
                meta.cells,
                meta.dim,
                mesh.cell_count(),
                mesh.dim()
            )));
        }
        if meta.frames <= frames {
            return Err(FluidError::State(format!(
                "{}: the run holds frames 0 to {}, the comparison needs {frames}",
                full.display(),
                meta.frames.saturating_sub(1)
            )));
        }
        Ok(Self::Recorded(reader, with_h))
    }

    fn is_recorded(&self) -> bool {
        matches!(self, Self::Recorded(..))
    }

    /// Frame `t` (velocity, geometry, flux, and the induced flux into it if asked for);
    /// frames are asked for in order from 0.
    fn frame(&mut self, t: usize) -> Result<FullFrame, FluidError> {
        match self {
            Self::Recorded(reader, with_h) => Ok(FullFrame {
                u: reader.frame("u", t)?,
                g: reader.frame("g", t)?,
                f: reader.frame("f", t)?,
                h: if *with_h && t > 0 { Some(reader.frame("h", t)?) } else { None },
            }),
            Self::Simulated { scene, cavity, solver, state, schedule, with_h } => {
                let g = cavity.mapped_for(schedule(t)?);
                let (next, h) = match state.take() {
                    None => (solver.initial_state(g, &scene.initial_velocity)?, None),
                    Some(s) => {
                        let h = with_h.then(|| solver.induced_flux(&s.g, &g));
                        (solver.step(&s, &g, t)?.0, h)
                    }
                };
                let out = FullFrame { u: next.u.clone(), g: next.g.clone(), f: next.f.clone(), h };
                *state = Some(next);
                Ok(out)
            }
        }
    }
}

/// The last frame's cell errors on the section of the domain by the plane z = 0 (the plane of
/// the cavity's centres), coloured on a ramp from 0 to the largest error: where the error
/// sits.
pub fn error_section(
    gpu: &crate::gpu::Gpu,
    mesh: &crate::mesh::SimplexMesh,
    c: &Comparison,
    size: (u32, u32),
) -> Result<crate::fluid::render::FluidPicture, FluidError> {
    use crate::fluid::render::{draw_triangles, plane_section, DrawStyle, Projection, View2d};
    let triangles = plane_section(mesh, &c.last_geometry, &c.cell_error, 2, 0.0);
    let (lo, hi) = mesh.bounds();
    let style = DrawStyle {
        colormap: crate::render::Colormap::viridis(),
        range: c.cell_error_range(),
        log: false,
        colour_cells: true,
        sprite_px: 0.0,
    };
    let view = View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], size, 0.03);
    draw_triangles(gpu, &triangles, &c.cell_error, None, &style, &Projection::Plane(view), size)
}

impl Comparison {
    /// Writes the comparison of `frames` frames titled `title` into `dir`: comparison.csv,
    /// the plots energy.png and error.png, and error-section.png (the last frame's cell
    /// errors on the plane z = 0 with its colour bar, drawn on `gpu`).
    pub fn write_outputs(
        &self,
        gpu: &crate::gpu::Gpu,
        mesh: &crate::mesh::SimplexMesh,
        title: &str,
        frames: usize,
        dir: &std::path::Path,
    ) -> Result<(), FluidError> {
        std::fs::create_dir_all(dir).map_err(FluidError::io(dir))?;
        let csv = dir.join("comparison.csv");
        crate::atomic_file::write(&csv, self.csv().as_bytes()).map_err(FluidError::io(&csv))?;
        super::plot::plot_comparison(self, title, &dir.join("energy.png"), &dir.join("error.png"))?;
        let size = (900, 700);
        let picture = error_section(gpu, mesh, self, size)?;
        super::plot::plot_picture_with_colour_bar(
            &picture.rgba,
            size,
            &crate::render::Colormap::viridis(),
            self.cell_error_range(),
            (
                &format!("Velocity error at frame {frames} on the plane z = 0 — {title}"),
                "|u_full − u_reduced| per cell",
            ),
            &dir.join("error-section.png"),
        )
    }
}
