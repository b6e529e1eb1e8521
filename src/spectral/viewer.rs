//! Spectral elements in the interactive viewer (feature `viewer`), seed 002's "scale the data
//! to look at one region in detail" and "animated over time steps" made interactive. Keys:
//! space plays and pauses the time steps, `.` and `,` step; `l` log scale; `p` next palette;
//! `i` more iso-lines, `I` fewer; `e` element edges; `v` per-vertex colour; `r` narrows the
//! colour range to its middle half, `R` restores it. Surfaces orbit with the viewer's camera;
//! planar meshes stay fitted to the window.

use std::sync::Arc;

use anyhow::Result;
use ash::vk;

use super::{fit_camera, SpectralMesh, SpectralRenderer, SpectralView};
use crate::gpu::Gpu;
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// The palettes `p` cycles through.
const PALETTES: [&str; 3] = ["viridis", "cool-warm", "grey"];

/// The viewer's spectral content.
pub struct SpectralContent {
    mesh: Arc<SpectralMesh>,
    renderer: Option<SpectralRenderer>,
    gpu: Option<Gpu>,
    view: SpectralView,
    palette: usize,
    size: (u32, u32),
    playing: bool,
    /// Seconds per time step while playing.
    step_seconds: f64,
    clock: f64,
    frames: u64,
    /// The palette changed: swap the colour map in `update`, when no frame is in flight.
    recolour: bool,
}

impl SpectralContent {
    /// Shows `mesh` as `view` in a `size` window with `palette` (a name of [`PALETTES`] or
    /// another map); `playing` starts stepping through time at once.
    pub fn new(
        mesh: Arc<SpectralMesh>,
        view: SpectralView,
        palette: &str,
        size: (u32, u32),
        playing: bool,
    ) -> Self {
        let palette = PALETTES.iter().position(|p| *p == palette).unwrap_or(0);
        Self {
            mesh,
            renderer: None,
            gpu: None,
            view,
            palette,
            size,
            playing,
            step_seconds: 0.5,
            clock: 0.0,
            frames: 0,
            recolour: false,
        }
    }

    fn steps(&self) -> usize {
        self.mesh.fields[self.view.field].steps.len()
    }

    fn recolour(&mut self) -> Result<()> {
        if let (Some(gpu), Some(r)) = (&self.gpu, self.renderer.as_mut()) {
            r.set_colormap(gpu, &Colormap::by_name(PALETTES[self.palette])?)?;
        }
        Ok(())
    }
}

impl ViewerContent for SpectralContent {
    fn title(&self) -> String {
        let f = &self.mesh.fields[self.view.field];
        let range =
            self.view.range.map_or("auto range".to_string(), |(lo, hi)| format!("[{lo:.3}, {hi:.3}]"));
        format!(
            "galerkin spectral — {} step {}/{} ({}) — {} {}, {}, {} iso-lines{}{}",
            f.name,
            self.view.step,
            self.steps(),
            if self.playing { "playing" } else { "paused" },
            PALETTES[self.palette],
            if self.view.log { "log" } else { "linear" },
            range,
            self.view.isolines,
            if self.view.edges { ", edges" } else { "" },
            if self.view.per_vertex { ", per-vertex colour" } else { ", per-pixel colour" },
        )
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        self.view.camera.unwrap_or_else(|| fit_camera(&self.mesh))
    }

    fn start(&mut self, gpu: &Gpu, _: &RenderTarget) -> Result<()> {
        let colormap = Colormap::by_name(PALETTES[self.palette])?;
        self.renderer = Some(SpectralRenderer::new(gpu, self.mesh.clone(), &colormap)?);
        self.gpu = Some(gpu.clone());
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if std::mem::take(&mut self.recolour) {
            self.recolour()?;
        }
        if self.playing && self.frames > 0 {
            self.clock += seconds.min(0.1);
            while self.clock >= self.step_seconds {
                self.clock -= self.step_seconds;
                self.view.step = (self.view.step + 1) % self.steps();
            }
        }
        self.frames += 1;
        Ok(self.playing)
    }

    fn record_prepass(
        &mut self,
        cmd: vk::CommandBuffer,
        target: &RenderTarget,
        camera: &Camera,
    ) -> Result<()> {
        if let Some(r) = self.renderer.as_mut() {
            let view = SpectralView { camera: Some(*camera), ..self.view.clone() };
            r.record_prepass(cmd, target, &view)?;
        }
        Ok(())
    }

    fn record(&mut self, cmd: vk::CommandBuffer, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let Some(r) = self.renderer.as_mut() {
            let view = SpectralView { camera: Some(*camera), ..self.view.clone() };
            r.record_draw_into(cmd, target, &view)?;
        }
        Ok(())
    }

    fn key(&mut self, key: &str) -> bool {
        let steps = self.steps();
        match key {
            " " => self.playing = !self.playing,
            "." => self.view.step = (self.view.step + 1) % steps,
            "," => self.view.step = (self.view.step + steps - 1) % steps,
            "l" | "L" => self.view.log = !self.view.log,
            "i" => self.view.isolines += 2,
            "I" => self.view.isolines = self.view.isolines.saturating_sub(2),
            "e" | "E" => self.view.edges = !self.view.edges,
            "v" | "V" => self.view.per_vertex = !self.view.per_vertex,
            "r" => {
                let (lo, hi) = match (self.view.range, self.renderer.as_mut()) {
                    (Some(r), _) => r,
                    (None, Some(r)) => r.range(&self.view),
                    (None, None) => return false,
                };
                let q = 0.25 * (hi - lo);
                self.view.range = Some((lo + q, hi - q));
            }
            "R" => self.view.range = None,
            "p" | "P" => {
                self.palette = (self.palette + 1) % PALETTES.len();
                self.recolour = true;
            }
            _ => return false,
        }
        true
    }

    fn summary(&self) -> Option<String> {
        Some(format!("viewer: {} frames, last time step {}", self.frames, self.view.step))
    }
}
