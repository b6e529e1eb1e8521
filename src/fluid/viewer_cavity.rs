//! The reduced cavity in the interactive viewer (feature `viewer`; seed 000 §7.2, Fig. 6): the
//! reduced simulation stepping live, driven by the user. Keys `1`, `2`, `3` compress or release
//! a small cavity (its compression moves towards 0.5 or back to 0 over about half a second of
//! frames; any combination, trained or not — [`super::reduced::cavity_motion`]); space pauses,
//! `r` resets to rest, `p` reseeds the particles. Each frame the reduced step runs on the CPU
//! (ĥ from the reduced induced-flux tensor), the particles are advected on the device from the
//! reduced state alone (§6.5, [`super::gpu::GpuParticles::new_reduced`], recorded into the
//! frame) and drawn as sprites coloured by their speed, over the domain's walls drawn as a
//! depth-tested cutaway (far walls seen through the near ones). The title shows the frame,
//! the compressions, the error the unseen-velocity indicator estimates
//! ([`super::reduced::unseen`]; models trained before it lack it), the step's time and the
//! particle pass's device time.

use std::time::Instant;

use anyhow::{anyhow, bail, Result};

use super::gpu::GpuParticles;
use super::particles::{seed_particles, Particle};
use super::reduced::particles::ReducedParticles;
use super::reduced::unseen::UnseenIndicator;
use super::reduced::{CavityMotion, ReducedFluid, ReducedFluidModel, ReducedState};
use super::render::{surface_vertices, DrawStyle, FluidRenderer, Output, ParticleSet, Projection};
use crate::gpu::{Gpu, Profiler, Recorder};
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// How far a compression moves towards its target per frame.
const COMPRESS_RATE: f64 = 0.02;
/// The compression a pressed cavity moves to.
const COMPRESSED: f64 = 0.5;
/// Euler substeps of the particles per frame (the seed's ten).
const SUBSTEPS: usize = 10;

/// The viewer's reduced cavity.
pub struct CavityContent {
    model: ReducedFluidModel,
    fluid: ReducedFluid,
    motion: CavityMotion,
    reference: ReducedParticles,
    state: ReducedState,
    rest: ReducedState,
    amounts: [f64; 3],
    targets: [f64; 3],
    /// Each cavity's largest trained compression (the title says when the user goes beyond).
    trained: Option<[f64; 3]>,
    particle_count: usize,
    /// The frame to advect the particles through (ĝ_t, ĝ_{t+1}, f̂_{t+1}), recorded next.
    pending: Option<(Vec<f64>, Vec<f64>, Vec<f64>)>,
    particles: Option<GpuParticles>,
    renderer: Option<FluidRenderer>,
    particle_set: Option<ParticleSet>,
    profiler: Option<Profiler>,
    gpu: Option<Gpu>,
    style: DrawStyle,
    camera: Camera,
    size: (u32, u32),
    playing: bool,
    frame: usize,
    step_ms: f64,
    particle_ms: f64,
    fps: f64,
    /// Frames presented and their seconds, for the summary's mean rate.
    shown: (usize, f64),
    walls_dirty: bool,
    /// The unseen-velocity indicator, where the model carries its Gram matrices.
    indicator: Option<UnseenIndicator>,
    /// The indicator's estimate at the current frame.
    estimate: Option<f64>,
}

