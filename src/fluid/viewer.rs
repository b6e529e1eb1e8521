//! A 2D fluid scene in the interactive viewer (feature `viewer`): the simulation runs one
//! frame per displayed frame — the full solver (seed 000 §5) on a scene, or a reduced model
//! (§6) replaying a training run's motion, its state lifted for drawing — the particles are
//! advected on the device (§6.5) and drawn over the cells. Keys: space plays and pauses, `c` colours the
//! cells by speed (particles white) or not (particles coloured), `r` restarts. The title
//! shows the frame, the step's time and the frame rate, and for a reduced model the error the
//! unseen-velocity indicator estimates ([`super::reduced::unseen`]; models trained before it
//! lack it).

use std::time::Instant;

use anyhow::{bail, Result};

use super::gpu::GpuParticles;
use super::particles::seed_particles;
use super::reduced::unseen::UnseenIndicator;
use super::reduced::{ReducedFluid, ReducedFluidModel, ReducedMotion, ReducedState};
use super::render::{
    cell_speeds, cell_vertices, DrawStyle, FluidRenderer, Output, ParticleSet, Projection, View2d,
};
use super::scene::FluidScene;
use super::{FluidSolver, FluidState};
use crate::gpu::{Gpu, Recorder};
use crate::mesh::{SimplexMesh, Topology};
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// What steps the viewer's fluid.
enum Source {
    /// The full solver on a scene.
    Full { scene: Box<FluidScene>, solver: Box<FluidSolver> },
    /// A reduced model replaying training run `run`'s motion.
    Reduced {
        model: Box<ReducedFluidModel>,
        fluid: Box<ReducedFluid>,
        run: usize,
        state: ReducedState,
        /// The unseen-velocity indicator, where the model carries its Gram matrices.
        unseen: Option<Box<UnseenIndicator>>,
    },
}

/// The viewer's fluid content.
pub struct FluidContent {
    source: Source,
    mesh: SimplexMesh,
    topology: Topology,
    frame_time: f64,
    description: String,
    state: FluidState,
    initial: FluidState,
    particle_count: usize,
    particles: Option<GpuParticles>,
    renderer: Option<FluidRenderer>,
    particle_set: Option<ParticleSet>,
    gpu: Option<Gpu>,
    style: DrawStyle,
    size: (u32, u32),
    playing: bool,
    frame: usize,
    step_ms: f64,
    fps: f64,
    dirty: bool,
    /// A reduced model's estimated error at the current frame (the unseen-velocity indicator).
    estimate: Option<f64>,
}

