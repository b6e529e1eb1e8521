//! `galerkin radiosity render`'s picture: a scene's radiosity at one design-parameter vector —
//! the full solve (Eq. 14 with Eq. 15's form factors, visibility by ray casting) or a trained
//! model's reduced evaluation (Table 2) — drawn with flat or smooth shading and written as
//! PNG (tone-mapped sRGB) or EXR (the colour, then the raw radiance R, G, B and the face index
//! of every pixel); optionally the per-face result as a CSV or NPY table ([`super::face_table`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::any_scene::AnyScene;
use super::estimate::Estimate;
use super::reduced::ReducedRadiosity;
use super::render::{default_exposure, display_radiance, draw_picture, scene_vertices, Shading, Viewpoint};
use super::{LightMode, RadiosityError};
use crate::gpu::Gpu;
use crate::picture::{self, ImageFormat};

/// What to draw.
#[derive(Clone, Debug)]
pub struct PictureRequest {
    /// The design parameters (in the scene's order; [`AnyScene::parameters_from`]).
    pub params: Vec<f64>,
    /// The viewpoint (the two rooms; an OBJ scene is seen from outside its bounds).
    pub viewpoint: Viewpoint,
    /// A camera orbiting the scene's bounding box instead (`--camera`, `--fit`), overriding
    /// the viewpoint.
    pub orbit: Option<crate::render::Orbit>,
    /// The scene's outline and the axis triad drawn over a PNG ([`picture::Overlay`]).
    pub overlay: picture::Overlay,
    /// Flat or smooth shading.
    pub shading: Shading,
    /// Exposure (`None`: automatic from the solution, [`default_exposure`]).
    pub exposure: Option<f64>,
    /// Image size.
    pub size: (u32, u32),
    /// Also write the per-face radiosity here (CSV or NPY, f64: [`super::face_table`]).
    pub faces: Option<PathBuf>,
    /// The full solve's form factors (ignored with a model).
    pub form_factors: super::near_field::FormFactorMethod,
    /// With a model: the estimated error above which the configuration is untrusted and not
    /// drawn ([`Estimate::untrusted`]); `None` draws it whatever the estimate says (the
    /// report still carries it).
    pub trust_threshold: Option<f64>,
    /// A PNG gets a title above it (how the radiosity was found, faces, with a model its
    /// estimated error) and a colour bar beside it: the tone map's grey levels over radiance 0
    /// to [`LEGEND_WHITE`]`/exposure` ([`crate::render::Colormap::tone_ramp`]). `false`: the
    /// bare picture.
    pub legend: bool,
}

/// The top of a radiosity picture's colour bar, in units of 1/exposure: the tone map shows
/// radiance `LEGEND_WHITE / exposure` at `1 − e^{-4}` ≈ 98 % of white.
pub const LEGEND_WHITE: f64 = 4.0;

/// The legend's ramp at `exposure`: the tone map's grey levels over radiance 0 to
/// [`LEGEND_WHITE`]` / exposure` ([`crate::render::Colormap::tone_ramp`]).
pub fn tone_ramp(exposure: f64) -> crate::render::Colormap {
    crate::render::Colormap::tone_ramp(exposure, LEGEND_WHITE / exposure)
}

/// The colour bar of a radiosity picture or window at `exposure`, drawn with `tone`
/// ([`tone_ramp`] of the same exposure): the tone map's radiance scale.
pub fn tone_bar(tone: &crate::render::Colormap, exposure: f64) -> crate::plot::ColourBar<'_> {
    crate::plot::ColourBar {
        colormap: tone,
        range: (0.0, LEGEND_WHITE / exposure),
        log: false,
        label: "radiance (W/m²/sr), tone-mapped",
        shift: 0.0,
    }
}

/// What [`write_picture`] drew.
#[derive(Clone, Debug)]
pub struct PictureReport {
    /// Faces of the scene at these parameters.
    pub faces: usize,
    /// The lighting.
    pub lights: LightMode,
    /// How the radiosity was found: the full solve with its Jacobi sweeps, or the model.
    pub how: String,
    /// Seconds of the solve or the reduced evaluation (mesh build included).
    pub solve_seconds: f64,
    /// The exposure used.
    pub exposure: f64,
    /// With a model: its error estimate and stability check at these parameters
    /// ([`super::estimate`]).
    pub estimate: Option<Estimate>,
}

