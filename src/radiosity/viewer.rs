//! A radiosity scene in the interactive viewer (feature `viewer`): seed 000 §9's lighting
//! design made interactive, for the two rooms and for OBJ scenes. Keys, in any scene: `1`–`9`
//! choose a design parameter, `[`/`]` lower/raise it (a twentieth of its range); in the two
//! rooms also `w`/`W` narrower/wider windows, `k`/`K` smaller/larger skylight, `d`/`D`
//! narrower/wider door, `t`/`T` less/more ceiling tilt. `f` switches between the reduced model
//! and the full radiosity (with a model), `m` flat/smooth shading, `e`/`E` darker/brighter
//! exposure, space plays and pauses a sweep through the parameters. The title shows the mode,
//! the parameters (the chosen one in brackets), the solve's time and the frame rate.

use super::estimate::{Estimate, DEFAULT_THRESHOLD};
use std::time::Instant;

use anyhow::Result;

use super::any_scene::AnyScene;
use super::reduced::ReducedRadiosity;
use super::render::{display_radiance, scene_vertices, Output, SceneRenderer, Shading, Viewpoint};
use super::{full_radiosity_of, SceneMesh};
use crate::gpu::{Gpu, Recorder};
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, RenderTarget};

/// How the viewer starts.
#[derive(Clone, Debug)]
pub struct ViewSettings {
    /// Design parameters, in the scene's order.
    pub params: Vec<f64>,
    /// Viewpoint (the two rooms; an OBJ scene is seen from outside its bounds).
    pub view: Viewpoint,
    /// Shading.
    pub shading: Shading,
    /// Exposure.
    pub exposure: f64,
    /// Window size.
    pub size: (u32, u32),
    /// Sweep the parameters from the start.
    pub playing: bool,
}

/// The viewer's radiosity content.
pub struct RadiosityContent {
    scene: AnyScene,
    names: Vec<String>,
    model: Option<ReducedRadiosity>,
    params: Vec<f64>,
    /// The parameter `[` and `]` move.
    chosen: usize,
    camera: Camera,
    reduced: bool,
    shading: Shading,
    exposure: f64,
    size: (u32, u32),
    renderer: Option<SceneRenderer>,
    dirty: bool,
    playing: bool,
    clock: f64,
    solve_ms: f64,
    fps: f64,
    frames: u64,
    mesh_faces: usize,
    /// The reduced solution's error estimate and stability check (reduced mode).
    estimate: Option<Estimate>,
    /// The legend's ramp: the tone map's grey levels at the current exposure
    /// ([`crate::render::Colormap::tone_ramp`], as `radiosity render`'s PNG shows it).
    tone: crate::render::Colormap,
}

impl RadiosityContent {
    /// Shows `scene` as `settings` say, reduced when `model` is given; fails if the
    /// parameters are not the scene's (their number, their ranges).
    pub fn new(
        scene: AnyScene,
        model: Option<ReducedRadiosity>,
        settings: ViewSettings,
    ) -> Result<Self, super::RadiosityError> {
        let reduced = model.is_some();
        let ViewSettings { params, view, shading, exposure, size, playing } = settings;
        let mesh = scene.space().mesh(&params)?;
        let camera = scene.camera(&mesh, view);
        Ok(Self {
            names: scene.names(),
            scene,
            model,
            params,
            chosen: 0,
            camera,
            reduced,
            shading,
            exposure,
            size,
            renderer: None,
            dirty: true,
            playing,
            clock: 0.0,
            solve_ms: 0.0,
            fps: 0.0,
            frames: 0,
            mesh_faces: mesh.len(),
            estimate: None,
            tone: super::picture::tone_ramp(exposure),
        })
    }

    /// Solves the current configuration (reduced or full) and uploads its vertices.
    fn solve(&mut self) -> Result<()> {
        let start = Instant::now();
        let mesh: SceneMesh = self.scene.space().mesh(&self.params)?;
        let (mesh, geometry, b) = match (&self.model, self.reduced) {
            (Some(model), true) => {
                let (b, _, estimate) = model.evaluate_estimated(&mesh)?;
                self.estimate = Some(estimate);
                let geometry = mesh.geometry();
                (mesh, geometry, b)
            }
            _ => {
                self.estimate = None;
                let s = full_radiosity_of(mesh, self.scene.space().lights())?;
                (s.mesh, s.geometry, s.radiosity)
            }
        };
        self.solve_ms = start.elapsed().as_secs_f64() * 1e3;
        let radiance = display_radiance(&mesh, &geometry, self.scene.space().lights(), &b);
        let vertices = scene_vertices(&mesh, &geometry, &radiance, self.shading);
        self.mesh_faces = mesh.len();
        if let Some(r) = &mut self.renderer {
            r.update(&vertices)?;
        }
        Ok(())
    }

