//! `galerkin spacetime render`'s pictures (seed 003): a time slice drawn per pixel and
//! written as PNG (lit colour with a title and the log colour bar of U beside it) or EXR (the
//! channels U, speed, normal.x/y/z; NaN where no surface; data only), and Fig. 3's whole
//! (x, t) spacetime of the 1D bar (EXR channels U, speed, u, s).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use super::bar::{bar1d, BarRenderer};
use super::{SliceStats, SpacetimeData, SpacetimeError, SpacetimeRenderer, SpacetimeView};
use crate::expression::spacetime::SpacetimeExpression;
use crate::gpu::Gpu;
use crate::picture::{self, ImageFormat, Legend};
use crate::plot::ColourBar;
use crate::render::{ColorFormat, Colormap, Pixels, RenderTarget};

/// What [`write_slice`] drew.
#[derive(Clone, Debug)]
pub struct SliceReport {
    /// The slice's counts (active elements, streamed, triangles, edge lines).
    pub stats: SliceStats,
    /// Time of the slice on the device, ms.
    pub slice_ms: f64,
    /// Render and readback time, ms.
    pub render_ms: f64,
    /// The colour ramp's U_max (resolved from the picture when the view left it open).
    pub u_max: Option<f64>,
}

/// What the colours of a spacetime picture mean, for its legend (the PNG's and the viewer's):
/// the strain energy density U on the ramp log(U + 1) up to `u_max`, labelled in U.
pub fn colour_bar(colormap: &Colormap, u_max: f64) -> ColourBar<'_> {
    ColourBar {
        colormap,
        range: (1.0, u_max + 1.0),
        log: true,
        label: "U, strain energy density (ramp log(U + 1))",
        shift: 1.0,
    }
}

/// Checks a view's numbers (the subdivision area, U_max and the height scale are positive
/// when given) and its time against the data's span.
pub fn check_view(data: &SpacetimeData, view: &SpacetimeView) -> Result<(), SpacetimeError> {
    for (name, v) in [
        ("--subdivide (the subdivision area)", view.subdivide),
        ("--umax (U_max)", view.u_max),
        ("--height-scale", view.height_scale),
    ] {
        if let Some(v) = v.filter(|v| !(v.is_finite() && *v > 0.0)) {
            return Err(SpacetimeError::Request(format!("{name} must be a positive number, got {v}")));
        }
    }
    let [t0, t1] = data.summary().time;
    if !(t0..=t1).contains(&view.time) {
        return Err(SpacetimeError::Request(format!(
            "--time {} is outside the data set's time span [{t0}, {t1}]",
            view.time
        )));
    }
    Ok(())
}

/// A derived field to show instead of U (`--expr`) and its colour range (`None`: the
/// slice's own).
pub type Derived = (Arc<SpacetimeExpression>, Option<(f64, f64)>);

