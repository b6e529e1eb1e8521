//! A graphics pass whose fragment shader evaluates a polynomial of the fragment position: the
//! square [-1, 1]² of the plane z = 0, tessellated into triangles and seen through a perspective
//! camera, coloured by the bivariate cubic of [`super::polynomial`] at every pixel.
//!
//! Its CPU reference casts the ray through each pixel centre in f64, intersects the plane,
//! and evaluates the cubic there: the value the pixel must show if the pass is pixel-exact.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::DVec2;

use super::polynomial::BivariateCubic;
use crate::gpu::{
    BindingKind, Buffer, DescriptorSet, Gpu, GpuResult, GraphicsPipeline, GraphicsPipelineDesc, PushLayout,
    Recorder, RenderPass, Resource, Viewport,
};
use crate::render::{ramp_coordinate, Camera, Colormap, ColormapTexture};

/// What the fragment shader writes.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum FieldOutput {
    /// (p, x, y, 1) to a float target: the raw value, for checking and EXR files.
    Value,
    /// The colour of p through the colour map.
    Colour,
}

/// Ramp settings: the value range mapped onto the colour map, linear or logarithmic.
#[derive(Copy, Clone, Debug, PartialEq)]
pub struct Ramp {
    /// Value at the start of the colour map.
    pub lo: f64,
    /// Value at its end.
    pub hi: f64,
    /// Logarithmic mapping (needs 0 < lo < hi).
    pub log: bool,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct FieldUniform {
    coefficients: [f32; 12],
    ramp: [f32; 4],
}

/// Triangles covering [-1, 1]² on z = 0: `k`×`k` squares, two triangles each.
pub fn square_triangles(k: u32) -> Vec<[f32; 3]> {
    let k = k.max(1);
    let at = |i: u32| -1.0 + 2.0 * i as f32 / k as f32;
    let mut v = Vec::with_capacity(6 * (k * k) as usize);
    for j in 0..k {
        for i in 0..k {
            let (x0, x1, y0, y1) = (at(i), at(i + 1), at(j), at(j + 1));
            v.extend_from_slice(&[
                [x0, y0, 0.0],
                [x1, y0, 0.0],
                [x1, y1, 0.0],
                [x0, y0, 0.0],
                [x1, y1, 0.0],
                [x0, y1, 0.0],
            ]);
        }
    }
    v
}

crate::push_constants! {
    /// `field.vert`'s push constants.
    struct FieldPush {
        view_proj: [f32; 16],
    }
}

/// The field pass, resident: pipeline, triangles, coefficients, colour map.
pub struct FieldPass {
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    vertices: Buffer<[f32; 3]>,
    _uniform: Buffer<FieldUniform>,
    _colormap: ColormapTexture,
}

impl FieldPass {
    /// Builds the pass for `pass` (the render target's render pass).
    pub fn new(
        gpu: &Gpu,
        pass: &RenderPass,
        polynomial: &BivariateCubic,
        tessellation: u32,
        colormap: &Colormap,
        ramp: Ramp,
        output: FieldOutput,
    ) -> GpuResult<Self> {
        let mut coefficients = [0f32; 12];
        for (c, &p) in coefficients.iter_mut().zip(&polynomial.coefficients) {
            *c = p as f32;
        }
        let uniform = FieldUniform {
            coefficients,
            ramp: [
                ramp.lo as f32,
                ramp.hi as f32,
                if ramp.log { 1.0 } else { 0.0 },
                colormap.texels().len() as f32,
            ],
        };
        let uniform =
            Buffer::from_slice(gpu, "field coefficients", &[uniform], vk::BufferUsageFlags::UNIFORM_BUFFER)?;
        let vertices = Buffer::from_slice(
            gpu,
            "field triangles",
            &square_triangles(tessellation),
            vk::BufferUsageFlags::VERTEX_BUFFER,
        )?;
        let texture = colormap.upload(gpu)?;
        let spec = [u32::from(output == FieldOutput::Value)];
        let mut desc = GraphicsPipelineDesc::new(
            "field",
            crate::demo::shaders::FIELD_VERT,
            crate::demo::shaders::FIELD_FRAG,
            pass,
        );
        desc.bindings = &[BindingKind::UniformBuffer, BindingKind::Texture];
        desc.push = PushLayout::of::<FieldPush>();
        desc.vertex_stride = 12;
        desc.vertex_attributes = &[(0, vk::Format::R32G32B32_SFLOAT, 0)];
        desc.specialization = &spec;
        let pipeline = GraphicsPipeline::new(gpu, &desc)?;
        let set = pipeline.bind(gpu, &[Resource::Uniform(uniform.whole()), texture.resource()])?;
        Ok(Self { pipeline, set, vertices, _uniform: uniform, _colormap: texture })
    }

