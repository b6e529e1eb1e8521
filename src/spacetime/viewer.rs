//! Spacetime data in the interactive viewer (feature `viewer`): the slice at an animated time.
//! Keys: space plays and pauses, `.` and `,` step t forward and back by 1/200 of the span,
//! `]` and `[` double and halve the playback speed, `h` height, `e` edges, `v` per-vertex
//! colour, `d` subdivision on and off. The colour ramp's U_max is fixed when the window opens
//! (the view's, or the largest U of the first frame), so colours are comparable as t moves.

use anyhow::Result;

use super::{SpacetimeData, SpacetimeRenderer, SpacetimeView};
use crate::gpu::{Gpu, Recorder};
use crate::plot::ColourBar;
use crate::render::viewer::ViewerContent;
use crate::render::{Camera, Colormap, RenderTarget};

/// The viewer's spacetime content.
pub struct SpacetimeContent {
    data: Option<SpacetimeData>,
    renderer: Option<SpacetimeRenderer>,
    colormap: Colormap,
    view: SpacetimeView,
    span: [f64; 2],
    size: (u32, u32),
    playing: bool,
    /// Time units per second of playback.
    speed: f64,
    u_max: f64,
    subdivide_area: f64,
    frames: u64,
    start_time: f64,
}

impl SpacetimeContent {
    /// Shows `data` as `view` in a `size` window; `playing` starts the animation at once.
    pub fn new(
        data: SpacetimeData,
        view: SpacetimeView,
        colormap: Colormap,
        size: (u32, u32),
        playing: bool,
    ) -> Self {
        let span = data.summary().time;
        // A structured-looking default: quadrisect down to 1/100 of the domain squared.
        let subdivide_area = (0.01 * data.summary().size()).powi(2);
        Self {
            data: Some(data),
            renderer: None,
            colormap,
            start_time: view.time,
            view,
            span,
            size,
            playing,
            // The whole span in 10 s.
            speed: (span[1] - span[0]) / 10.0,
            u_max: view.u_max.unwrap_or(1.0),
            subdivide_area,
            frames: 0,
        }
    }

    fn step(&mut self, dt: f64) {
        let [t0, t1] = self.span;
        let mut t = self.view.time + dt;
        if t > t1 {
            t = t0 + (t - t1) % (t1 - t0).max(f64::MIN_POSITIVE);
        } else if t < t0 {
            t = t1 - (t0 - t) % (t1 - t0).max(f64::MIN_POSITIVE);
        }
        self.view.time = t;
    }
}

impl ViewerContent for SpacetimeContent {
    fn title(&self) -> String {
        let on = |b: bool, name: &str| if b { name.to_string() } else { format!("no {name}") };
        format!(
            "galerkin spacetime — t = {:.4} ({}, ×{:.3}/s) — {}, {}, {}{}",
            self.view.time,
            if self.playing { "playing" } else { "paused" },
            self.speed,
            on(self.view.height, "height"),
            on(self.view.edges, "edges"),
            if self.view.per_vertex { "per-vertex colour" } else { "per-pixel colour" },
            if self.view.subdivide.is_some() { ", subdivided" } else { "" }
        )
    }

    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn camera(&self) -> Camera {
        self.view.camera
    }

    fn start(&mut self, gpu: &Gpu, target: &RenderTarget) -> Result<()> {
        let data = self.data.take().ok_or_else(|| anyhow::anyhow!("the viewer started twice"))?;
        let mut renderer = SpacetimeRenderer::new(gpu, data, &self.colormap)?;
        self.u_max = renderer.u_max_for(target, &self.view)?;
        self.view.u_max = Some(self.u_max);
        self.renderer = Some(renderer);
        Ok(())
    }

    fn update(&mut self, _: &RenderTarget, seconds: f64) -> Result<bool> {
        if self.playing && self.frames > 0 {
            // At most a tenth of a second per frame, so a stall does not jump.
            self.step(self.speed * seconds.min(0.1));
        }
        self.frames += 1;
        if let Some(r) = self.renderer.as_mut() {
            r.slice(self.view.time, self.view.subdivide)?;
        }
        Ok(self.playing)
    }

    fn record(&mut self, rec: &mut Recorder<'_>, target: &RenderTarget, camera: &Camera) -> Result<()> {
        if let Some(r) = self.renderer.as_mut() {
            let view = SpacetimeView { camera: *camera, ..self.view };
            r.record_draw_into(rec, target.draw_target(), &view, self.u_max)?;
        }
        Ok(())
    }

    fn legend(&self) -> Option<ColourBar<'_>> {
        (self.renderer.is_some() && self.u_max > 0.0)
            .then(|| super::picture::colour_bar(&self.colormap, self.u_max))
    }

    fn key(&mut self, key: &str) -> bool {
        let step = (self.span[1] - self.span[0]) / 200.0;
        match key {
            " " => self.playing = !self.playing,
            "." => self.step(step),
            "," => self.step(-step),
            "]" => self.speed *= 2.0,
            "[" => self.speed *= 0.5,
            "h" | "H" => self.view.height = !self.view.height,
            "e" | "E" => self.view.edges = !self.view.edges,
            "v" | "V" => self.view.per_vertex = !self.view.per_vertex,
            "d" | "D" => {
                self.view.subdivide = match self.view.subdivide {
                    Some(_) => None,
                    None => Some(self.subdivide_area),
                }
            }
            _ => return false,
        }
        true
    }

    fn summary(&self) -> Option<String> {
        Some(format!(
            "viewer: {} frames, t from {:.4} to {:.4}",
            self.frames, self.start_time, self.view.time
        ))
    }
}
