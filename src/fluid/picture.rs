//! `galerkin fluid render`'s picture: one frame of a snapshot directory (a full run, or a
//! reduced run lifted to the full space) drawn by the device — in 2D the cells by speed or
//! plain, in 3D the domain's walls as a cutaway — with marker particles advected from frame 0
//! on top (Eq. 13 on the device, 10 Euler substeps per frame), written as PNG or as EXR (the
//! colour, then the raw speed, the cell index and the kind — 0 cell, 1 particle, 2 wall).

use std::path::Path;

use super::gpu::GpuParticles;
use super::particles::seed_particles;
use super::render::{cell_speeds, draw_picture, DrawStyle, Projection, View2d};
use super::snapshots::SnapshotReader;
use super::FluidError;
use crate::gpu::Gpu;
use crate::picture::{self, ImageFormat};
use crate::render::Colormap;

/// What to draw of a run.
#[derive(Clone, Debug)]
pub struct FrameRequest {
    /// The frame (`None`: the last).
    pub frame: Option<usize>,
    /// Marker particles seeded at frame 0 and advected to the frame (0: none).
    pub particles: usize,
    /// The colour map of speeds.
    pub colormap: Colormap,
    /// The speed range (`None`: 0 to the frame's largest cell speed).
    pub range: Option<(f64, f64)>,
    /// Cells coloured by speed (else plain, the particles carry the colour).
    pub colour_cells: bool,
    /// Particle sprite radius, pixels.
    pub sprite_px: f64,
    /// Image size (`None`: [`picture::DEFAULT_SIZE`]).
    pub size: Option<(u32, u32)>,
    /// A 3D run's camera orbiting the domain's bounding box (`--camera`, `--fit`; `None`: the
    /// fitted default). A 2D run is drawn flat and refuses one.
    pub orbit: Option<crate::render::Orbit>,
    /// The domain's outline and the axis triad drawn over a PNG ([`picture::Overlay`]).
    pub overlay: picture::Overlay,
    /// A PNG gets a title (run, frame, time) above the picture and a colour bar of the speed
    /// beside it ([`crate::picture::Legend`]); `false`: the bare picture.
    pub legend: bool,
}

/// What [`write_frame`] drew.
#[derive(Clone, Debug)]
pub struct FrameReport {
    /// The frame drawn.
    pub frame: usize,
    /// Cells of the run's mesh.
    pub cells: usize,
    /// The speed range of the colour map.
    pub range: (f64, f64),
}

fn state(dir: &Path, message: String) -> FluidError {
    FluidError::File { path: dir.to_path_buf(), message }
}

/// Draws frame `request.frame` of the run in `dir` and writes it to `out` (format by
/// extension). `progress` is told each frame the particles have been advected through.
pub fn write_frame(
    gpu: &Gpu,
    dir: &Path,
    request: &FrameRequest,
    out: &Path,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<FrameReport, FluidError> {
    let format = picture::format_of(out)?;
    let reader = SnapshotReader::open(dir)?;
    let meta = reader.meta().clone();
    if meta.frames == 0 {
        return Err(state(dir, "no frames".into()));
    }
    if meta.dim == 2 && request.orbit.is_some() {
        return Err(state(
            dir,
            "a 2D run is drawn flat, fitted to the picture: --camera and --fit apply to 3D runs".into(),
        ));
    }
    let frame = request.frame.unwrap_or(meta.frames - 1);
    if frame >= meta.frames {
        return Err(state(dir, format!("frame {frame} asked, the run has frames 0 to {}", meta.frames - 1)));
    }
    let (mesh, topo) = reader.mesh_at(0)?;
    let particles = if request.particles > 0 {
        let seeds = seed_particles(&mesh, request.particles);
        let mut device = GpuParticles::new(gpu, &mesh, &topo, &seeds)?;
        let mut g0 = reader.frame("g", 0)?;
        for k in 1..=frame {
            let g1 = reader.frame("g", k)?;
            let f = reader.frame("f", k)?;
            device.advect(gpu, &mesh, &g0, &g1, &f, meta.frame_time, 10)?;
            g0 = g1;
            progress(k, frame);
        }
        Some(device)
    } else {
        None
    };
    let g = reader.frame("g", frame)?;
    let f = reader.frame("f", frame)?;
    let speeds = cell_speeds(&mesh, &topo, &g, &f);
    let range = request.range.unwrap_or((0.0, speeds.iter().fold(0.0f64, |m, v| m.max(*v)).max(1e-12)));
    let style = DrawStyle {
        colormap: request.colormap.clone(),
        range,
        log: false,
        colour_cells: request.colour_cells,
        sprite_px: request.sprite_px,
    };
    let (lo, hi) = mesh.bounds();
    let size = request.size.unwrap_or(picture::DEFAULT_SIZE);
    let projection = match (meta.dim, request.orbit) {
        (2, _) => Projection::Plane(View2d::fit([lo[0], lo[1]], [hi[0], hi[1]], size, 0.02)),
        (_, Some(orbit)) => Projection::Perspective(orbit.camera(lo, hi)),
        (_, None) => Projection::Perspective(crate::render::camera_for_box(lo, hi)),
    };
    let mut picture =
        draw_picture(gpu, (&mesh, &topo), &g, &speeds, particles.as_ref(), &style, &projection, size)?;
    if request.overlay != picture::Overlay::default() && format == ImageFormat::Png {
        let projector = match &projection {
            Projection::Plane(v) => picture::Projector::Plane {
                centre: [0.5 * (v.lo[0] + v.hi[0]), 0.5 * (v.lo[1] + v.hi[1])],
                pixel_size: (v.hi[0] - v.lo[0]) / f64::from(size.0.max(1)),
            },
            Projection::Perspective(camera) => picture::Projector::Camera(camera),
        };
        picture::draw_overlay(&mut picture.rgba, size, projector, (lo, hi), request.overlay, out)?;
    }
    let legend = picture::Legend {
        title: format!(
            "{}: frame {frame} of {}, t = {} s",
            dir.display(),
            meta.frames - 1,
            crate::plot::tick_label(frame as f64 * meta.frame_time, meta.frame_time)
        ),
        bar: style.colour_bar(),
    };
    match format {
        ImageFormat::Png => picture::write_png(out, size, &picture.rgba, request.legend.then_some(&legend))?,
        ImageFormat::Exr => {
            let channels = picture::float_channels(&picture.raw, &["speed", "cell", "kind"]);
            picture::write_exr(out, size, Some(&picture.rgba), channels)?;
        }
    }
    Ok(FrameReport { frame, cells: mesh.cell_count(), range })
}