    /// Records the draw inside the render pass it was built for, in `viewport` (an extent: the
    /// whole target).
    pub fn record(&self, rec: &mut Recorder<'_>, viewport: impl Into<Viewport>, camera: &Camera) {
        let viewport = viewport.into();
        let m = FieldPush { view_proj: camera.view_proj_f32(viewport.aspect()).to_cols_array() };
        self.pipeline.record_draw(
            rec,
            viewport,
            &self.set,
            &m,
            Some(self.vertices.whole()),
            self.vertices.len() as u32,
        );
    }
}

/// What the CPU reference says a pixel must show.
#[derive(Copy, Clone, Debug, PartialEq)]
pub enum Coverage {
    /// The pixel centre sees the square at (x, y), farther than `margin` pixels from its
    /// outline: it must be drawn and show p(x, y).
    Inside {
        /// The plane point seen through the pixel centre.
        point: DVec2,
    },
    /// The pixel centre is outside the square by more than the margin: background.
    Outside,
    /// Within the margin of the outline: rasterisation rules decide; not checked.
    Edge,
}

/// CPU f64 reference coverage of every pixel (row-major from the top): the outline is projected
/// exactly and each pixel centre is classified with a `margin` in pixels.
pub fn reference_coverage(camera: &Camera, width: u32, height: u32, margin: f64) -> Vec<Coverage> {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| camera.project(glam::DVec3::new(x, y, 0.0), width, height))
        .map(|(x, y)| DVec2::new(x, y));
    let mut out = Vec::with_capacity((width * height) as usize);
    for py in 0..height {
        for px in 0..width {
            let c = DVec2::new(f64::from(px) + 0.5, f64::from(py) + 0.5);
            // Signed distance to each projected edge; the quad is convex, its orientation known
            // from the sign of its area.
            let area: f64 = (0..4).map(|i| corners[i].perp_dot(corners[(i + 1) % 4])).sum();
            let s = area.signum();
            let inside = (0..4)
                .map(|i| {
                    let (a, b) = (corners[i], corners[(i + 1) % 4]);
                    s * (b - a).perp_dot(c - a) / (b - a).length()
                })
                .fold(f64::INFINITY, f64::min);
            out.push(if inside > margin {
                match camera.pixel_on_plane_z(px, py, width, height, 0.0) {
                    Some(p) => Coverage::Inside { point: p.truncate() },
                    None => Coverage::Edge,
                }
            } else if inside < -margin {
                Coverage::Outside
            } else {
                Coverage::Edge
            });
        }
    }
    out
}

/// CPU f64 reference colour of a value: ramp coordinate, then the sampler's linear filtering.
pub fn reference_colour(colormap: &Colormap, ramp: Ramp, value: f64) -> [f64; 4] {
    colormap.sample(ramp_coordinate(value, ramp.lo, ramp.hi, ramp.log))
}

/// Pixels whose centre lies within this many pixels of the square's outline are left to the
/// rasteriser's tie-breaking rules (vertices snap to 1/256 px on lavapipe); all others are
/// checked.
pub const OUTLINE_MARGIN_PX: f64 = 0.05;

/// Tolerance of a value pixel seen at plane point `q`: the interpolated position is f32
/// (relative error ~1e-6 over a domain of size 1, so |Δx| ≤ 4e-6 with margin) and moves p by
/// |∇p|·|Δx|; the f32 Horner evaluation adds a few ulps of Σ|c_ij||x|ⁱ|y|ʲ.
pub fn value_tolerance(p: &BivariateCubic, q: DVec2) -> f64 {
    4e-6 * p.gradient_norm(q.x, q.y) + 8.0 * f64::from(f32::EPSILON) * p.abs_sum(q.x, q.y)
}

/// Outcome of comparing a rendered image with the CPU reference, pixel by pixel.
#[derive(Clone, Debug, Default)]
pub struct FieldCheck {
    /// Covered pixels compared.
    pub checked: usize,
    /// Background pixels compared.
    pub background: usize,
    /// Pixels on the outline, left unchecked.
    pub outline: usize,
    /// Largest error as a fraction of its tolerance (≤ 1 passes).
    pub worst: f64,
    /// Number of pixels outside tolerance.
    pub failures: usize,
    /// The first failing pixel, described.
    pub first_failure: Option<String>,
}