impl CavityContent {
    /// Plays the cavity model `model` (trained by `galerkin fluid train-scene` from a cavity
    /// scene) from rest with `particles` markers.
    pub fn new(model: ReducedFluidModel, particles: usize, size: (u32, u32), playing: bool) -> Result<Self> {
        if model.dim != 3 {
            bail!("the cavity viewer shows 3D cavity models ({}D given)", model.dim);
        }
        let motion = model.cavity.clone().ok_or_else(|| {
            anyhow!(
                "the model has no cavity motion model: train it with `fluid train-scene` from a cavity scene"
            )
        })?;
        let fluid = ReducedFluid::new(&model)?;
        let reference = ReducedParticles::new(&model)?;
        let g = motion.geometry([0.0; 3])?;
        let rest = ReducedState { u: vec![0.0; model.dim_of("u")], f: vec![0.0; model.dim_of("f")], g };
        let (lo, hi) = reference.mesh().bounds();
        let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
        let span = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let camera = Camera {
            eye: [centre[0] + 0.35 * span, centre[1] - 1.1 * span, centre[2] + 0.9 * span],
            target: centre,
            ..Camera::default()
        };
        let style = DrawStyle {
            colormap: Colormap::viridis(),
            range: (0.0, 2.0),
            log: false,
            colour_cells: false,
            sprite_px: 1.5,
        };
        let trained = model.trained_compressions();
        Ok(Self {
            indicator: UnseenIndicator::new(&model).ok(),
            estimate: None,
            trained,
            model,
            fluid,
            motion,
            reference,
            state: rest.clone(),
            rest,
            amounts: [0.0; 3],
            targets: [0.0; 3],
            particle_count: particles,
            pending: None,
            particles: None,
            renderer: None,
            particle_set: None,
            profiler: None,
            gpu: None,
            style,
            camera,
            size,
            playing,
            frame: 0,
            step_ms: 0.0,
            particle_ms: 0.0,
            fps: 0.0,
            shown: (0, 0.0),
            walls_dirty: true,
        })
    }

    /// The compressions the cavities are at.
    pub fn compressions(&self) -> [f64; 3] {
        self.amounts
    }

    /// The compressions the cavities move towards (what the keys set).
    pub fn targets(&self) -> [f64; 3] {
        self.targets
    }

    /// The current reduced state.
    pub fn state(&self) -> &ReducedState {
        &self.state
    }

    /// The particles seeded at rest.
    fn seeds(&self) -> Vec<Particle> {
        seed_particles(self.reference.mesh(), self.particle_count)
    }

    /// One reduced step: the compressions move towards their targets, ĝ follows from them, ĥ
    /// from the reduced induced-flux tensor.
    pub fn step(&mut self) -> Result<()> {
        let start = Instant::now();
        for (a, t) in self.amounts.iter_mut().zip(self.targets) {
            *a += (t - *a).clamp(-COMPRESS_RATE, COMPRESS_RATE);
        }
        let g1 = self.motion.geometry(self.amounts)?;
        let h1 = self
            .fluid
            .induced_flux(&self.state.g, &g1)
            .ok_or_else(|| anyhow!("the model has no induced-flux tensor H (retrain it)"))?;
        let (next, report) = self.fluid.step(&self.state, &g1, &h1)?;
        if let Some(indicator) = &mut self.indicator {
            self.estimate = Some(
                indicator.observe_step(&self.fluid, &self.state, &next, &report, self.frame + 1)?.estimate,
            );
        }
        let g0 = std::mem::replace(&mut self.state, next).g;
        // The walls are lifted and rebuilt only when the geometry moved (compressions settled
        // leave ĝ unchanged).
        self.walls_dirty |= g0 != self.state.g;
        self.pending = Some((g0, self.state.g.clone(), self.state.f.clone()));
        self.frame += 1;
        self.step_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(())
    }

    fn upload_walls(&mut self) -> Result<()> {
        let Some(r) = &mut self.renderer else { return Ok(()) };
        let g = self.model.basis("g").ok_or_else(|| anyhow!("the model has no basis g"))?.lift(&self.state.g);
        let walls = surface_vertices(self.reference.mesh(), self.reference.topology(), &g, self.camera.eye);
        r.update(&walls, &[])?;
        Ok(())
    }
}