/// Slices `data` at `view.time`, renders it at `size` and writes `out` (format by extension):
/// a PNG with `title` and the colour bar of U (or of the derived field) beside it (the bare
/// picture when `title` is `None`), or an EXR of the raw channels (the derived value in the
/// first, named `value`).
pub fn write_slice(
    gpu: &Gpu,
    data: SpacetimeData,
    view: &SpacetimeView,
    colormap: &Colormap,
    (size, out): ((u32, u32), &Path),
    decor: picture::Decor<'_>,
    derived: Option<Derived>,
) -> Result<SliceReport, SpacetimeError> {
    check_view(&data, view)?;
    let title = decor.title;
    let bounds = view.shown_box(data.summary());
    let exr = picture::format_of(out)? == ImageFormat::Exr;
    let dev = SpacetimeError::device;
    let mut renderer = SpacetimeRenderer::new(gpu, data, colormap)?;
    if let Some((e, range)) = &derived {
        renderer.set_expression(Some(e.clone()), *range)?;
    }
    let start = Instant::now();
    let stats = renderer.slice(view.time, view.subdivide)?;
    let slice_ms = start.elapsed().as_secs_f64() * 1e3;
    let (w, h) = size;
    let format = if exr { ColorFormat::Rgba32F } else { ColorFormat::Rgba8 };
    let target = RenderTarget::new(gpu, "spacetime", w, h, format).map_err(dev("the picture's target"))?;
    let start = Instant::now();
    // The legend needs the ramp's U_max: resolved once here, and the render uses the same.
    let legend = !exr && title.is_some();
    let mut view = *view;
    let mut derived_range = None;
    if let Some((e, range)) = &derived {
        if legend {
            let range = match range {
                Some(r) => *r,
                None => renderer.derived_range_for(&target, &view)?,
            };
            renderer.set_expression(Some(e.clone()), Some(range))?;
            derived_range = Some((e.expression.text.clone(), range));
        }
    } else if legend && view.u_max.is_none() {
        view.u_max = Some(renderer.u_max_for(&target, &view)?);
    }
    let mut pixels = renderer.render(&target, &view)?;
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    if let Pixels::Rgba8(rgba) = &mut pixels {
        if decor.overlay != picture::Overlay::default() {
            let projector = picture::Projector::Camera(&view.camera);
            picture::draw_overlay(rgba, size, projector, bounds, decor.overlay, out)?;
        }
    }
    if let (Pixels::Rgba8(rgba), Some(title), Some((label, range))) = (&pixels, title, &derived_range) {
        let bar = ColourBar { colormap, range: *range, log: false, label, shift: 0.0 };
        let legend = Legend { title: title.to_string(), bar };
        picture::write_png(out, size, rgba, Some(&legend))?;
        return Ok(SliceReport { stats, slice_ms, render_ms, u_max: None });
    }
    let first = if derived.is_some() { "value" } else { "U" };
    match (pixels, title, view.u_max) {
        (Pixels::Rgba8(rgba), Some(title), Some(u_max)) if u_max > 0.0 => {
            let legend = Legend { title: title.to_string(), bar: colour_bar(colormap, u_max) };
            picture::write_png(out, size, &rgba, Some(&legend))?;
        }
        (Pixels::Rgba8(rgba), ..) => picture::write_png(out, size, &rgba, None)?,
        (Pixels::Rgba32F(raw), ..) => {
            // n_z from the unit length; NaN where no surface.
            let nz = |p: &[f32]| {
                if p[2].is_nan() {
                    f32::NAN
                } else {
                    (1.0 - p[2] * p[2] - p[3] * p[3]).max(0.0).sqrt()
                }
            };
            let channels = picture::mapped_channels(
                &raw,
                &[
                    (first, |p| p[0]),
                    ("speed", |p| p[1]),
                    ("normal.x", |p| p[2]),
                    ("normal.y", |p| p[3]),
                    ("normal.z", nz),
                ],
            );
            picture::write_exr(out, size, None, channels)?;
        }
    }
    Ok(SliceReport { stats, slice_ms, render_ms, u_max: view.u_max })
}

/// What [`write_bar`] drew.
#[derive(Clone, Debug)]
pub struct BarReport {
    /// Triangles of the (x, t) mesh.
    pub triangles: usize,
    /// The time window shown.
    pub time: [f64; 2],
    /// The colour ramp's U_max.
    pub u_max: f64,
}

/// Seed 003's Fig. 3: the whole (x, t) spacetime of the 1D bar of `elements` elements, per
/// pixel (or per vertex), written as PNG or EXR (channels U, speed, u, s). `u_max` fixes the
/// ramp; without it, the largest U over the picture's pixels (from a float pass).
pub fn write_bar(
    gpu: &Gpu,
    elements: usize,
    colormap: &Colormap,
    u_max: Option<f64>,
    per_vertex: bool,
    size: (u32, u32),
    out: &Path,
) -> Result<BarReport, SpacetimeError> {
    let exr = picture::format_of(out)? == ImageFormat::Exr;
    let dev = SpacetimeError::device;
    let mesh = bar1d(elements);
    let mut renderer = BarRenderer::new(gpu, &mesh, colormap)?;
    let (w, h) = size;
    let u_max = match u_max {
        Some(u) => u,
        None => {
            let data = RenderTarget::new(gpu, "bar U_max", w, h, ColorFormat::Rgba32F)
                .map_err(dev("the data target"))?;
            let Pixels::Rgba32F(v) = renderer.render(&data, 1.0, false)? else {
                return Err(SpacetimeError::Request("a float target returned bytes".into()));
            };
            v.chunks_exact(4).map(|p| f64::from(p[0])).filter(|u| u.is_finite()).fold(0.0, f64::max)
        }
    };
    let format = if exr { ColorFormat::Rgba32F } else { ColorFormat::Rgba8 };
    let target = RenderTarget::new(gpu, "bar", w, h, format).map_err(dev("the picture's target"))?;
    match renderer.render(&target, u_max, per_vertex)? {
        Pixels::Rgba8(rgba) => picture::write_png(out, size, &rgba, None)?,
        Pixels::Rgba32F(raw) => {
            picture::write_exr(out, size, None, picture::float_channels(&raw, &["U", "speed", "u", "s"]))?
        }
    }
    let window = renderer.window();
    Ok(BarReport { triangles: mesh.triangles.len(), time: [window[2], window[3]], u_max })
}
