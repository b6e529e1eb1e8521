//! `galerkin demo`: one small run of every capability, each checked against its CPU f64
//! reference before its files count as written. [`run`] returns one [`DemoPart`] per check
//! (the command line prints them; `tests/demo.rs` runs the same parts); a part whose check
//! fails is an error naming what differed.
//!
//! This module holds the first passes' parts (`y ← a·x + y`, the polynomial field, a spacetime
//! slice); [`super::capabilities`] holds the spectral, radiosity and fluid parts.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};

use super::axpy::{axpy_error_ratio, Axpy};
use super::field::{check_colours, check_values, FieldOutput, FieldPass};
use super::scene::DemoScene;
use crate::gpu::{vk, Buffer, Gpu, Profiler};
use crate::render::{write_exr_rgba, write_png_rgba8, ColorFormat, Colormap, Pixels, RenderTarget};

/// One checked part of the demo: what ran, what its check found, the files it wrote.
#[derive(Clone, Debug)]
pub struct DemoPart {
    /// The capability or pass (`axpy`, `field values`, `spectral`, …).
    pub name: &'static str,
    /// What was run and what its check measured, in one line.
    pub summary: String,
    /// The files written.
    pub files: Vec<PathBuf>,
}

impl std::fmt::Display for DemoPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.name, self.summary)?;
        if !self.files.is_empty() {
            let names: Vec<String> = self.files.iter().map(|p| p.display().to_string()).collect();
            write!(f, " → {}", names.join(", "))?;
        }
        Ok(())
    }
}

/// Runs every part in order, handing each to `report` as it finishes (for progress), and
/// returns them all. `out` must exist. Stops at the first part whose check fails.
pub fn run(
    gpu: &Gpu,
    scene: &DemoScene,
    out: &Path,
    report: &mut dyn FnMut(&DemoPart),
) -> Result<Vec<DemoPart>> {
    let size = (scene.image.width, scene.image.height);
    let mut parts = Vec::new();
    let mut keep = |part: DemoPart| {
        report(&part);
        parts.push(part);
    };
    keep(axpy(gpu, scene)?);
    for part in field(gpu, scene, out)? {
        keep(part);
    }
    keep(spacetime(gpu, size, out)?);
    for part in super::capabilities::spectral(gpu, size, out)? {
        keep(part);
    }
    keep(super::capabilities::radiosity(gpu, size, out)?);
    keep(super::capabilities::fluid(gpu, size, out)?);
    keep(super::capabilities::fluid_reduced(gpu, size, out)?);
    Ok(parts)
}

