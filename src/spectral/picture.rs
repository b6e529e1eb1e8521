//! `galerkin spectral render`'s picture (seed 002): a view checked against its data set, drawn
//! per pixel and written as PNG (with a title and a colour bar beside it) or EXR (the colour,
//! then the raw value (of the derived field with `--expr`), the reference coordinates ξ, η — for cut planes the plane and ζ — and
//! the element of every pixel; NaN where no element, −(e + 1) where only edge overdraw drew).

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use super::render::PictureView;
use super::{Shape, SpectralError, SpectralMesh, SpectralRenderer, SpectralView};
use crate::gpu::Gpu;
use crate::picture::{self, ImageFormat, Legend};
use crate::plot::ColourBar;
use crate::render::{ColorFormat, Colormap, Pixels, RenderTarget};

/// What [`write_picture`] drew.
#[derive(Clone, Debug)]
pub struct PictureReport {
    /// The colour range used (the field's own unless the view fixed one).
    pub range: (f64, f64),
    /// Render and readback time, ms.
    pub render_ms: f64,
    /// Triangles drawn.
    pub triangles: u64,
    /// What the triangles are (proxies, node grids, device tessellation, cut sections).
    pub triangle_kind: &'static str,
    /// Edge lines drawn.
    pub lines: u64,
}

/// Warnings about `view` that do not stop a picture: iso values outside the field's sampled
/// range (their surfaces are empty; the picture is drawn, empty where nothing else is).
pub fn view_warnings(mesh: &SpectralMesh, view: &SpectralView) -> Vec<String> {
    if view.iso.is_empty() || view.field >= mesh.fields.len() {
        return Vec::new();
    }
    let (lo, hi) = mesh.value_range(view.field, view.step);
    view.iso
        .iter()
        .filter(|&&c| c < lo || c > hi)
        .map(|c| {
            format!(
                "iso value {c} is outside the field's range [{lo}, {hi}] (sampled on a (2n + 1)-point grid per element): its surface is empty or nearly"
            )
        })
        .collect()
}

/// Checks `view` against `mesh` before any work: the step exists, a log scale has a positive
/// range (given, or the field's own), the tessellation budget is a positive number of pixels.
pub fn check_view(mesh: &SpectralMesh, view: &SpectralView) -> Result<(), SpectralError> {
    let field = mesh.fields.get(view.field).ok_or_else(|| SpectralError::Missing("no such field".into()))?;
    let steps = field.steps.len();
    if view.step >= steps {
        return Err(SpectralError::Missing(format!(
            "--step {}: field {:?} has {steps} time steps (0 to {})",
            view.step,
            field.name,
            steps.saturating_sub(1)
        )));
    }
    if let Some(camera) = &view.camera {
        camera.check().map_err(SpectralError::View)?;
        if mesh.is_planar() && view.height.is_none() && view.cuts.is_empty() {
            return Err(SpectralError::View(
                "--camera: this mesh is planar and drawn flat, seen from above; give --height to see it as a height field in 3D".into(),
            ));
        }
    }
    if let Some(d) = &view.expression {
        d.check_step(mesh, view.field, view.step)?;
    }
    if view.colour_by.is_some() && view.iso.is_empty() {
        return Err(SpectralError::View("--colour-by colours isosurfaces: give --iso too".into()));
    }
    if let Some(k) = view.colour_by {
        let f =
            mesh.fields.get(k).ok_or_else(|| SpectralError::Missing(format!("--colour-by: no field {k}")))?;
        if view.step >= f.steps.len() {
            return Err(SpectralError::Missing(format!(
                "--colour-by {:?} has {} time steps; step {} does not exist",
                f.name,
                f.steps.len(),
                view.step
            )));
        }
    }
    if view.volume.is_some() && !mesh.shape.is_volume() {
        return Err(SpectralError::View(format!(
            "--volume: volume rendering is for hexahedral and tetrahedral meshes; this one is of {:?}s",
            mesh.shape
        )));
    }
    if view.volume.is_some() && (!view.cuts.is_empty() || view.expression.is_some()) {
        return Err(SpectralError::View("--volume cannot be combined with --cut or --expr yet".into()));
    }
    crate::spectral::transfer::Sheets::check_opacity(view.iso_opacity)
        .map_err(|e| SpectralError::View(format!("--iso-opacity: {e}")))?;
    if view.uses_volume_pass() && !view.iso.is_empty() && (view.edges || view.colour_by.is_some()) {
        return Err(SpectralError::View(
            "--edges and --colour-by go with opaque isosurfaces, not transparent ones or isosurfaces in a volume"
                .into(),
        ));
    }
    if view.log {
        match view.range {
            Some((lo, _)) if lo <= 0.0 => {
                return Err(SpectralError::Missing("--log needs a positive --range (LO > 0)".into()))
            }
            Some(_) => {}
            None => {
                let (what, (lo, hi)) = match &view.expression {
                    Some(d) => (
                        format!("--expr {:?}", d.expression.text),
                        d.range(mesh, view.field, view.step).unwrap_or((f64::NAN, f64::NAN)),
                    ),
                    None => (format!("field {:?}", field.name), mesh.value_range(view.field, view.step)),
                };
                if lo.is_nan() || lo <= 0.0 {
                    return Err(SpectralError::Missing(format!(
                        "--log: {what} at step {} spans [{lo}, {hi}], not above 0; give --range LO,HI with LO > 0",
                        view.step
                    )));
                }
            }
        }
    }
    if !(view.max_error_px.is_finite() && view.max_error_px > 0.0) {
        return Err(SpectralError::Missing(
            "--max-error (the tessellation's error budget) must be a positive number of pixels".into(),
        ));
    }
    Ok(())
}

