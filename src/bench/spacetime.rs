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

/// What [`report`] measures.
#[derive(Clone, Debug)]
pub struct SpacetimeBench {
    /// Data-set sizes, elements (at least 1000 each).
    pub sizes: Vec<usize>,
    /// The data sets' name (`pulses` or a tent-pitched scenario).
    pub data_set: String,
    /// Where the generated data sets are kept between runs.
    pub data_dir: std::path::PathBuf,
    /// Frames per configuration (medians are reported).
    pub frames: usize,
    /// The out-of-core first frame of a 2·10⁷-element `pulses` file, rendered by this
    /// executable in a fresh process (`None`: skipped).
    pub out_of_core: Option<std::path::PathBuf>,
}

impl SpacetimeBench {
    /// The sizes of the full run (10⁵, 10⁶, 5·10⁶; out of core when `exe` is given) or the
    /// quick one (10⁵, 10⁶).
    pub fn new(quick: bool, data_dir: &std::path::Path, exe: Option<&std::path::Path>) -> Self {
        Self {
            sizes: if quick { vec![100_000, 1_000_000] } else { vec![100_000, 1_000_000, 5_000_000] },
            data_set: "pulses".into(),
            data_dir: data_dir.to_path_buf(),
            frames: 30,
            out_of_core: if quick { None } else { exe.map(std::path::Path::to_path_buf) },
        }
    }
}

/// Seed 003's renderer benchmark as Markdown, section by section through `emit`: frame times
/// (wall and per stage) at 1280×720 at an advancing `t` for each size, the largest with
/// subdivision, without edges and with nothing shaded (the floor), its growth with pixels, and
/// the out-of-core first frame. Data sets are generated into `data_dir` on first use
/// (`progress`: elements generated).
pub fn report(
    gpu: &Gpu,
    bench: &SpacetimeBench,
    progress: &mut dyn FnMut(u64),
    emit: &mut dyn FnMut(&str),
) -> anyhow::Result<()> {
    use crate::render::Colormap;
    use crate::spacetime::{dataset, gst};
    macro_rules! say {
        ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
    }
    anyhow::ensure!(bench.frames > 0, "the frame count must be positive");
    if let Some(&n) = bench.sizes.iter().find(|&&n| n < 1000) {
        anyhow::bail!("{n} elements: data sets start at 1000 elements");
    }
    let (largest_n, rest) = bench.sizes.split_last().ok_or_else(|| anyhow::anyhow!("no data-set sizes"))?;
    let c = gpu.caps();
    say!("Device: {} ({}). Frames at an advancing t (0.3 → 0.7 of the span), height and edges on, U_max 0.05; medians of {} frames.\n", c.device_name, c.driver, bench.frames);
    let header = "| elements | active | triangles | size | subdivide | frame (wall) | FPS | slice | subdivide | draw | frames streaming |\n|---:|---:|---:|---|---|---:|---:|---:|---:|---:|---:|";
    let row = |n: usize, size: (u32, u32), sub: Option<f64>, r: &FrameReport| {
        format!(
            "| {n} | {:.0} | {:.0} | {}×{} | {} | {:.1} ms | {:.1} | {:.2} ms | {:.2} ms | {:.1} ms | {}/{} |\n",
            r.active,
            r.triangles,
            size.0,
            size.1,
            sub.map_or("off".into(), |a| format!("{a:.1e}")),
            r.wall_ms,
            r.fps(),
            r.slice_ms,
            r.subdivide_ms,
            r.draw_ms,
            r.streaming_frames,
            r.frames
        )
    };
    say!("{header}");
    let colormap = Colormap::viridis();
    let hd = (1280, 720);
    let open = |n: usize, progress: &mut dyn FnMut(u64)| -> anyhow::Result<_> {
        let path = dataset::cached(&bench.data_dir, &bench.data_set, n, progress)?;
        let data = gst::open(&path)?;
        let [t0, t1] = data.summary().time;
        let view = SpacetimeView { u_max: Some(0.05), ..SpacetimeView::looking_at(data.summary(), t0) };
        let times = [t0 + 0.3 * (t1 - t0), t0 + 0.7 * (t1 - t0)];
        Ok((SpacetimeRenderer::new(gpu, data, &colormap)?, view, times))
    };
    // Rows name the elements the data set has (the generators round the size asked for).
    for &n in rest {
        let (mut r, view, times) = open(n, progress)?;
        let elements = r.data().len();
        emit(&row(elements, hd, None, &measure_frames(gpu, &mut r, &view, hd, times, bench.frames, 3)?));
    }
    let (mut r, view, times) = open(*largest_n, progress)?;
    let n = r.data().len();
    let base = measure_frames(gpu, &mut r, &view, hd, times, bench.frames, 3)?;
    emit(&row(n, hd, None, &base));
    // Subdivision: triangles larger than the mean slice triangle (over the bounding box) are
    // quadrisected.
    let area = r.data().summary().size().powi(2) / base.triangles.max(1.0);
    let sub = SpacetimeView { subdivide: Some(area), ..view };
    emit(&row(n, hd, Some(area), &measure_frames(gpu, &mut r, &sub, hd, times, bench.frames, 2)?));
    let no_edges = SpacetimeView { edges: false, ..view };
    let rep = measure_frames(gpu, &mut r, &no_edges, hd, times, bench.frames, 2)?;
    say!("\nWithout edge overdraw: {:.1} ms per frame, draw {:.1} ms.", rep.wall_ms, rep.draw_ms);
    // The floor: the same triangles with nothing evaluated per pixel and no edges — what the
    // slicing and the rasteriser cost by themselves, before any shading.
    let floor = SpacetimeView { unshaded: true, ..no_edges };
    let rep = measure_frames(gpu, &mut r, &floor, hd, times, bench.frames, 2)?;
    say!(
        "The floor (one constant colour per pixel, nothing evaluated, no edges): {:.1} ms per frame, slice {:.2} ms, subdivide {:.2} ms, draw {:.1} ms.",
        rep.wall_ms,
        rep.slice_ms,
        rep.subdivide_ms,
        rep.draw_ms
    );
    say!("\nGrowth with pixels ({n} elements):\n\n{header}");
    for size in [(320, 180), (640, 360), hd, (1920, 1080)] {
        let rep =
            if size == hd { base } else { measure_frames(gpu, &mut r, &view, size, times, bench.frames, 2)? };
        emit(&row(n, size, None, &rep));
    }
    drop(r);
    if let Some(exe) = &bench.out_of_core {
        let path = dataset::cached(&bench.data_dir, "pulses", 20_000_000, progress)?;
        let out = bench.data_dir.join("out-of-core.png");
        let start = Instant::now();
        let status = std::process::Command::new(exe)
            .args(["spacetime", "render"])
            .arg(&path)
            .args(["--time", "0.2", "--umax", "0.05", "--out"])
            .arg(&out)
            .status()
            .map_err(|e| anyhow::anyhow!("running {} for the out-of-core frame: {e}", exe.display()))?;
        anyhow::ensure!(status.success(), "the out-of-core frame failed ({status})");
        say!(
            "\nOut of core: the first frame of {} in a fresh process (Vulkan start-up included): {:.2} s wall.",
            path.display(),
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