/// Compute: `y ← a x + y` over the scene's `axpy.n` floats, every element against the CPU
/// f64 reference within a rigorous f32 bound.
pub fn axpy(gpu: &Gpu, scene: &DemoScene) -> Result<DemoPart> {
    let n = usize::try_from(scene.axpy.n).context("axpy.n does not fit in memory")?;
    let a = scene.axpy.a;
    let x: Vec<f32> = (0..n).map(|i| ((i % 1013) as f32 - 506.0) / 506.0).collect();
    let y: Vec<f32> = (0..n).map(|i| ((i % 977) as f32) / 977.0).collect();
    let xb = Buffer::from_slice(gpu, "demo x", &x, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let yb = Buffer::from_slice(gpu, "demo y", &y, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let axpy = Axpy::new(gpu)?;
    let binding = axpy.bind(gpu, &xb, &yb)?;
    let mut profiler = Profiler::new(gpu, 1).ok();
    let t = Instant::now();
    gpu.run(|rec| match profiler.as_mut() {
        Some(p) => {
            p.record_reset(rec);
            p.scope(rec, "axpy", |rec| axpy.record(gpu, rec, &binding, a as f32));
        }
        None => axpy.record(gpu, rec, &binding, a as f32),
    })?;
    let wall = t.elapsed();
    let kernel_ms = profiler.as_ref().and_then(|p| p.results().ok()).and_then(|r| r.first().map(|s| s.1));
    let result = yb.download(gpu)?;
    let (ratio, at) = axpy_error_ratio(a, &x, &y, &result);
    if ratio > 1.0 {
        bail!("axpy differs from its CPU reference beyond the f32 bound ({ratio:.2} of it at element {at})");
    }
    Ok(DemoPart {
        name: "axpy",
        summary: format!(
            "{n} floats in {} binding(s), {} (kernel) / {:.1} ms (submit + wait); worst error {ratio:.2} of the f32 bound at element {at}",
            binding.chunk_count(),
            kernel_ms.map_or("n/a".to_string(), |ms| format!("{ms:.1} ms")),
            wall.as_secs_f64() * 1e3
        ),
        files: Vec::new(),
    })
}

/// Graphics: the scene's polynomial field, its values (checked, EXR) and its colours
/// (checked, PNG), every covered pixel against the f64 ray-plane reference.
pub fn field(gpu: &Gpu, scene: &DemoScene, out: &Path) -> Result<Vec<DemoPart>> {
    let (w, h) = (scene.image.width, scene.image.height);
    let colormap = Colormap::by_name(&scene.colormap_name())?;
    let p = scene.field.coefficients;
    let values = RenderTarget::new(gpu, "demo field values", w, h, ColorFormat::Rgba32F)?;
    let pass = FieldPass::new(
        gpu,
        values.render_pass(),
        &p,
        scene.field.tessellation,
        &colormap,
        scene.ramp(),
        FieldOutput::Value,
    )?;
    let Pixels::Rgba32F(v) =
        values.render(gpu, [0.0; 4], |rec| pass.record(rec, values.extent(), &scene.camera))?
    else {
        bail!("float target returned bytes");
    };
    let check = check_values(&scene.camera, &p, w, h, &v);
    if !check.passed() {
        bail!(
            "field values: {} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.first_failure.unwrap_or_default()
        );
    }
    let exr = out.join("field.exr");
    write_exr_rgba(&exr, w, h, &v)?;
    let values_part = DemoPart {
        name: "field values",
        summary: format!(
            "{w}×{h}, {} covered pixels checked (worst {:.3} of tolerance), {} background, {} on the outline",
            check.checked, check.worst, check.background, check.outline
        ),
        files: vec![exr],
    };
    let colours = RenderTarget::new(gpu, "demo field colours", w, h, ColorFormat::Rgba8)?;
    let pass = FieldPass::new(
        gpu,
        colours.render_pass(),
        &p,
        scene.field.tessellation,
        &colormap,
        scene.ramp(),
        FieldOutput::Colour,
    )?;
    let background = crate::render::BACKGROUND;
    let Pixels::Rgba8(c) =
        colours.render(gpu, background, |rec| pass.record(rec, colours.extent(), &scene.camera))?
    else {
        bail!("RGBA8 target returned floats");
    };
    let bg = background.map(|v| (v * 255.0f32).round() as u8);
    let check = check_colours(&scene.camera, &p, &colormap, scene.ramp(), w, h, &c, bg);
    if !check.passed() {
        bail!(
            "field colours: {} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.first_failure.unwrap_or_default()
        );
    }
    let png = out.join("field.png");
    write_png_rgba8(&png, w, h, &c)?;
    let colours_part = DemoPart {
        name: "field colours",
        summary: format!(
            "{}: {} covered pixels checked (worst {:.3} of tolerance)",
            colormap.name(),
            check.checked,
            check.worst
        ),
        files: vec![png],
    };
    Ok(vec![values_part, colours_part])
}

/// Spacetime DG (seed 003): one lit frame (PNG) and its raw fields (EXR) of generated pulses;
/// a flat view from above checked against the CPU f64 fields at every 4th pixel.
pub fn spacetime(gpu: &Gpu, (w, h): (u32, u32), out: &Path) -> Result<DemoPart> {
    let colormap = Colormap::viridis();
    let mesh = crate::spacetime::generate::pulses(20_000);
    let mut renderer = crate::spacetime::SpacetimeRenderer::from_mesh(gpu, &mesh, &colormap)?;
    let t = 0.5 * mesh.time_range().1;
    let view = crate::spacetime::SpacetimeView::looking_at(renderer.data().summary(), t);
    let stats = renderer.slice(t, None)?;
    let colours = RenderTarget::new(gpu, "demo spacetime", w, h, ColorFormat::Rgba8)?;
    let Pixels::Rgba8(c) = renderer.render(&colours, &view)? else { bail!("RGBA8 target returned floats") };
    let values = RenderTarget::new(gpu, "demo spacetime fields", w, h, ColorFormat::Rgba32F)?;
    let Pixels::Rgba32F(v) = renderer.render(&values, &view)? else { bail!("float target returned bytes") };
    let flat = crate::spacetime::SpacetimeView::from_above(renderer.data().summary(), t);
    let Pixels::Rgba32F(d) = renderer.render(&values, &flat)? else { bail!("float target returned bytes") };
    let hs = renderer.default_height_scale();
    let check = crate::spacetime::reference::check_flat_pixels(&mesh, &flat, hs, (w, h), &d, 4, 1e-4);
    if !check.passed() {
        bail!(
            "spacetime: {} of {} pixels differ from the CPU reference; first: {}",
            check.failures,
            check.checked,
            check.first_failure.unwrap_or_default()
        );
    }
    let (png, exr) = (out.join("spacetime.png"), out.join("spacetime.exr"));
    write_png_rgba8(&png, w, h, &c)?;
    write_exr_rgba(&exr, w, h, &v)?;
    Ok(DemoPart {
        name: "spacetime",
        summary: format!(
            "{} elements (analytic pulses, L2-projected per element), t = {t:.3}: {} triangles; EXR channels U, |v|, n_x, n_y; flat view checked at {} pixels against f64: worst U {:.1e}, |v| {:.1e} of max",
            mesh.tets.len(),
            stats.triangles,
            check.checked,
            check.worst_u,
            check.worst_speed
        ),
        files: vec![png, exr],
    })
}
