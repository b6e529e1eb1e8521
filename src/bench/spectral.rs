//! `galerkin spectral bench`: seed 002's table — frames per second of the artery-like tube
//! (704 curved elements) and the coil-like helix (3332) at 1024×768, orders 1–8, per pixel
//! against per vertex in the same run — and frame time against pixels and elements. Device
//! time from timestamps, medians.

use std::sync::Arc;

use anyhow::{bail, Result};

use crate::gpu::Gpu;
use crate::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use crate::spectral::{generate, NodeSet, SpectralRenderer, SpectralView};

fn median(mut v: Vec<f64>) -> f64 {
    crate::bench::median_f64(&mut v)
}

/// The median device times (ms) of two views drawn in turn, frame by frame, `frames` times
/// after `warmup` unmeasured rounds, so the machine's drift hits both alike.
pub(crate) fn interleaved_medians(
    renderer: &mut SpectralRenderer,
    target: &RenderTarget,
    views: [&SpectralView; 2],
    frames: usize,
    warmup: usize,
    profiler: &mut crate::gpu::Profiler,
) -> Result<(f64, f64)> {
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for round in 0..frames + warmup {
        let ta = renderer.frame(target, views[0], profiler)?;
        let tb = renderer.frame(target, views[1], profiler)?;
        if round >= warmup {
            a.push(ta);
            b.push(tb);
        }
    }
    Ok((median(a), median(b)))
}

/// A ray-cast view (isosurfaces, volumes) of one solid mesh against the cut-plane frame of the
/// same mesh, image and camera: the median device times (ms) of `frames` frames of each at
/// `timed` (the plane z through the mesh's middle, interleaved frame by frame after one
/// unmeasured round), then the view drawn once as data at `checked` for the accuracy check.
/// `what` names the view in the refusal of a mesh that is not hexahedral or tetrahedral.
pub(crate) struct AgainstCutPlane {
    /// Median device time of the cut-plane frame.
    pub cut_ms: f64,
    /// Median device time of the view's frame.
    pub view_ms: f64,
    /// The view's data pass at `checked` (RGBA32F).
    pub data: Vec<f32>,
}

impl AgainstCutPlane {
    /// Measures `view` of `mesh` (see the type).
    pub(crate) fn measure(
        gpu: &Gpu,
        profiler: &mut crate::gpu::Profiler,
        (name, what): (&str, &str),
        mesh: &Arc<crate::spectral::SpectralMesh>,
        view: &SpectralView,
        (timed, checked): ((u32, u32), (u32, u32)),
        frames: usize,
    ) -> Result<Self> {
        if !mesh.shape.is_volume() {
            bail!("{name}: {what} takes a hexahedral or tetrahedral mesh, not {:?}s", mesh.shape);
        }
        let (blo, bhi) = mesh.bounds();
        let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &Colormap::viridis())?;
        let target =
            RenderTarget::new(gpu, "bench against the cut plane", timed.0, timed.1, ColorFormat::Rgba8)?;
        let cut = SpectralView {
            cuts: vec![[0.0, 0.0, 1.0, 0.5 * (blo[2] + bhi[2])]],
            overdraw: false,
            ..SpectralView::default()
        };
        let (cut_ms, view_ms) =
            interleaved_medians(&mut renderer, &target, [&cut, view], frames.max(1), 1, profiler)?;
        let data_target = RenderTarget::new(gpu, "bench data", checked.0, checked.1, ColorFormat::Rgba32F)?;
        let Pixels::Rgba32F(data) = renderer.render(&data_target, view)? else {
            bail!("a float target returned bytes")
        };
        Ok(Self { cut_ms, view_ms, data })
    }
}

/// Covered pixels of `view` (a data pass): the fragments the per-pixel path shades.
fn covered(
    renderer: &mut SpectralRenderer,
    gpu: &Gpu,
    (w, h): (u32, u32),
    view: &SpectralView,
) -> Result<usize> {
    let data = RenderTarget::new(gpu, "bench coverage", w, h, ColorFormat::Rgba32F)?;
    let Pixels::Rgba32F(v) = renderer.render(&data, view)? else { bail!("a float target returned bytes") };
    Ok(v.chunks_exact(4).filter(|p| p[3] >= 0.0).count())
}

/// Median device times (ms) of per-pixel frames (tessellated anew each frame, as when the
/// camera moves), per-vertex frames on the node grids, per-vertex frames on the per-pixel
/// path's own tessellation, and per-pixel frames that reuse the last tessellation (camera
/// still), interleaved round by round.
fn per_pixel_and_vertex(
    profiler: &mut crate::gpu::Profiler,
    renderer: &mut SpectralRenderer,
    target: &RenderTarget,
    frames: usize,
) -> Result<[f64; 4]> {
    let pixel = SpectralView { overdraw: false, ..SpectralView::default() };
    let views = [
        pixel.clone(),
        SpectralView { per_vertex: true, ..pixel.clone() },
        SpectralView { per_vertex: true, per_vertex_on_tessellation: true, ..pixel.clone() },
        pixel,
    ];
    let mut times = [Vec::new(), Vec::new(), Vec::new(), Vec::new()];
    for round in 0..frames + 2 {
        for (k, v) in views.iter().enumerate() {
            if k < 3 {
                renderer.invalidate_tessellation();
            }
            let ms = renderer.frame(target, v, profiler)?;
            if round >= 2 {
                times[k].push(ms);
            }
        }
    }
    Ok(times.map(median))
}