    fn nudge(&mut self, axis: usize, steps: f64) -> bool {
        let Some(&[lo, hi]) = self.scene.space().ranges().get(axis) else { return false };
        let v = (self.params[axis] + steps * (hi - lo) / 20.0).clamp(lo, hi);
        let changed = v != self.params[axis];
        self.params[axis] = v;
        changed
    }
}

impl ViewerContent for RadiosityContent {
    fn legend(&self) -> Option<crate::plot::ColourBar<'_>> {
        Some(super::picture::tone_bar(&self.tone, self.exposure))
    }

    fn title(&self) -> String {
        let p: Vec<String> = (self.names.iter().zip(&self.params).enumerate())
            .map(|(a, (n, v))| if a == self.chosen { format!("[{n} {v:.2}]") } else { format!("{n} {v:.2}") })
            .collect();
        // The reduced radiosity's trust, by name: its estimated error, or why it is untrusted.
        let trust = match &self.estimate {
            Some(e) => match e.untrusted(DEFAULT_THRESHOLD) {
                Some(why) => format!(" — UNTRUSTED: {why}"),
                None if e.error.is_finite() => format!(", est. error {:.1} %", 100.0 * e.error),
                None => String::new(),
            },
            None => String::new(),
        };
        format!(
            "galerkin radiosity — {} ({:.1} ms{trust}) — {} — {:.0} FPS",
            if self.reduced { "reduced" } else { "full" },
            self.solve_ms,
            p.join(", "),
            self.fps
        )
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        self.camera
    }

    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()> {
        // The topology is fixed: every configuration has the faces counted in `new`.
        self.renderer = Some(SceneRenderer::new(gpu, target.render_pass(), Output::Colour, self.mesh_faces)?);
        self.dirty = true;
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if seconds > 0.0 {
            self.fps = 0.9 * self.fps + 0.1 / seconds.max(1e-6);
        }
        if self.playing && self.frames > 0 {
            // One sweep through the box every 20 s.
            self.clock += seconds.min(0.1);
            let ranges = self.scene.space().ranges();
            let t = self.clock / 20.0;
            for (a, range) in ranges.iter().enumerate() {
                let u = 0.5 + 0.47 * (2.0 * std::f64::consts::PI * (a as f64 + 1.0) * t + a as f64).sin();
                self.params[a] = range[0] + u * (range[1] - range[0]);
            }
            self.dirty = true;
        }
        if std::mem::take(&mut self.dirty) {
            self.solve()?;
        }
        self.frames += 1;
        Ok(self.playing)
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let Some(r) = &self.renderer {
            r.record(rec, target.extent(), camera, self.exposure);
        }
        Ok(())
    }

    fn key(&mut self, key: &str) -> bool {
        let rooms = matches!(self.scene, AnyScene::Rooms(_));
        let changed = match key {
            "[" => self.nudge(self.chosen, -1.0),
            "]" => self.nudge(self.chosen, 1.0),
            digit if digit.len() == 1 && ("1"..="9").contains(&digit) => {
                let a = usize::from(digit.as_bytes()[0] - b'1');
                if a < self.params.len() {
                    self.chosen = a;
                }
                return true;
            }
            "w" if rooms => self.nudge(0, -1.0),
            "W" if rooms => self.nudge(0, 1.0),
            "k" if rooms => self.nudge(1, -1.0),
            "K" if rooms => self.nudge(1, 1.0),
            "d" if rooms => self.nudge(2, -1.0),
            "D" if rooms => self.nudge(2, 1.0),
            "t" if rooms => self.nudge(3, -1.0),
            "T" if rooms => self.nudge(3, 1.0),
            "f" if self.model.is_some() => {
                self.reduced = !self.reduced;
                true
            }
            "m" => {
                self.shading = if self.shading == Shading::Flat { Shading::Smooth } else { Shading::Flat };
                true
            }
            "e" => {
                self.exposure /= 1.25;
                self.tone = super::picture::tone_ramp(self.exposure);
                return true;
            }
            "E" => {
                self.exposure *= 1.25;
                self.tone = super::picture::tone_ramp(self.exposure);
                return true;
            }
            " " => {
                self.playing = !self.playing;
                return true;
            }
            _ => false,
        };
        self.dirty |= changed;
        changed
    }

    fn summary(&self) -> Option<String> {
        let p: Vec<String> =
            self.names.iter().zip(&self.params).map(|(n, v)| format!("{n}={v:.3}")).collect();
        Some(format!(
            "radiosity: {} faces, {} mode, last solve {:.1} ms, at {}",
            self.mesh_faces,
            if self.reduced { "reduced" } else { "full" },
            self.solve_ms,
            p.join(",")
        ))
    }
}