impl FluidContent {
    /// Shows `scene` (2D) with `particles` markers, playing from the start if `playing`.
    pub fn new(scene: FluidScene, particles: usize, size: (u32, u32), playing: bool) -> Result<Self> {
        if scene.mesh.dim() != 2 {
            bail!("the fluid viewer shows 2D scenes so far ({}D given)", scene.mesh.dim());
        }
        let mut solver = FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params)?;
        let state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity)?;
        let (mesh, topology) = (scene.mesh.clone(), scene.topology.clone());
        let (frame_time, description) = (scene.params.frame_time, scene.description.clone());
        let source = Source::Full { scene: Box::new(scene), solver: Box::new(solver) };
        Self::with_source(source, (mesh, topology), frame_time, description, state, particles, size, playing)
    }

    /// Plays a reduced model (2D) under `motion` with `particles` markers.
    pub fn reduced(
        model: ReducedFluidModel,
        motion: ReducedMotion,
        particles: usize,
        size: (u32, u32),
        playing: bool,
    ) -> Result<Self> {
        if model.dim != 2 {
            bail!("the fluid viewer shows 2D models so far ({}D given)", model.dim);
        }
        if let ReducedMotion::Computed(_) = motion {
            bail!("the viewer replays training motions (replay:K) so far");
        }
        let run = motion.run();
        let traj = model.trajectories.get(run).ok_or_else(|| {
            anyhow::anyhow!(
                "{motion}: the model has training runs 0 to {}",
                model.trajectories.len().saturating_sub(1)
            )
        })?;
        let mg = traj.g.shape()[1];
        let reduced =
            ReducedState { u: traj.u0.clone(), f: traj.f0.clone(), g: traj.g.data()[..mg].to_vec() };
        let fluid = ReducedFluid::new(&model)?;
        let (mesh, topology) = model.mesh_and_topology()?;
        let state = lift(&model, &reduced)?;
        let description = format!(
            "reduced model (m_u {}, m_f {}), replaying run {run}",
            model.dim_of("u"),
            model.dim_of("f")
        );
        let frame_time = model.frame_time;
        let unseen = UnseenIndicator::new(&model).ok().map(Box::new);
        let source =
            Source::Reduced { model: Box::new(model), fluid: Box::new(fluid), run, state: reduced, unseen };
        Self::with_source(source, (mesh, topology), frame_time, description, state, particles, size, playing)
    }

    #[allow(clippy::too_many_arguments)]
    fn with_source(
        source: Source,
        (mesh, topology): (SimplexMesh, Topology),
        frame_time: f64,
        description: String,
        state: FluidState,
        particles: usize,
        size: (u32, u32),
        playing: bool,
    ) -> Result<Self> {
        let top = cell_speeds(&mesh, &topology, &state.g, &state.f).into_iter().fold(0.0f64, f64::max);
        let style = DrawStyle {
            colormap: Colormap::viridis(),
            range: (0.0, (1.5 * top).max(1e-9)),
            log: false,
            colour_cells: false,
            sprite_px: 1.5,
        };
        Ok(Self {
            source,
            mesh,
            topology,
            frame_time,
            description,
            initial: state.clone(),
            state,
            particle_count: particles,
            particles: None,
            renderer: None,
            particle_set: None,
            gpu: None,
            style,
            size,
            playing,
            frame: 0,
            step_ms: 0.0,
            fps: 0.0,
            dirty: true,
            estimate: None,
        })
    }

    fn upload_cells(&mut self) -> Result<()> {
        let (mesh, topo) = (&self.mesh, &self.topology);
        let speeds = cell_speeds(mesh, topo, &self.state.g, &self.state.f);
        let vertices = cell_vertices(mesh, &self.state.g, &speeds);
        if let Some(r) = &mut self.renderer {
            r.update(&vertices, &speeds)?;
        }
        Ok(())
    }

    fn step(&mut self) -> Result<()> {
        let gpu = self.gpu.as_ref().expect("started");
        let start = Instant::now();
        let next = match &mut self.source {
            Source::Full { scene, solver } => {
                let g = scene.geometry(self.frame + 1)?;
                solver.step(&self.state, &g, self.frame + 1)?.0
            }
            Source::Reduced { model, fluid, run, state, unseen } => {
                let traj = &model.trajectories[*run];
                let (mg, mh) = (traj.g.shape()[1], traj.h.shape()[1]);
                let t = self.frame + 1;
                if t >= traj.g.shape()[0] {
                    // The replayed motion has ended.
                    self.playing = false;
                    return Ok(());
                }
                let (g1, h1) = (&traj.g.data()[t * mg..(t + 1) * mg], &traj.h.data()[t * mh..(t + 1) * mh]);
                let (next, report) = fluid.step(state, g1, h1)?;
                if let Some(indicator) = unseen {
                    self.estimate = Some(indicator.observe_step(fluid, state, &next, &report, t)?.estimate);
                }
                *state = next;
                lift(model, state)?
            }
        };
        self.frame += 1;
        if let Some(p) = &mut self.particles {
            p.advect(gpu, &self.mesh, &self.state.g, &next.g, &next.f, self.frame_time, 10)?;
        }
        self.state = next;
        self.step_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }
}