/// Solves `scene` at `request.params` — with `model` when given (its lighting must match the
/// scene's) — draws it and writes `out` (format by extension).
pub fn write_picture(
    gpu: &Gpu,
    scene: &AnyScene,
    model: Option<&ReducedRadiosity>,
    request: &PictureRequest,
    out: &Path,
) -> Result<PictureReport, RadiosityError> {
    let format = picture::format_of(out)?;
    if let Some(e) = request.exposure.filter(|e| !(e.is_finite() && *e > 0.0)) {
        return Err(RadiosityError::Mesh(format!("the exposure must be positive, got {e}")));
    }
    let space = scene.space();
    let lights = space.lights().clone();
    let start = Instant::now();
    let mesh = space.mesh(&request.params)?;
    let mut estimate = None;
    let exact_near = matches!(request.form_factors, super::near_field::FormFactorMethod::ExactNear { .. });
    let (mesh, geometry, radiosity, how) = match model {
        None => {
            let s = super::full_radiosity_with(mesh, &lights, request.form_factors)?;
            let near = if exact_near { ", exact near field" } else { "" };
            (s.mesh, s.geometry, s.radiosity, format!("full solve ({} Jacobi sweeps{near})", s.sweeps))
        }
        Some(model) => {
            if model.light_mode() != lights.mode {
                return Err(RadiosityError::Mesh(format!(
                    "the model was trained with {:?} lighting, the scene is lit by {:?}",
                    model.light_mode(),
                    lights.mode
                )));
            }
            let (b, _, found) = model.evaluate_estimated(&mesh)?;
            if let Some(why) = request.trust_threshold.and_then(|t| found.untrusted(t)) {
                return Err(RadiosityError::Untrusted(why));
            }
            estimate = Some(found);
            let geometry = mesh.geometry();
            (mesh, geometry, b, "reduced model loaded and evaluated (with its error estimate) in".to_string())
        }
    };
    let solve_seconds = start.elapsed().as_secs_f64();
    let radiance = display_radiance(&mesh, &geometry, &lights, &radiosity);
    let exposure = request.exposure.unwrap_or_else(|| default_exposure(&mesh, &geometry, &radiance));
    let vertices = scene_vertices(&mesh, &geometry, &radiance, request.shading);
    let camera = match request.orbit {
        Some(orbit) => {
            let (lo, hi) = mesh.bounds();
            orbit.camera(lo.to_array(), hi.to_array())
        }
        None => scene.camera(&mesh, request.viewpoint),
    };
    let mut picture = draw_picture(gpu, &vertices, &camera, exposure, request.size)?;
    if request.overlay != picture::Overlay::default() && format == ImageFormat::Png {
        let (lo, hi) = mesh.bounds();
        let projector = picture::Projector::Camera(&camera);
        picture::draw_overlay(
            &mut picture.rgba,
            request.size,
            projector,
            (lo.to_array(), hi.to_array()),
            request.overlay,
            out,
        )?;
    }
    let tone = tone_ramp(exposure);
    let title = match &estimate {
        Some(e) if e.error.is_finite() => {
            format!("radiance: reduced model, {} faces, estimated error {:.2} %", mesh.len(), 100.0 * e.error)
        }
        Some(_) => {
            format!("radiance: reduced model (trained without an error estimate), {} faces", mesh.len())
        }
        None => {
            let near = if exact_near { "exact near field" } else { "centroid form factors" };
            format!("radiance: full solve, {near}, {} faces", mesh.len())
        }
    };
    let legend = picture::Legend { title, bar: tone_bar(&tone, exposure) };
    match format {
        ImageFormat::Png => {
            picture::write_png(out, request.size, &picture.rgba, request.legend.then_some(&legend))?
        }
        ImageFormat::Exr => {
            let channels =
                picture::float_channels(&picture.raw, &["radiance.R", "radiance.G", "radiance.B", "face"]);
            picture::write_exr(out, request.size, Some(&picture.rgba), channels)?;
        }
    }
    if let Some(table) = &request.faces {
        super::face_table::write(table, &mesh, &geometry, &radiosity)?;
    }
    Ok(PictureReport { faces: mesh.len(), lights: lights.mode, how, solve_seconds, exposure, estimate })
}

/// The exposure a picture of `scene` at `params` gets by default: [`default_exposure`] of its
/// full solution (the viewer's starting exposure, so full and reduced frames share one).
pub fn automatic_exposure(scene: &AnyScene, params: &[f64]) -> Result<f64, RadiosityError> {
    let space = scene.space();
    let lights = space.lights().clone();
    let s = super::full_radiosity_of(space.mesh(params)?, &lights)?;
    let radiance = display_radiance(&s.mesh, &s.geometry, &lights, &s.radiosity);
    Ok(default_exposure(&s.mesh, &s.geometry, &radiance))
}

/// Refuses a model trained on a scene with another number of faces than `faces`.
pub fn check_model_faces(model: &ReducedRadiosity, faces: usize) -> Result<(), RadiosityError> {
    if faces != model.faces() {
        return Err(RadiosityError::Mesh(format!(
            "the model has {} faces, the scene {faces}",
            model.faces()
        )));
    }
    Ok(())
}