/// "hexahedral", "tetrahedral", "planar" or "surface": how `mesh` is shown.
pub fn kind(mesh: &SpectralMesh) -> &'static str {
    match (mesh.shape, mesh.is_planar()) {
        (Shape::Hexahedron, _) => "hexahedral",
        (Shape::Tetrahedron, _) => "tetrahedral",
        (_, true) => "planar",
        (_, false) => "surface",
    }
}

/// What the colours of a spectral picture mean, for its legend (the PNG's and the viewer's):
/// `field` mapped through `colormap` over `range`, on a log scale when `log`.
pub fn colour_bar<'a>(colormap: &'a Colormap, range: (f64, f64), log: bool, field: &'a str) -> ColourBar<'a> {
    ColourBar { colormap, range, log, label: field, shift: 0.0 }
}

/// What `view` colours: its derived field's expression, or the field's name.
pub fn shown_label(mesh: &SpectralMesh, view: &SpectralView) -> String {
    if let Some(k) = view.colour_by.filter(|_| !view.iso.is_empty()) {
        return mesh.fields.get(k).map_or_else(String::new, |f| f.name.clone());
    }
    match &view.expression {
        Some(d) => d.expression.text.clone(),
        None => mesh.fields.get(view.field).map_or_else(String::new, |f| f.name.clone()),
    }
}

/// Renders `view` of `mesh` at `size` and writes it to `out` (format by extension): a PNG with
/// `title` and a colour bar beside it, or the bare picture when `title` is `None`; an EXR with
/// the raw channels.
pub fn write_picture(
    gpu: &Gpu,
    mesh: Arc<SpectralMesh>,
    view: &SpectralView,
    colormap: &Colormap,
    size: (u32, u32),
    out: &Path,
    decor: picture::Decor<'_>,
) -> Result<PictureReport, SpectralError> {
    check_view(&mesh, view)?;
    let format = picture::format_of(out)?;
    let dev = SpectralError::device;
    let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), colormap)?;
    let (w, h) = size;
    let start = Instant::now();
    let colour =
        RenderTarget::new(gpu, "spectral", w, h, ColorFormat::Rgba8).map_err(dev("the colour target"))?;
    let Pixels::Rgba8(mut rgba) = renderer.render(&colour, view)? else {
        return Err(SpectralError::Missing("an RGBA8 target returned floats".into()));
    };
    if decor.overlay != picture::Overlay::default() && format == ImageFormat::Png {
        let shown = renderer.picture_view(view, w, h);
        let projector = match &shown {
            PictureView::Plane(v) => picture::Projector::Plane { centre: v.centre, pixel_size: v.pixel_size },
            PictureView::Camera(camera) => picture::Projector::Camera(camera),
        };
        picture::draw_overlay(&mut rgba, size, projector, mesh.bounds(), decor.overlay, out)?;
    }
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    let range = renderer.range(view);
    let label = shown_label(&mesh, view);
    match format {
        ImageFormat::Png => {
            let legend = decor.title.map(|title| Legend {
                title: title.to_string(),
                bar: colour_bar(colormap, range, view.log, &label),
            });
            picture::write_png(out, size, &rgba, legend.as_ref())?;
        }
        ImageFormat::Exr => {
            let hex = mesh.shape.is_volume();
            let data = RenderTarget::new(gpu, "spectral values", w, h, ColorFormat::Rgba32F)
                .map_err(dev("the data target"))?;
            let Pixels::Rgba32F(v) = renderer.render(&data, view)? else {
                return Err(SpectralError::Missing("a float target returned bytes".into()));
            };
            let names = if view.volume.is_some() {
                ["red", "green", "blue", "transmittance"]
            } else if !view.iso.is_empty() {
                ["value", "distance", "iso_index", "element"]
            } else if hex {
                ["value", "plane", "zeta", "element"]
            } else {
                ["value", "xi", "eta", "element"]
            };
            picture::write_exr(out, size, Some(&rgba), picture::float_channels(&v, &names))?;
        }
    }
    let [proxies, grids, lines] = renderer.primitive_counts();
    let triangle_kind = if view.volume.is_some() {
        "volume: a ray cast per pixel through the elements of its screen tile"
    } else if view.uses_volume_pass() {
        "transparent isosurfaces: a ray cast per pixel through the elements of its screen tile"
    } else if !view.iso.is_empty() {
        "isosurfaces: a ray cast per pixel through each element's box"
    } else if mesh.shape.is_volume() {
        "cut planes: section rectangles cut out per pixel"
    } else if view.per_vertex {
        "node grids"
    } else if mesh.is_planar() && view.height.is_none() {
        "proxies"
    } else {
        "tessellated on the device"
    };
    Ok(PictureReport {
        range,
        render_ms,
        triangles: if view.per_vertex { grids } else { proxies },
        triangle_kind,
        lines,
    })
}
