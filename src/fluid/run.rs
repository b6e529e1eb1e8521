//! A full-space simulation run written as a snapshot directory (seed 000 §6.1's training
//! data): the loop `galerkin fluid simulate` runs, here so tests and the reduced model's
//! training use the same one.

use std::path::Path;
use std::time::Instant;

use super::scene::FluidScene;
use super::snapshots::{SnapshotMeta, SnapshotWriter};
use super::{FluidError, FluidSolver, FluidState, StepReport};

/// What a run did.
#[derive(Clone, Debug, Default)]
pub struct RunSummary {
    /// Frames simulated after the initial state.
    pub frames: usize,
    /// Seconds building the solver and the initial state.
    pub setup_seconds: f64,
    /// Per frame: deformation, advection–diffusion and projection seconds (t_d, t_a, t_p).
    pub stage_seconds: Vec<[f64; 3]>,
    /// Kinetic energy at the start and the end.
    pub energy: (f64, f64),
    /// Largest relative divergence left by a projection.
    pub worst_divergence: f64,
    /// RK4 substeps of the last frame.
    pub substeps: usize,
    /// Conjugate-gradient steps of all projections.
    pub cg_steps: usize,
}

impl RunSummary {
    /// Medians over the frames of t_d, t_a and t_p, seconds (Table 1's stage columns).
    pub fn stage_medians(&self) -> [f64; 3] {
        [0, 1, 2].map(|i| {
            let mut v: Vec<f64> = self.stage_seconds.iter().map(|s| s[i]).collect();
            crate::bench::median_f64(&mut v)
        })
    }

    /// Conjugate-gradient steps per projection, on average.
    pub fn cg_steps_per_frame(&self) -> f64 {
        self.cg_steps as f64 / self.frames.max(1) as f64
    }
}

/// The momentum `p = V(g) u` of a state (the snapshot's `p`).
pub fn momentum(solver: &FluidSolver, state: &FluidState) -> Vec<f64> {
    let d = solver.mesh().dim();
    let vols = solver.mesh().volumes_at(&state.g);
    state.u.iter().enumerate().map(|(i, u)| vols[i / d] * u).collect()
}

/// Simulates `frames` frames of `scene` in the full space and writes every frame (the initial
/// state first) to the snapshot directory `out` (refused if it holds snapshots, unless
/// `overwrite`). `on_frame(frame, solver, state, report)` is called after each frame is written.
pub fn simulate_run(
    scene: &mut FluidScene,
    frames: usize,
    out: &Path,
    overwrite: bool,
    on_frame: &mut dyn FnMut(usize, &FluidSolver, &FluidState, &StepReport),
) -> Result<RunSummary, FluidError> {
    scene.check_frames(frames)?;
    let setup = RunSetup {
        mesh: scene.mesh.clone(),
        topology: scene.topology.clone(),
        params: scene.params,
        initial_velocity: scene.initial_velocity.clone(),
        periodic_axis: scene.periodic_axis,
    };
    simulate_with(&setup, frames, &mut |k| scene.geometry(k), out, overwrite, on_frame)
}

/// Simulates the cavity scene `scene` driven by `schedule` — its three compressions per frame,
/// a motion no training run needs to have made — for `frames` frames into the snapshot
/// directory `out` (as [`simulate_run`]): the full run a driven reduced run
/// ([`super::reduced::run_driven`]) is compared with. Refused for a scene that is not a cavity.
pub fn simulate_driven(
    scene: &mut FluidScene,
    schedule: &super::reduced::CompressionSchedule,
    frames: usize,
    out: &Path,
    overwrite: bool,
    on_frame: &mut dyn FnMut(usize, &FluidSolver, &FluidState, &StepReport),
) -> Result<RunSummary, FluidError> {
    scene.check_frames(frames)?;
    let super::scene::Motion::Cavity { cavity, .. } = &mut scene.motion else {
        return Err(FluidError::State(
            "--drive moves the cavity's small cavities: give a cavity scene (e.g. scenes/fluid/cavity_small.toml)"
                .into(),
        ));
    };
    let setup = RunSetup {
        mesh: scene.mesh.clone(),
        topology: scene.topology.clone(),
        params: scene.params,
        initial_velocity: scene.initial_velocity.clone(),
        periodic_axis: scene.periodic_axis,
    };
    let mut geometry = |k: usize| Ok(cavity.geometry(schedule.at(k), k)?);
    simulate_with(&setup, frames, &mut geometry, out, overwrite, on_frame)
}

/// What a run starts from: the mesh at frame 0, its topology, parameters and initial velocity.
#[derive(Clone, Debug)]
pub struct RunSetup {
    /// The mesh at frame 0.
    pub mesh: crate::mesh::SimplexMesh,
    /// Its topology.
    pub topology: crate::mesh::Topology,
    /// Solver parameters.
    pub params: super::FluidParams,
    /// Initial velocity (projected to be divergence-free first).
    pub initial_velocity: Vec<f64>,
    /// The periodic axis, recorded in the header.
    pub periodic_axis: Option<usize>,
}

/// [`simulate_run`] for any motion: `geometry(frame)` gives the geometry vector of each frame.
pub fn simulate_with(
    setup: &RunSetup,
    frames: usize,
    geometry: &mut dyn FnMut(usize) -> Result<Vec<f64>, FluidError>,
    out: &Path,
    overwrite: bool,
    on_frame: &mut dyn FnMut(usize, &FluidSolver, &FluidState, &StepReport),
) -> Result<RunSummary, FluidError> {
    let (mesh, topo) = (&setup.mesh, &setup.topology);
    let t_setup = Instant::now();
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), setup.params)?;
    let mut state = solver.initial_state(mesh.g().to_vec(), &setup.initial_velocity)?;
    let mut summary = RunSummary { setup_seconds: t_setup.elapsed().as_secs_f64(), ..RunSummary::default() };
    let meta = SnapshotMeta::new(mesh, topo, setup.params.frame_time, setup.periodic_axis)
        .with_params(&setup.params);
    let mut writer = SnapshotWriter::create(out, meta, mesh.cells(), overwrite)?;
    writer.push(&state.u, &momentum(&solver, &state), &state.f, &state.g, &vec![0.0; topo.face_count()])?;
    let e0 = solver.energy(&state);
    for frame in 1..=frames {
        let t0 = Instant::now();
        let g = geometry(frame)?;
        let td = t0.elapsed().as_secs_f64();
        let (next, report) = solver.step(&state, &g, frame)?;
        writer.push(&next.u, &momentum(&solver, &next), &next.f, &next.g, &report.h)?;
        summary.stage_seconds.push([td, report.advection_seconds, report.projection_seconds]);
        summary.worst_divergence = summary.worst_divergence.max(report.projection.relative_divergence);
        summary.substeps = report.substeps;
        summary.cg_steps += report.projection.cg_steps;
        state = next;
        summary.frames = frame;
        on_frame(frame, &solver, &state, &report);
    }
    summary.energy = (e0, solver.energy(&state));
    Ok(summary)
}