impl ViewerContent for FluidContent {
    fn legend(&self) -> Option<crate::plot::ColourBar<'_>> {
        Some(self.style.colour_bar())
    }

    fn title(&self) -> String {
        format!(
            "galerkin fluid — {} — frame {}{} (step {:.2} ms) — {:.0} FPS{}",
            self.description,
            self.frame,
            self.estimate.map_or(String::new(), |e| format!(", estimated error {:.1} %", 100.0 * e)),
            self.step_ms,
            self.fps,
            if self.playing { "" } else { " — paused (space plays)" }
        )
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        Camera::default()
    }

    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()> {
        let mesh = &self.mesh;
        let seeds = seed_particles(mesh, self.particle_count);
        let particles = GpuParticles::new(gpu, mesh, &self.topology, &seeds)?;
        let renderer = FluidRenderer::new(
            gpu,
            target.render_pass(),
            Output::Colour,
            &self.style.colormap,
            mesh.cell_count(),
            mesh.cell_count(),
        )?;
        self.particle_set = Some(renderer.particle_set(gpu, &particles)?);
        self.particles = Some(particles);
        self.renderer = Some(renderer);
        self.gpu = Some(gpu.clone());
        self.dirty = true;
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if seconds > 0.0 {
            self.fps = 0.9 * self.fps + 0.1 / seconds.max(1e-6);
        }
        if self.playing {
            self.step()?;
            self.dirty = true;
        }
        if std::mem::take(&mut self.dirty) {
            self.upload_cells()?;
        }
        Ok(self.playing)
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, _: &Camera) -> Result<()> {
        let (lo, hi) = self.mesh.bounds();
        let extent = target.extent();
        let view = View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], (extent.width, extent.height), 0.02);
        if let (Some(r), Some(p)) = (&self.renderer, &self.particles) {
            let projection = Projection::Plane(view);
            r.record(
                rec,
                extent,
                &projection,
                &self.style,
                self.particle_set.as_ref().map(|s| (s, p.count())),
            );
        }
        Ok(())
    }

    fn key(&mut self, key: &str) -> bool {
        match key {
            " " => self.playing = !self.playing,
            "c" => self.style.colour_cells = !self.style.colour_cells,
            "r" => {
                self.state = self.initial.clone();
                self.frame = 0;
                self.estimate = None;
                if let Source::Reduced { model, run, state, unseen, .. } = &mut self.source {
                    let traj = &model.trajectories[*run];
                    let mg = traj.g.shape()[1];
                    *state = ReducedState {
                        u: traj.u0.clone(),
                        f: traj.f0.clone(),
                        g: traj.g.data()[..mg].to_vec(),
                    };
                    if let Some(indicator) = unseen {
                        indicator.restart();
                    }
                }
                let seeds = seed_particles(&self.mesh, self.particle_count);
                if let (Some(p), Some(gpu)) = (&mut self.particles, &self.gpu) {
                    if p.upload(gpu, &seeds).is_err() {
                        return false;
                    }
                }
                self.dirty = true;
            }
            _ => return false,
        }
        true
    }

    fn summary(&self) -> Option<String> {
        Some(format!(
            "fluid: {} cells, {} particles, stopped at frame {} (last step {:.1} ms)",
            self.mesh.cell_count(),
            self.particle_count,
            self.frame,
            self.step_ms
        ))
    }
}

/// A reduced state lifted to the full space: `g = B_g ĝ`, `u = B_u û`, `f = B_f f̂`.
fn lift(model: &ReducedFluidModel, s: &ReducedState) -> Result<FluidState> {
    let basis = |n: &str| model.basis(n).ok_or_else(|| anyhow::anyhow!("the model has no basis {n}"));
    Ok(FluidState { g: basis("g")?.lift(&s.g), u: basis("u")?.lift(&s.u), f: basis("f")?.lift(&s.f) })
}