impl ViewerContent for CavityContent {
    fn legend(&self) -> Option<crate::plot::ColourBar<'_>> {
        Some(self.style.colour_bar())
    }

    fn title(&self) -> String {
        let a = self.amounts;
        let beyond = self.trained.and_then(|t| super::reduced::cavity_motion::beyond_training(t, a));
        format!(
            "galerkin fluid — reduced cavity (m_u {}, m_f {}) — frame {}, compressions {:.2}/{:.2}/{:.2}{}{} — step {:.2} ms, {} particles {:.2} ms — {:.0} FPS{}",
            self.model.dim_of("u"),
            self.model.dim_of("f"),
            self.frame,
            a[0],
            a[1],
            a[2],
            if beyond.is_some() { " (beyond the training)" } else { "" },
            self.estimate.map_or(String::new(), |e| format!(" — estimated error {:.1} %", 100.0 * e)),
            self.step_ms,
            self.particle_count,
            self.particle_ms,
            self.fps,
            if self.playing { "" } else { " — paused (space plays)" }
        )
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        self.camera
    }

    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()> {
        let particles = GpuParticles::new_reduced(gpu, &self.reference, &self.seeds())?;
        let faces = self.reference.topology().boundary_faces().len();
        let renderer =
            FluidRenderer::new(gpu, target.render_pass(), Output::Colour, &self.style.colormap, faces, 1)?;
        self.particle_set = Some(renderer.own_speed_set(gpu, &particles)?);
        self.particles = Some(particles);
        self.renderer = Some(renderer);
        self.profiler = Profiler::new(gpu, 1).ok();
        self.gpu = Some(gpu.clone());
        self.walls_dirty = true;
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if seconds > 0.0 {
            self.fps = 0.9 * self.fps + 0.1 / seconds.max(1e-6);
            self.shown = (self.shown.0 + 1, self.shown.1 + seconds);
        }
        if let Some(ms) =
            self.profiler.as_ref().and_then(|p| p.results().ok()).and_then(|r| r.first().map(|s| s.1))
        {
            self.particle_ms = ms;
        }
        if self.playing {
            self.step()?;
        }
        if std::mem::take(&mut self.walls_dirty) {
            self.upload_walls()?;
        }
        Ok(self.playing)
    }

    fn record_prepass(&mut self, rec: &mut Recorder<'_>, _: &RenderTarget, _: &Camera) -> Result<()> {
        let (Some(p), Some((g0, g1, f))) = (&self.particles, self.pending.take()) else { return Ok(()) };
        let frame_time = self.model.frame_time;
        let advect = |rec: &mut Recorder<'_>| -> Result<()> {
            p.record_reduced_frame(rec, &g0, &g1, &f)?;
            p.record_advect(rec, frame_time, SUBSTEPS)?;
            Ok(())
        };
        match &mut self.profiler {
            Some(profiler) => {
                profiler.record_reset(rec);
                profiler.scope(rec, "particles", advect)
            }
            None => advect(rec),
        }
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let (Some(r), Some(p)) = (&self.renderer, &self.particles) {
            let projection = Projection::Perspective(*camera);
            r.record(
                rec,
                target.extent(),
                &projection,
                &self.style,
                self.particle_set.as_ref().map(|s| (s, p.count())),
            );
        }
        Ok(())
    }

    fn key(&mut self, key: &str) -> bool {
        match key {
            "1" | "2" | "3" => {
                let i = usize::from(key.as_bytes()[0] - b'1');
                self.targets[i] = if self.targets[i] > 0.0 { 0.0 } else { COMPRESSED };
                if !self.playing {
                    self.playing = true;
                }
            }
            " " => self.playing = !self.playing,
            "r" => {
                self.state = self.rest.clone();
                self.amounts = [0.0; 3];
                self.targets = [0.0; 3];
                self.frame = 0;
                self.pending = None;
                self.walls_dirty = true;
                if let Some(indicator) = &mut self.indicator {
                    indicator.restart();
                }
                self.estimate = None;
                return self.reseed();
            }
            "p" => return self.reseed(),
            _ => return false,
        }
        true
    }

    fn summary(&self) -> Option<String> {
        let a = self.amounts;
        Some(format!(
            "fluid: reduced cavity, {} particles, stopped at frame {} with compressions {:.2}/{:.2}/{:.2} (last step {:.2} ms, particles {:.2} ms; {:.1} frames per second over {} frames)",
            self.particle_count,
            self.frame,
            a[0],
            a[1],
            a[2],
            self.step_ms,
            self.particle_ms,
            self.shown.0 as f64 / self.shown.1.max(1e-9),
            self.shown.0
        ))
    }
}

impl CavityContent {
    /// Puts the particles back at their seeds; false if the device refused.
    fn reseed(&mut self) -> bool {
        let seeds = self.seeds();
        match (&mut self.particles, &self.gpu) {
            (Some(p), Some(gpu)) => p.upload(gpu, &seeds).is_ok(),
            _ => true,
        }
    }
}
