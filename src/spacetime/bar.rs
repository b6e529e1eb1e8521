//! The 1D-space case of seed 003 (Fig. 3): a bar over a 2D spacetime (x, t), triangles, a
//! cubic displacement per triangle, shown whole — every pixel of the image is a point (x, t)
//! and shows the strain energy density there, per pixel or, for comparison, per vertex.
//!
//! A bar element is the plane-strain element of [`super::cubic`] with no y dependence and
//! `u_y = 0`: its 10 monomials are the y-free ones of the 20 (1, x, t, x², xt, t², x³, x²t,
//! xt², t³), so `ε = ∂u/∂x` and `U = ½ (λ + 2μ) ε²` (the P-wave modulus of a bar in uniaxial
//! strain). One evaluation ([`super::evaluate`], `spacetime_evaluate` in GLSL) serves both
//! cases.
//!
//! The data are generated ([`bar1d`]): d'Alembert's solution of a Gaussian displacement released
//! at the centre of a bar fixed at x = 0 (the reflection there is out of phase: an odd image
//! pulse) and open at x = L (the wave travels on past it), L2-projected per triangle. Analytic,
//! not solved.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

use super::cubic::{evaluate, CubicCoefficients, LocalFrame, Material, PointFields, MONOMIALS};
use super::error::SpacetimeError;
use crate::gpu::{BindingKind, Buffer, Gpu, GpuError, GraphicsPipeline, GraphicsPipelineDesc, Resource};
use crate::render::{ColorFormat, Colormap, ColormapTexture, Pixels, RenderTarget, BACKGROUND};
use crate::tensor::{solve, Tensor};

/// Indices into [`MONOMIALS`] of the 10 monomials without y, in the seed's order.
pub const BAR_MONOMIALS: [usize; 10] = [0, 1, 3, 4, 6, 9, 10, 12, 15, 19];

/// One triangle's field: its frame (centre and extents in x and t) and the coefficients of
/// the 10 y-free monomials (local coordinates).
#[derive(Clone, Debug, PartialEq)]
pub struct BarElement {
    /// Frame centre (x, t).
    pub centre: [f64; 2],
    /// Frame extents (x, t), positive.
    pub extent: [f64; 2],
    /// Coefficients of [`BAR_MONOMIALS`].
    pub coefficients: [f64; 10],
}

impl BarElement {
    /// The same field as a plane-strain spacetime element (y extent 1, u_y = 0).
    pub fn as_spacetime(&self) -> (LocalFrame, CubicCoefficients) {
        let frame = LocalFrame {
            centre: [self.centre[0], 0.0, self.centre[1]],
            extent: [self.extent[0], 1.0, self.extent[1]],
        };
        let mut c = [[0.0; 2]; 20];
        for (k, &m) in BAR_MONOMIALS.iter().enumerate() {
            c[m][0] = self.coefficients[k];
        }
        (frame, c)
    }
}

/// A bar's spacetime triangulation with one material.
#[derive(Clone, Debug, PartialEq)]
pub struct BarMesh {
    /// Vertices (x, t).
    pub vertices: Vec<[f64; 2]>,
    /// Triangles: three vertex indices each.
    pub triangles: Vec<[u32; 3]>,
    /// One per triangle.
    pub elements: Vec<BarElement>,
    /// The bar's material.
    pub material: Material,
}

impl BarMesh {
    /// Corners of triangle `e`.
    pub fn corners(&self, e: usize) -> [[f64; 2]; 3] {
        self.triangles[e].map(|i| self.vertices[i as usize])
    }

    /// The fields of element `e` at `(x, t)` (no containment check).
    pub fn evaluate(&self, e: usize, x: f64, t: f64) -> PointFields {
        let (frame, c) = self.elements[e].as_spacetime();
        evaluate(&frame, &self.material, &c, [x, 0.0, t])
    }

    /// The bounding rectangle `[x0, x1, t0, t1]`.
    pub fn window(&self) -> [f64; 4] {
        self.vertices
            .iter()
            .fold([f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY], |w, p| {
                [w[0].min(p[0]), w[1].max(p[0]), w[2].min(p[1]), w[3].max(p[1])]
            })
    }