/// Median device time (ms) of `frames` frames of `view`, after one unmeasured frame.
fn timed(
    renderer: &mut SpectralRenderer,
    target: &RenderTarget,
    view: &SpectralView,
    profiler: &mut crate::gpu::Profiler,
    frames: usize,
) -> Result<f64> {
    renderer.frame(target, view, profiler)?;
    let ms = (0..frames)
        .map(|_| {
            renderer.invalidate_tessellation();
            renderer.frame(target, view, profiler)
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(median(ms))
}

/// Seed 002's table on `gpu` as Markdown, section by section through `emit`: frame times of
/// orders 1–8 (`quick`: 1, 3, 8) on the artery and the coil at 1024×768, per pixel against
/// per vertex in the same run; frame time against pixels and against elements. Medians of
/// `frames` frames.
pub fn report(gpu: &Gpu, quick: bool, frames: usize, emit: &mut dyn FnMut(&str)) -> Result<()> {
    macro_rules! say {
        ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
    }
    let mut profiler = crate::gpu::Profiler::new(gpu, 1)?;
    let frames = if quick { frames.min(7) } else { frames }.max(1);
    let orders: Vec<usize> = if quick { vec![1, 3, 8] } else { (1..=8).collect() };
    let size = (1024, 768);
    let c = gpu.caps();
    say!(
        "Device: {} ({}); 1024×768, geometry of order 3 (GLL), GLL fields, median device time of {frames} frames per mode, the four modes interleaved frame by frame; edge overdraw off in all (the seed had none). Per pixel: the surface tessellated anew to ½ px each frame (as when the camera moves) and the field evaluated per fragment. Per vertex, node grid: the seed's baseline (colour at the nodes, the geometry flat between them). Per vertex, same tessellation: the per-pixel path's triangles with colour at their vertices. Per pixel, camera still: the last tessellation reused (time stepping, range changes).\n",
        c.device_name, c.driver
    );
    say!("| data | order | per pixel ms (FPS) | per vertex, node grid ms (FPS) | rate ÷ node grid | per vertex, same tessellation ms | rate ÷ same tessellation | per pixel, camera still ms | its rate ÷ node grid | triangles: per pixel / node grid | fragments | per-pixel device memory | node grids |");
    say!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let colormap = Colormap::viridis();
    let target = RenderTarget::new(gpu, "bench spectral", size.0, size.1, ColorFormat::Rgba8)?;
    let pixel = SpectralView { overdraw: false, ..SpectralView::default() };
    for name in ["artery", "coil"] {
        for &order in &orders {
            let mesh = Arc::new(generate::by_name(name, 3, order, NodeSet::GaussLobatto)?);
            let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &colormap)?;
            let [pp, pv, pt, ps] = per_pixel_and_vertex(&mut profiler, &mut renderer, &target, frames)?;
            let fragments = covered(&mut renderer, gpu, size, &pixel)?;
            renderer.frame(&target, &pixel, &mut profiler)?;
            let tessellated = renderer.last_tessellation()?.map_or(0, |t| t.0) / 3;
            let (bytes, grids) = renderer.device_bytes();
            say!(
                "| {name} ({}) | {order} | {pp:.1} ({:.1}) | {pv:.1} ({:.1}) | {:.2}× | {pt:.1} | {:.2}× | {ps:.1} | {:.2}× | {tessellated} / {} | {fragments} | {:.2} MB | {:.2} MB |",
                mesh.elements(),
                1e3 / pp,
                1e3 / pv,
                pv / pp,
                pt / pp,
                pv / ps,
                renderer.primitive_counts()[1],
                bytes as f64 / 1e6,
                grids as f64 / 1e6
            );
        }
    }
    say!("\nFrame time against pixels (coil, order 3, per pixel; the tessellation follows the pixel size):\n\n| size | ms | fragments | triangles | ns per fragment |\n|---|---:|---:|---:|---:|");
    let coil = Arc::new(generate::by_name("coil", 3, 3, NodeSet::GaussLobatto)?);
    let mut renderer = SpectralRenderer::new(gpu, coil, &colormap)?;
    for (w, h) in [(512, 384), (1024, 768), (2048, 1536)] {
        let t = RenderTarget::new(gpu, "bench size", w, h, ColorFormat::Rgba8)?;
        let ms = timed(&mut renderer, &t, &pixel, &mut profiler, frames)?;
        let f = covered(&mut renderer, gpu, (w, h), &pixel)?;
        renderer.frame(&t, &pixel, &mut profiler)?;
        let tris = renderer.last_tessellation()?.map_or(0, |t| t.0) / 3;
        say!("| {w}×{h} | {ms:.1} | {f} | {tris} | {:.0} |", ms * 1e6 / f.max(1) as f64);
    }
    drop(renderer);
    say!("\nFrame time against elements (helices of 7 turns, 14 elements around, order 3, 1024×768, per pixel):\n\n| elements | ms | fragments | triangles |\n|---:|---:|---:|---:|");
    for along in [60, 119, 238, 476] {
        let mesh = Arc::new(generate::coil(along, 14, 3, 3, NodeSet::GaussLobatto)?);
        let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &colormap)?;
        let ms = timed(&mut renderer, &target, &pixel, &mut profiler, frames)?;
        let f = covered(&mut renderer, gpu, size, &pixel)?;
        renderer.frame(&target, &pixel, &mut profiler)?;
        let tris = renderer.last_tessellation()?.map_or(0, |t| t.0) / 3;
        say!("| {} | {ms:.1} | {f} | {tris} |", mesh.elements());
    }
    drop((target, profiler));
    Ok(())
}
