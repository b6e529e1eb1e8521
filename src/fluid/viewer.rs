//! A 2D fluid scene in the interactive viewer (feature `viewer`): the simulation runs one
//! frame per displayed frame (full space, seed 000 §5), the particles are advected on the
//! device (§6.5) and drawn over the cells. Keys: space plays and pauses, `c` colours the
//! cells by speed (particles white) or not (particles coloured), `r` restarts. The title
//! shows the frame, the step's time and the frame rate.

use std::time::Instant;

use anyhow::{bail, Result};
use ash::vk;

use super::gpu::GpuParticles;
use super::particles::seed_particles;
use super::render::{cell_speeds, cell_vertices, DrawStyle, FluidRenderer, Output, Projection, View2d};
use super::scene::FluidScene;
use super::{FluidSolver, FluidState};
use crate::gpu::{DescriptorSet, Gpu};
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// The viewer's fluid content.
pub struct FluidContent {
    scene: FluidScene,
    solver: FluidSolver,
    state: FluidState,
    initial: FluidState,
    particle_count: usize,
    particles: Option<GpuParticles>,
    renderer: Option<FluidRenderer>,
    particle_set: Option<DescriptorSet>,
    gpu: Option<Gpu>,
    style: DrawStyle,
    size: (u32, u32),
    playing: bool,
    frame: usize,
    step_ms: f64,
    fps: f64,
    dirty: bool,
}

impl FluidContent {
    /// Shows `scene` (2D) with `particles` markers, playing from the start if `playing`.
    pub fn new(scene: FluidScene, particles: usize, size: (u32, u32), playing: bool) -> Result<Self> {
        if scene.mesh.dim() != 2 {
            bail!("the fluid viewer shows 2D scenes so far ({}D given)", scene.mesh.dim());
        }
        let mut solver = FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params)?;
        let state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity)?;
        let top =
            cell_speeds(&scene.mesh, &scene.topology, &state.g, &state.f).into_iter().fold(0.0f64, f64::max);
        let style = DrawStyle {
            colormap: Colormap::viridis(),
            range: (0.0, (1.5 * top).max(1e-9)),
            log: false,
            colour_cells: false,
            sprite_px: 1.5,
        };
        Ok(Self {
            scene,
            solver,
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
        })
    }

    fn upload_cells(&mut self) {
        let (mesh, topo) = (&self.scene.mesh, &self.scene.topology);
        let speeds = cell_speeds(mesh, topo, &self.state.g, &self.state.f);
        let vertices = cell_vertices(mesh, &self.state.g, &speeds);
        if let Some(r) = &mut self.renderer {
            r.update(&vertices, &speeds);
        }
    }

    fn step(&mut self) -> Result<()> {
        let gpu = self.gpu.as_ref().expect("started");
        let start = Instant::now();
        self.frame += 1;
        let g = self.scene.geometry(self.frame)?;
        let (next, _) = self.solver.step(&self.state, &g, self.frame)?;
        if let Some(p) = &mut self.particles {
            p.advect(
                gpu,
                &self.scene.mesh,
                &self.state.g,
                &next.g,
                &next.f,
                self.scene.params.frame_time,
                10,
            )?;
        }
        self.state = next;
        self.step_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }
}

impl ViewerContent for FluidContent {
    fn title(&self) -> String {
        format!(
            "galerkin fluid — {} — frame {} (step {:.1} ms) — {:.0} FPS{}",
            self.scene.description,
            self.frame,
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
        let mesh = &self.scene.mesh;
        let seeds = seed_particles(mesh, self.particle_count);
        let particles = GpuParticles::new(gpu, mesh, &self.scene.topology, &seeds)?;
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
            self.upload_cells();
        }
        Ok(self.playing)
    }

    fn record(&mut self, cmd: vk::CommandBuffer, target: &RenderTarget, _: &Camera) -> Result<()> {
        let (lo, hi) = self.scene.mesh.bounds();
        let extent = target.extent();
        let view = View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], (extent.width, extent.height), 0.02);
        if let (Some(r), Some(p)) = (&self.renderer, &self.particles) {
            let projection = Projection::Plane(view);
            r.record(
                cmd,
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
                let seeds = seed_particles(&self.scene.mesh, self.particle_count);
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
            self.scene.mesh.cell_count(),
            self.particle_count,
            self.frame,
            self.step_ms
        ))
    }
}