    /// Checks indices, finite values, non-degenerate triangles, positive extents and the
    /// material; the error names the element.
    pub fn validate(&self) -> Result<(), SpacetimeError> {
        if self.elements.len() != self.triangles.len() {
            return Err(SpacetimeError::Length {
                what: "bar elements".into(),
                found: self.elements.len(),
                expected: self.triangles.len(),
            });
        }
        if let Some(what) = self.material.problem() {
            return Err(SpacetimeError::Invalid { element: 0, what: format!("the material {what}") });
        }
        for (e, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= self.vertices.len()) {
                return Err(SpacetimeError::BadIndex {
                    element: e,
                    index: u64::from(i),
                    vertices: self.vertices.len(),
                });
            }
            let p = self.corners(e);
            let f = &self.elements[e];
            if p.iter()
                .flatten()
                .chain(&f.centre)
                .chain(&f.extent)
                .chain(&f.coefficients)
                .any(|x| !x.is_finite())
            {
                return Err(SpacetimeError::NotFinite {
                    element: e,
                    what: "a corner, frame value or coefficient".into(),
                });
            }
            let area2 = (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
            let scale = (f.extent[0] * f.extent[1]).abs();
            if area2.abs() <= 1e-12 * scale || f.extent.iter().any(|&w| w <= 0.0) {
                return Err(SpacetimeError::Degenerate { element: e, volume: 0.5 * area2 });
            }
        }
        Ok(())
    }
}

/// The L2 projection of `field` onto the 10 y-free cubic monomials of the triangle `p`, in its
/// bounding-box frame: collapsed Gauss 5×5 quadrature (exact to degree 8 ≥ 6, the mass
/// matrix's degree), one solve.
pub fn project_bar_element(p: [[f64; 2]; 3], field: &(impl Fn(f64, f64) -> f64 + Sync)) -> BarElement {
    let lo = [p[0][0].min(p[1][0]).min(p[2][0]), p[0][1].min(p[1][1]).min(p[2][1])];
    let hi = [p[0][0].max(p[1][0]).max(p[2][0]), p[0][1].max(p[1][1]).max(p[2][1])];
    let centre = [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])];
    let extent = [hi[0] - lo[0], hi[1] - lo[1]];
    let mut mass = vec![0.0; 100];
    let mut rhs = [0.0; 10];
    for &(a, wa) in &super::generate::GAUSS5 {
        for &(b, wb) in &super::generate::GAUSS5 {
            // (l1, l2) = (a, b (1 − a)), Jacobian (1 − a).
            let (l1, l2) = (a, b * (1.0 - a));
            let w = wa * wb * (1.0 - a);
            let l0 = 1.0 - l1 - l2;
            let x = l0 * p[0][0] + l1 * p[1][0] + l2 * p[2][0];
            let t = l0 * p[0][1] + l1 * p[1][1] + l2 * p[2][1];
            let q = [(x - centre[0]) / extent[0], (t - centre[1]) / extent[1]];
            let m: [f64; 10] = std::array::from_fn(|k| {
                let e = MONOMIALS[BAR_MONOMIALS[k]];
                q[0].powi(e[0] as i32) * q[1].powi(e[2] as i32)
            });
            let f = field(x, t);
            for i in 0..10 {
                for j in 0..10 {
                    mass[10 * i + j] += w * m[i] * m[j];
                }
                rhs[i] += w * m[i] * f;
            }
        }
    }
    let mass = Tensor::from_vec(&[10, 10], mass).expect("10 × 10");
    // SPD for a non-degenerate triangle (the 10 monomials are independent on any open set).
    let c = solve("bar element mass matrix", &mass, &rhs).expect("non-degenerate triangle");
    BarElement { centre, extent, coefficients: std::array::from_fn(|k| c[k]) }
}

/// The bar's material: λ = 2, μ = 1, ρ = 1 (wave speed 2).
pub const BAR_MATERIAL: Material = Material { lambda: 2.0, mu: 1.0, density: 1.0 };

/// d'Alembert's solution for the bar `[0, length]` fixed at x = 0 with a Gaussian displacement
/// of amplitude `amp` and width `sigma` released at rest at `length / 2`:
/// `u = ½ [g(x − x₀ − ct) + g(x − x₀ + ct)] − ½ [g(−x − x₀ − ct) + g(−x − x₀ + ct)]` — the odd
/// image keeps `u(0, t) = 0` (the out-of-phase reflection); nothing reflects at x = L.
pub fn bar_pulse(material: Material, length: f64, amp: f64, sigma: f64) -> impl Fn(f64, f64) -> f64 + Sync {
    let c = material.p_wave_speed();
    let x0 = 0.5 * length;
    let g = move |xi: f64| amp * (-xi * xi / (2.0 * sigma * sigma)).exp();
    move |x: f64, t: f64| {
        0.5 * (g(x - x0 - c * t) + g(x - x0 + c * t)) - 0.5 * (g(-x - x0 - c * t) + g(-x - x0 + c * t))
    }
}