impl FieldCheck {
    fn fail(&mut self, what: String) {
        self.failures += 1;
        if self.first_failure.is_none() {
            self.first_failure = Some(what);
        }
    }

    /// True if every checked pixel was within tolerance.
    pub fn passed(&self) -> bool {
        self.failures == 0
    }
}

/// Walks every pixel against [`reference_coverage`]: covered pixels go to `inside`, which
/// returns the pixel's error as a fraction of its tolerance and, if out of tolerance, why;
/// background pixels must equal `background`; outline pixels are counted and skipped.
fn compare_pixels<T: Copy + PartialEq + std::fmt::Debug>(
    camera: &Camera,
    width: u32,
    height: u32,
    pixels: &[T],
    background: [T; 4],
    mut inside: impl FnMut(DVec2, &[T]) -> (f64, Option<String>),
) -> FieldCheck {
    let mut check = FieldCheck::default();
    for (i, c) in reference_coverage(camera, width, height, OUTLINE_MARGIN_PX).into_iter().enumerate() {
        let got = &pixels[4 * i..4 * i + 4];
        let (x, y) = (i as u32 % width, i as u32 / width);
        match c {
            Coverage::Inside { point } => {
                check.checked += 1;
                let (ratio, failure) = inside(point, got);
                check.worst = check.worst.max(if ratio.is_nan() { f64::INFINITY } else { ratio });
                if let Some(why) = failure {
                    check.fail(format!("pixel ({x}, {y}): {why}"));
                }
            }
            Coverage::Outside => {
                check.background += 1;
                if got != background {
                    check
                        .fail(format!("pixel ({x}, {y}) should be background {background:?}, holds {got:?}"));
                }
            }
            Coverage::Edge => check.outline += 1,
        }
    }
    check
}

/// Compares a value image (RGBA32F from [`FieldOutput::Value`], cleared to zero) with the CPU
/// reference: covered pixels must hold p at the plane point seen through their centre, within
/// [`value_tolerance`], with alpha 1; background pixels must be untouched.
pub fn check_values(
    camera: &Camera,
    p: &BivariateCubic,
    width: u32,
    height: u32,
    rgba: &[f32],
) -> FieldCheck {
    compare_pixels(camera, width, height, rgba, [0.0; 4], |point, got| {
        let reference = p.eval(point.x, point.y);
        let tol = value_tolerance(p, point);
        let ratio = (f64::from(got[0]) - reference).abs() / tol;
        let ok = ratio <= 1.0 && got[3] == 1.0;
        (ratio, (!ok).then(|| format!("{got:?} vs reference {reference} (tolerance {tol:.2e})")))
    })
}

/// Compares a colour image (RGBA8 from [`FieldOutput::Colour`]) with the CPU reference. A
/// covered pixel's channels must lie between the reference colours of p ± 1e-4 (p's own error
/// bound, generously) widened by 1.5/255 (the sampler's 8-bit subtexel weights and the final
/// 8-bit rounding), with alpha 255. Background pixels must hold `background`.
#[allow(clippy::too_many_arguments)]
pub fn check_colours(
    camera: &Camera,
    p: &BivariateCubic,
    colormap: &Colormap,
    ramp: Ramp,
    width: u32,
    height: u32,
    rgba: &[u8],
    background: [u8; 4],
) -> FieldCheck {
    const SLACK: f64 = 1.5 / 255.0;
    compare_pixels(camera, width, height, rgba, background, |point, got| {
        let v = p.eval(point.x, point.y);
        let lo = reference_colour(colormap, ramp, v - 1e-4);
        let hi = reference_colour(colormap, ramp, v + 1e-4);
        let mut worst = 0f64;
        let mut failure = None;
        for ch in 0..3 {
            let g = f64::from(got[ch]) / 255.0;
            let (a, b) = (lo[ch].min(hi[ch]), lo[ch].max(hi[ch]));
            let excess = (a - g).max(g - b).max(0.0);
            worst = worst.max(excess / SLACK);
            if excess > SLACK && failure.is_none() {
                failure = Some(format!("channel {ch}: {} outside [{a:.4}, {b:.4}] ± 1.5/255", got[ch]));
            }
        }
        if got[3] != 255 {
            failure = Some(format!("alpha {}", got[3]));
        }
        (worst, failure)
    })
}
