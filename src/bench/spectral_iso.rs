//! `galerkin spectral bench --iso`: what an isosurface frame (`--iso`, per pixel: `iso.frag`)
//! costs against the cut-plane frame of the same mesh, image and camera (the yardstick:
//! at most 4×), interleaved frame by frame, and how exact it is: the same view at a smaller
//! size against the f64 ray caster ([`crate::spectral::iso_reference`]), the distance along
//! each pixel's ray between the device's point and the f64 root.

use std::sync::Arc;

use anyhow::Result;

use super::spectral::AgainstCutPlane;
use crate::gpu::Gpu;
use crate::spectral::iso_reference::{compare, iso_reference};
use crate::spectral::proxy::value_bounds;
use crate::spectral::render::fit_camera;
use crate::spectral::{generate, NodeSet, SpectralMesh, SpectralView};

/// The image the frames are timed at.
pub const TIMED_SIZE: (u32, u32) = (640, 480);
/// The image the accuracy is checked at (the f64 ray caster's cost grows with the pixels).
pub const CHECKED_SIZE: (u32, u32) = (200, 150);

/// The default meshes: the generated shell (72 curved hexahedra) at orders 3 and 6.
pub fn default_meshes() -> Result<Vec<(String, SpectralMesh)>> {
    [3, 6]
        .into_iter()
        .map(|n| Ok((format!("shell, order {n}"), generate::by_name("shell", 3, n, NodeSet::GaussLobatto)?)))
        .collect()
}

/// The isosurface table on `gpu` as Markdown through `emit`, per mesh (name, mesh): iso values
/// at 30 % and 60 % of the field's range, the median device time of `frames` isosurface
/// frames and of as many cut-plane frames (the plane z through the mesh's middle), the
/// elements the value bounds cull, and the accuracy against the f64 ray caster at
/// [`CHECKED_SIZE`].
pub fn report(
    gpu: &Gpu,
    meshes: Vec<(String, SpectralMesh)>,
    frames: usize,
    emit: &mut dyn FnMut(&str),
) -> Result<()> {
    macro_rules! say {
        ($($t:tt)*) => { emit(&format!("{}\n", format_args!($($t)*))) };
    }
    let frames = frames.max(1);
    let c = gpu.caps();
    let (w, h) = TIMED_SIZE;
    let (cw, ch) = CHECKED_SIZE;
    say!(
        "Device: {} ({}); {w}×{h}, median device time of {frames} frames, isosurfaces and the cut plane z = middle interleaved frame by frame; iso values at 30 % and 60 % of the field's range; accuracy at {cw}×{ch} against the f64 ray caster (distances along the ray, in units of the mesh's diagonal).\n",
        c.device_name, c.driver
    );
    say!("| data | elements drawn / all | cut ms | iso ms | iso ÷ cut | pixels shown | matched | worst (of bound) | worst distance | mean distance | grazing | mismatched |");
    say!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut profiler = crate::gpu::Profiler::new(gpu, 1)?;
    for (name, mesh) in meshes {
        let mesh = Arc::new(mesh);
        let (lo, hi) = mesh.value_range(0, 0);
        let values = vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)];
        let iso = SpectralView { iso: values.clone(), overdraw: false, ..SpectralView::default() };
        let run = AgainstCutPlane::measure(
            gpu,
            &mut profiler,
            (&name, "drawing isosurfaces"),
            &mesh,
            &iso,
            (TIMED_SIZE, CHECKED_SIZE),
            frames,
        )?;
        let (a, b) = (run.cut_ms, run.view_ms);
        let drawn = value_bounds(&mesh, 0, 0)?
            .iter()
            .filter(|b| values.iter().any(|&v| v >= b[0] && v <= b[1]))
            .count();
        let diag = mesh.diagonal();
        let reference = iso_reference(&mesh, (0, 0), &fit_camera(&mesh), &values, CHECKED_SIZE);
        let g = compare(&mesh, (0, 0), &run.data, &reference);
        say!(
            "| {name} | {drawn} / {} | {a:.1} | {b:.1} | {:.1}× | {} | {} | {:.3} | {:.1e} | {:.1e} | {} | {} |",
            mesh.elements(),
            b / a,
            g.shown,
            g.matched,
            g.worst_of_bound,
            g.worst_along_ray / diag,
            g.mean_along_ray / diag,
            g.grazing,
            g.mismatched.len()
        );
    }
    Ok(())
}