/// The Fig. 3 data set: the unit bar over the time the released pulse needs to reach the fixed
/// end, reflect and cross the bar (`1.25 L / c`), structured triangles (each rectangle of an
/// `nx × nt` grid split by a diagonal, alternating) about `elements` in all.
pub fn bar1d(elements: usize) -> BarMesh {
    let material = BAR_MATERIAL;
    let (length, duration) = (1.0, 1.25 / material.p_wave_speed());
    // Square-ish cells in (x, c t): nx = 1.6 nt.
    let nt = ((elements as f64 / 3.2).sqrt().round() as usize).max(1);
    let nx = ((1.6 * nt as f64).round() as usize).max(1);
    let mut vertices = Vec::with_capacity((nx + 1) * (nt + 1));
    for j in 0..=nt {
        for i in 0..=nx {
            vertices.push([length * i as f64 / nx as f64, duration * j as f64 / nt as f64]);
        }
    }
    let v = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
    let mut triangles = Vec::with_capacity(2 * nx * nt);
    for j in 0..nt {
        for i in 0..nx {
            if (i + j) % 2 == 0 {
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            } else {
                triangles.push([v(i, j), v(i + 1, j), v(i, j + 1)]);
                triangles.push([v(i + 1, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
    }
    let field = bar_pulse(material, length, 0.01, 0.05);
    let elements =
        triangles.par_iter().map(|t| project_bar_element(t.map(|i| vertices[i as usize]), &field)).collect();
    BarMesh { vertices, triangles, elements, material }
}

/// A bar element as the shaders read it (`SpacetimeElement`: centre and λ, extents and μ, the
/// 20 coefficient 2-vectors).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuBarElement {
    centre_lambda: [f32; 4],
    extent_mu: [f32; 4],
    coefficients: [[f32; 2]; 20],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BarVertex {
    xt: [f32; 2],
    element: u32,
    pad: u32,
}

crate::push_constants! {
    struct BarPush {
        window: [f32; 4],
        ramp: [f32; 4],
        flags: [u32; 4],
    }
}

/// A device failure met while doing `context` ([`SpacetimeError::device`]).
fn dev(context: &str) -> impl FnOnce(GpuError) -> SpacetimeError + '_ {
    SpacetimeError::device(context)
}

/// Draws a [`BarMesh`] whole: x across the image, t upwards, the window of the mesh filling
/// the target.
pub struct BarRenderer {
    gpu: Gpu,
    window: [f64; 4],
    elements: Buffer<GpuBarElement>,
    vertices: Buffer<BarVertex>,
    colormap: ColormapTexture,
    pipelines: std::collections::HashMap<ColorFormat, (GraphicsPipeline, crate::gpu::DescriptorSet)>,
}

impl BarRenderer {
    /// Validates `mesh` and uploads it.
    pub fn new(gpu: &Gpu, mesh: &BarMesh, colormap: &Colormap) -> Result<Self, SpacetimeError> {
        mesh.validate()?;
        let m = mesh.material;
        let elements: Vec<GpuBarElement> = mesh
            .elements
            .iter()
            .map(|e| {
                let (frame, c) = e.as_spacetime();
                let (cf, wf) = (frame.centre.map(|x| x as f32), frame.extent.map(|x| x as f32));
                GpuBarElement {
                    centre_lambda: [cf[0], cf[1], cf[2], m.lambda as f32],
                    extent_mu: [wf[0], wf[1], wf[2], m.mu as f32],
                    coefficients: c.map(|v| v.map(|x| x as f32)),
                }
            })
            .collect();
        let vertices: Vec<BarVertex> = (0..mesh.triangles.len())
            .flat_map(|e| {
                mesh.corners(e).map(|p| BarVertex {
                    xt: [p[0] as f32, p[1] as f32],
                    element: e as u32,
                    pad: 0,
                })
            })
            .collect();
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            gpu: gpu.clone(),
            window: mesh.window(),
            elements: Buffer::from_slice(gpu, "bar elements", &elements, storage)
                .map_err(dev("uploading the bar"))?,
            vertices: Buffer::from_slice(gpu, "bar vertices", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)
                .map_err(dev("uploading the bar"))?,
            colormap: colormap.upload(gpu).map_err(dev("uploading the colour map"))?,
            pipelines: Default::default(),
        })
    }

    /// The rectangle `[x0, x1, t0, t1]` the image shows.
    pub fn window(&self) -> [f64; 4] {
        self.window
    }

    /// The point `(x, t)` at the centre of pixel (`px`, `py`) of a `width`×`height` image.
    pub fn pixel_point(&self, px: u32, py: u32, width: u32, height: u32) -> [f64; 2] {
        let [x0, x1, t0, t1] = self.window;
        let sx = (f64::from(px) + 0.5) / f64::from(width);
        let sy = (f64::from(py) + 0.5) / f64::from(height);
        [x0 + sx * (x1 - x0), t1 - sy * (t1 - t0)]
    }

    /// Renders the bar: lit-free colour from U on the seed's log ramp with `u_max` (per pixel,
    /// or per vertex interpolated when `per_vertex`) in an RGBA8 target; `(U, |v|, u, s)` in an
    /// RGBA32F target, `s` the colour coordinate shown (NaN outside the mesh).
    pub fn render(
        &mut self,
        target: &RenderTarget,
        u_max: f64,
        per_vertex: bool,
    ) -> Result<Pixels, SpacetimeError> {
        let format = target.format();
        if !self.pipelines.contains_key(&format) {
            let mut desc = GraphicsPipelineDesc::new(
                "spacetime bar",
                crate::spacetime::shaders::BAR_VERT,
                crate::spacetime::shaders::BAR_FRAG,
                target.render_pass(),
            );
            desc.bindings = &[BindingKind::StorageBuffer, BindingKind::Texture];
            desc.push = crate::gpu::PushLayout::of::<BarPush>();
            desc.vertex_stride = std::mem::size_of::<BarVertex>() as u32;
            desc.vertex_attributes = &[(0, vk::Format::R32G32_SFLOAT, 0), (1, vk::Format::R32_UINT, 8)];
            let p = GraphicsPipeline::new(&self.gpu, &desc).map_err(dev("building the bar pipeline"))?;
            let binding = self.elements.binding().map_err(dev("binding the bar"))?;
            let set = p
                .bind(&self.gpu, &[Resource::Storage(binding), self.colormap.resource()])
                .map_err(dev("binding the bar"))?;
            self.pipelines.insert(format, (p, set));
        }
        let (pipeline, set) = &self.pipelines[&format];
        let data = format == ColorFormat::Rgba32F;
        let push = BarPush {
            window: self.window.map(|x| x as f32),
            ramp: [u_max as f32, self.colormap.texels() as f32, 0.0, 0.0],
            flags: [u32::from(data), u32::from(per_vertex), 0, 0],
        };
        let clear = if data { [f32::NAN; 4] } else { BACKGROUND };
        let (vertices, count) = (self.vertices.whole(), self.vertices.len() as u32);
        let extent = target.extent();
        target
            .render(&self.gpu, clear, |rec| {
                pipeline.record_draw(rec, extent, set, &push, Some(vertices), count)
            })
            .map_err(dev("drawing the bar"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pulse_solves_the_wave_equation_and_the_fixed_end_holds() {
        let m = BAR_MATERIAL;
        let u = bar_pulse(m, 1.0, 0.01, 0.05);
        let c = m.p_wave_speed();
        let h = 1e-3;
        for &(x, t) in &[(0.3, 0.1), (0.45, 0.2), (0.1, 0.4), (0.7, 0.5)] {
            let utt = (u(x, t + h) - 2.0 * u(x, t) + u(x, t - h)) / (h * h);
            let uxx = (u(x + h, t) - 2.0 * u(x, t) + u(x - h, t)) / (h * h);
            // Central differences: O(h²) of the fourth derivatives (~amp/σ⁴ ~ 1e3) ≈ 1e-3.
            assert!((utt - c * c * uxx).abs() < 1e-2, "({x}, {t}): {utt} vs {}", c * c * uxx);
        }
        for t in [0.0, 0.2, 0.3, 0.6] {
            assert!(u(0.0, t).abs() < 1e-15, "fixed end moves at t = {t}");
        }
        // Out of phase: after reflecting, the pulse comes back negative.
        let t = 0.5 / c + 0.25 / c;
        assert!(u(0.25, t) < -0.4 * 0.01, "{}", u(0.25, t));
    }

    #[test]
    fn a_cubic_in_x_and_t_is_projected_exactly() {
        let f = |x: f64, t: f64| 1.0 + x * x * t - 2.0 * t * t * t + x;
        let p = [[0.2, 0.1], [0.5, 0.15], [0.3, 0.4]];
        let e = project_bar_element(p, &f);
        let mesh = BarMesh {
            vertices: p.to_vec(),
            triangles: vec![[0, 1, 2]],
            elements: vec![e],
            material: BAR_MATERIAL,
        };
        mesh.validate().unwrap();
        let (x, t) = (0.31, 0.2);
        let got = mesh.evaluate(0, x, t);
        assert!((got.displacement[0] - f(x, t)).abs() < 1e-12);
        assert_eq!(got.displacement[1], 0.0);
        // ε = ∂u/∂x = 2xt + 1; U = ½ (λ + 2μ) ε².
        let eps = 2.0 * x * t + 1.0;
        assert!((got.strain_energy_density - 0.5 * 4.0 * eps * eps).abs() < 1e-10);
        // v = ∂u/∂t = x² − 6t².
        assert!((got.speed - (x * x - 6.0 * t * t).abs()).abs() < 1e-12);
    }
}
