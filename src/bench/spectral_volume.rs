//! `galerkin spectral bench --volume`: what a volume frame (`--volume`, per pixel:
//! `volume.frag`) costs against the cut-plane frame of the same mesh, image and camera,
//! interleaved frame by frame, and how exact it is: the same view at a smaller size against
//! the f64 ray caster ([`crate::spectral::volume_reference`]), per colour channel and the
//! transmittance (the goal: within 1/255).

use std::sync::Arc;

use anyhow::Result;

use super::spectral::AgainstCutPlane;
use crate::gpu::Gpu;
use crate::render::Colormap;
use crate::spectral::render::fit_camera;
use crate::spectral::transfer::TransferFunction;
use crate::spectral::volume_reference::{compare_volume, volume_reference, VolumeColours};
use crate::spectral::{generate, NodeSet, SpectralMesh, SpectralView};

/// The image the frames are timed at (a volume frame on lavapipe takes seconds to minutes).
pub const TIMED_SIZE: (u32, u32) = (320, 240);
/// The image the accuracy is checked at.
pub const CHECKED_SIZE: (u32, u32) = (96, 72);
/// Samples per order of the f64 reference (converged to well under 1/255: tests/spectral_volume.rs).
pub const REFERENCE_SAMPLES_PER_ORDER: usize = 16;

/// The default mesh: the generated shell (72 curved hexahedra) at order 3.
pub fn default_mesh() -> Result<(String, SpectralMesh)> {
    Ok(("shell, order 3".into(), generate::by_name("shell", 3, 3, NodeSet::GaussLobatto)?))
}

/// The benchmark's transfer function over a field's range [lo, hi]: clear at lo, opacity 0.6
/// at 30 %, 0.05 at 50 %, 0.9 at hi; a unit distance of a quarter of `diagonal` (the tests').
pub fn bench_transfer(lo: f64, hi: f64, diagonal: f64) -> Result<TransferFunction> {
    let at = |s: f64| lo + s * (hi - lo);
    TransferFunction::new(vec![(lo, 0.0), (at(0.3), 0.6), (at(0.5), 0.05), (hi, 0.9)], 0.25 * diagonal)
        .map_err(anyhow::Error::msg)
}

/// The volume table on `gpu` as Markdown through `emit`, per mesh (name, mesh): the median
/// device time of `frames` volume frames and of as many cut-plane frames (the plane z through
/// the mesh's middle), and the accuracy against the f64 ray caster at [`CHECKED_SIZE`].
pub fn report(
    gpu: &Gpu,
    meshes: Vec<(String, SpectralMesh)>,
    frames: usize,
    emit: &mut dyn FnMut(&str),
) -> Result<()> {
    table(gpu, meshes, frames, false, emit)
}

/// The same table for transparent isosurfaces (`--iso … --iso-opacity ½`, drawn by the volume
/// pass as sheets in a clear medium): values at 30 % and 60 % of the field's range, opacity ½.
pub fn report_transparent(
    gpu: &Gpu,
    meshes: Vec<(String, SpectralMesh)>,
    frames: usize,
    emit: &mut dyn FnMut(&str),
) -> Result<()> {
    table(gpu, meshes, frames, true, emit)
}

/// The view a row measures: the benchmark's volume, or transparent isosurfaces (`sheets`).
fn bench_view(mesh: &SpectralMesh, sheets: bool) -> Result<(SpectralView, TransferFunction)> {
    let (lo, hi) = mesh.value_range(0, 0);
    if sheets {
        let iso = vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)];
        let view = SpectralView { iso, iso_opacity: 0.5, overdraw: false, ..SpectralView::default() };
        return Ok((view, TransferFunction::clear()));
    }
    let tf = bench_transfer(lo, hi, mesh.diagonal())?;
    Ok((SpectralView { volume: Some(tf.clone()), overdraw: false, ..SpectralView::default() }, tf))
}

fn table(
    gpu: &Gpu,
    meshes: Vec<(String, SpectralMesh)>,
    frames: usize,
    sheets: bool,
    emit: &mut dyn FnMut(&str),
) -> Result<()> {
    macro_rules! say {
        ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
    }
    let frames = frames.max(1);
    let c = gpu.caps();
    let (w, h) = TIMED_SIZE;
    let (cw, ch) = CHECKED_SIZE;
    let (what, drawn) = if sheets {
        (
            "transparent isosurfaces (opacity ½, values at 30 % and 60 % of the field's range)",
            "transparent isosurfaces",
        )
    } else {
        ("the volume (transfer function: opacity 0, 0.6, 0.05, 0.9 at 0, 30, 50, 100 % of the field's range, unit distance a quarter of the diagonal)", "volume rendering")
    };
    say!(
        "Device: {} ({}); {w}×{h}, median device time of {frames} frames, {what} and the cut plane z = middle interleaved frame by frame; accuracy at {cw}×{ch} against the f64 ray caster (colour over black and transmittance, per channel).\n",
        c.device_name, c.driver
    );
    let kind = if sheets { "transparent iso" } else { "volume" };
    say!("| data | elements | cut ms | {kind} ms | {kind} ÷ cut | pixels | worst (× 1/255) | mean | grazing | beyond 1/255 |");
    say!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut profiler = crate::gpu::Profiler::new(gpu, 1)?;
    let colormap = Colormap::viridis();
    for (name, mesh) in meshes {
        let mesh = Arc::new(mesh);
        let range = mesh.value_range(0, 0);
        let (view, tf) = bench_view(&mesh, sheets)?;
        let run = AgainstCutPlane::measure(
            gpu,
            &mut profiler,
            (&name, drawn),
            &mesh,
            &view,
            (TIMED_SIZE, CHECKED_SIZE),
            frames,
        )?;
        let (a, b) = (run.cut_ms, run.view_ms);
        let colours = VolumeColours { colormap: &colormap, range, log: false };
        let reference = volume_reference(
            &mesh,
            (0, 0),
            &fit_camera(&mesh),
            &tf,
            &view.sheets(),
            &colours,
            CHECKED_SIZE,
            REFERENCE_SAMPLES_PER_ORDER,
        );
        let g = compare_volume(&run.data, &reference, 1.0 / 255.0);
        say!(
            "| {name} | {} | {a:.1} | {b:.0} | {:.0}× | {} | {:.2} | {:.1e} | {} | {} |",
            mesh.elements(),
            b / a,
            g.shown,
            g.worst * 255.0,
            g.mean,
            g.grazing,
            g.mismatched.len()
        );
    }
    Ok(())
}
