//! The spacetime renderer's frame benchmark (seed 003; the 30 FPS goal): frames as an
//! interactive loop runs them — the slice redone at an advancing `t`, drawn at the target's
//! size — timed on the wall clock (submission to completion, counters read back, no image
//! readback) and per stage with timestamp queries (cut, subdivide, draw). Medians.

use std::time::Instant;

use super::median_f64;
use crate::gpu::{Gpu, Profiler};
use crate::render::{ColorFormat, RenderTarget};
use crate::spacetime::{SpacetimeError, SpacetimeRenderer, SpacetimeView};

/// Medians over the frames of one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameReport {
    /// Frames measured.
    pub frames: usize,
    /// Elements in the active range (median).
    pub active: f64,
    /// Slice triangles drawn (median).
    pub triangles: f64,
    /// Wall time per frame, ms.
    pub wall_ms: f64,
    /// Device time of the cut, ms.
    pub slice_ms: f64,
    /// Device time of the quadrisection, ms.
    pub subdivide_ms: f64,
    /// Device time of the render pass, ms.
    pub draw_ms: f64,
    /// Frames in which elements were streamed to the device.
    pub streaming_frames: usize,
}

impl FrameReport {
    /// Frames per second from the median wall time.
    pub fn fps(&self) -> f64 {
        1e3 / self.wall_ms
    }
}

/// Renders `frames` frames of `view` at `width`×`height` with `t` advancing evenly over
/// `times` (after `warmup` frames at the first time, which build pipelines and fill the window).
pub fn measure_frames(
    gpu: &Gpu,
    renderer: &mut SpacetimeRenderer,
    view: &SpacetimeView,
    (width, height): (u32, u32),
    times: [f64; 2],
    frames: usize,
    warmup: usize,
) -> Result<FrameReport, SpacetimeError> {
    let dev = SpacetimeError::device;
    let target = RenderTarget::new(gpu, "spacetime bench", width, height, ColorFormat::Rgba8)
        .map_err(dev("the bench target"))?;
    let mut profiler = Profiler::new(gpu, 4).map_err(dev("timestamp queries"))?;
    for _ in 0..warmup {
        renderer.frame(&target, &SpacetimeView { time: times[0], ..*view }, None)?;
    }
    let mut cols: [Vec<f64>; 6] = Default::default();
    let mut streaming_frames = 0;
    for k in 0..frames {
        let t = times[0] + (times[1] - times[0]) * k as f64 / (frames.max(2) - 1) as f64;
        let start = Instant::now();
        let (stats, stages) =
            renderer.frame(&target, &SpacetimeView { time: t, ..*view }, Some(&mut profiler))?;
        let wall = start.elapsed().as_secs_f64() * 1e3;
        let stages = stages.unwrap_or_default();
        streaming_frames += usize::from(stats.streamed > 0);
        for (c, v) in cols.iter_mut().zip([
            wall,
            stages.slice_ms,
            stages.subdivide_ms,
            stages.draw_ms,
            stats.active as f64,
            stats.triangles as f64,
        ]) {
            c.push(v);
        }
    }
    let [wall, slice, subdivide, draw, active, triangles] = cols.map(|mut c| median_f64(&mut c));
    Ok(FrameReport {
        frames,
        active,
        triangles,
        wall_ms: wall,
        slice_ms: slice,
        subdivide_ms: subdivide,
        draw_ms: draw,
        streaming_frames,
    })
}
