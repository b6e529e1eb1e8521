//! The per-pixel check of a rendered field against the CPU f64 reference (seed 002's claim,
//! made testable): every pixel the renderer covered must show its element's polynomial at the
//! reference point that maps to the pixel centre (the inverse map solved in f64), and every
//! pixel centre that lies inside an element must be covered. Shared by the tests and the demo.

use super::mesh::SpectralMesh;
use super::render::View2d;
use crate::render::Camera;

/// How a rendered `(value, ξ, η, element)` image compares with the f64 reference.
#[derive(Clone, Debug, Default)]
pub struct PixelReport {
    /// Pixels an element covered.
    pub covered: usize,
    /// Pixels only edge overdraw covered (marked by a negative element channel): cracks and a
    /// rim of at most one pixel outside the mesh's boundary, showing the edge's value.
    pub overdraw: usize,
    /// Largest |GPU − reference| over the covered pixels.
    pub max_error: f64,
    /// Largest ratio of that error to the pixel's own f32 rounding bound (≤ 1 passes).
    pub max_error_ratio: f64,
    /// Where the ratio was largest: pixel, GPU value, reference value, bound.
    pub worst: Option<(u32, u32, f64, f64, f64)>,
    /// Covered pixels whose centre is not inside the element that drew them (beyond the
    /// renderer's inside tolerance, with a margin).
    pub wrong_element: usize,
    /// Covered pixels not compared: the reference or its bound is not finite (derived fields
    /// where a function meets the edge of its domain; always 0 for a field itself).
    pub uncomparable: usize,
    /// Uncovered pixels whose centre lies inside an element (by more than 10⁻³ of its
    /// reference square from its edges).
    pub missing: usize,
}

impl PixelReport {
    /// Whether every pixel passed.
    pub fn passed(&self) -> bool {
        self.max_error_ratio <= 1.0 && self.wrong_element == 0 && self.missing == 0
    }

    /// Accounts pixel `at`, which shows `shown` where the reference is `reference` within
    /// `bound`.
    fn compare(&mut self, at: (u32, u32), shown: f32, reference: f64, bound: f64) {
        let err = (f64::from(shown) - reference).abs();
        self.max_error = self.max_error.max(err);
        let ratio = err / bound;
        if ratio > self.max_error_ratio {
            self.max_error_ratio = ratio;
            self.worst = Some((at.0, at.1, f64::from(shown), reference, bound));
        }
    }
}

/// The f32 rounding bound of the value shown at reference point `r` of element `e`, times 4:
/// the tensor-product sum's rounding, 8m ε Σ|ℓ_i ℓ_j F_ij| (m = n + 1 terms per axis, each
/// basis value a product of m factors), plus the field's change over the reference-point error
/// that f32 geometry causes, |∇_ξ f| ‖J⁻¹‖ (2|p| + 8(g + 1) Σ|g_i g_j X_ij|) ε (pixel centre
/// and geometry map rounded to f32, pulled back through the Jacobian). Rational cells: the
/// sums are homogeneous (over w F and w X) and divided by W = Σ w B, so each sum's bound is
/// over W plus the quotient's size times W's own bound.
pub fn rounding_bound(mesh: &SpectralMesh, field: usize, step: usize, e: usize, r: [f64; 2]) -> f64 {
    if mesh.shape == super::mesh::Shape::Triangle {
        return rounding_bound_triangle(mesh, field, step, e, r);
    }
    let eps = f64::from(f32::EPSILON);
    let (fb, gb) = (&mesh.basis, &mesh.geometry);
    let (m, gm) = (fb.len(), gb.len());
    let (mut a, mut da, mut b, mut db) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
    fb.eval(r[0], &mut a, Some(&mut da));
    fb.eval(r[1], &mut b, Some(&mut db));
    let v = mesh.element_values(field, step, e);
    // Rational cells: homogeneous sums over w F and w, then N / W (weights 1 otherwise).
    let weights = mesh.element_weights(e);
    let wk = |k: usize| weights.map_or(1.0, |w| w[k]);
    let (mut s, mut fx, mut fy) = (0.0, 0.0, 0.0);
    let (mut n, mut ws, mut ws_abs, mut wx, mut wy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for j in 0..m {
        for i in 0..m {
            let k = j * m + i;
            s += (a[i] * b[j] * wk(k) * v[k]).abs();
            fx += da[i] * b[j] * wk(k) * v[k];
            fy += a[i] * db[j] * wk(k) * v[k];
            n += a[i] * b[j] * wk(k) * v[k];
            ws += a[i] * b[j] * wk(k);
            ws_abs += (a[i] * b[j] * wk(k)).abs();
            wx += da[i] * b[j] * wk(k);
            wy += a[i] * db[j] * wk(k);
        }
    }
    if weights.is_some() {
        // f = N / W: the numerator's and the denominator's rounding, and (N / W)'.
        let f = n / ws;
        s = (s + f.abs() * ws_abs) / ws;
        (fx, fy) = ((fx - f * wx) / ws, (fy - f * wy) / ws);
    }
    let (mut ga, mut gbv) = ([0.0; 16], [0.0; 16]);
    gb.eval(r[0], &mut ga, None);
    gb.eval(r[1], &mut gbv, None);
    let pts = mesh.element_points(e);
    let mut gs: f64 = 0.0;
    for (k, p) in pts.iter().enumerate() {
        gs += (ga[k % gm] * gbv[k / gm] * wk(k)).abs() * p[0].abs().max(p[1].abs());
    }
    let (x, [dx, dy]) = mesh.map(e, r[0], r[1]);
    if weights.is_some() {
        // x = (Σ B w X) / W: the homogeneous sums' rounding over W, plus |x| times W's.
        gs = (gs + x[0].abs().max(x[1].abs()) * ws_abs) / ws;
    }
    let det = (dx[0] * dy[1] - dy[0] * dx[1]).abs();
    // ‖J⁻¹‖ ≤ ‖J‖_F / |det J| for 2 × 2.
    let jinv = (dx[0] * dx[0] + dx[1] * dx[1] + dy[0] * dy[0] + dy[1] * dy[1]).sqrt() / det;
    let position = 2.0 * x[0].abs().max(x[1].abs()) + 8.0 * gm as f64 * gs;
    4.0 * (8.0 * m as f64 * eps * s + fx.hypot(fy) * jinv * position * eps)
}

/// [`rounding_bound`] on a Lagrange triangle of order n: the same two terms with Silvester's
/// basis, whose values are products of n factors summed in n + 1 rows of at most n + 1 terms
/// (so the sum's rounding is within 8(n + 1) ε Σ|L F|, as for a quadrilateral of m = n + 1),
/// and the geometry's 8(g + 1) ε Σ|L X| through the Jacobian, times 4.
fn rounding_bound_triangle(mesh: &SpectralMesh, field: usize, step: usize, e: usize, r: [f64; 2]) -> f64 {
    let eps = f64::from(f32::EPSILON);
    let v = mesh.element_values(field, step, e);
    let (mut s, mut fx, mut fy) = (0.0, 0.0, 0.0);
    super::simplex::triangle_terms(mesh.basis.order, r, |k, l, [lx, ly]| {
        s += (l * v[k]).abs();
        fx += lx * v[k];
        fy += ly * v[k];
    });
    let pts = mesh.element_points(e);
    let mut gs = 0.0;
    super::simplex::triangle_terms(mesh.geometry.order, r, |k, l, _| {
        gs += l.abs() * pts[k][0].abs().max(pts[k][1].abs())
    });
    let (x, [dx, dy]) = mesh.map(e, r[0], r[1]);
    let det = (dx[0] * dy[1] - dy[0] * dx[1]).abs();
    let jinv = (dx[0] * dx[0] + dx[1] * dx[1] + dy[0] * dy[0] + dy[1] * dy[1]).sqrt() / det;
    let position = 2.0 * x[0].abs().max(x[1].abs()) + 8.0 * (mesh.geometry.order + 1) as f64 * gs;
    4.0 * (8.0 * (mesh.basis.order + 1) as f64 * eps * s + fx.hypot(fy) * jinv * position * eps)
}

/// Compares `pixels` (RGBA32F `(value, ξ, η, element)`, NaN where uncovered, element
/// −(e + 1) where only edge overdraw drew) of `field` at
/// `step`, drawn with `view` into `width` × `height`, with the f64 reference, pixel by pixel.
pub fn check_pixels(
    mesh: &SpectralMesh,
    field: usize,
    step: usize,
    view: &View2d,
    size: (u32, u32),
    pixels: &[f32],
) -> PixelReport {
    check_pixels_of(mesh, view, size, pixels, |e, r| {
        (mesh.value(field, step, e, r[0], r[1]), rounding_bound(mesh, field, step, e, r))
    })
}

/// [`check_pixels`] for a derived field (`--expr`): the reference is the expression in f64
/// at the pixel centre's reference point, the bound [`DerivedField::rounding_bound`].
/// Pixels whose bound is infinite (a function at the edge of its domain) are counted in
/// `PixelReport::uncomparable`, not compared.
pub fn check_derived_pixels(
    mesh: &SpectralMesh,
    derived: &crate::expression::spectral::DerivedField,
    (field, step): (usize, usize),
    view: &View2d,
    size: (u32, u32),
    pixels: &[f32],
) -> PixelReport {
    check_pixels_of(mesh, view, size, pixels, |e, r| {
        (derived.value_at(mesh, field, step, e, r), derived.rounding_bound(mesh, field, step, e, r))
    })
}

/// The per-pixel comparison of [`check_pixels`] with the reference value and its bound at
/// element e's reference point r given by `reference(e, r)`.
fn check_pixels_of(
    mesh: &SpectralMesh,
    view: &View2d,
    (width, height): (u32, u32),
    pixels: &[f32],
    reference: impl Fn(usize, [f64; 2]) -> (f64, f64),
) -> PixelReport {
    let mut report = PixelReport::default();
    let slack = 1e-4;
    for py in 0..height {
        for px in 0..width {
            let k = 4 * (py * width + px) as usize;
            let p = view.pixel_centre(px, py, width, height);
            let texel = &pixels[k..k + 4];
            if texel[3].is_nan() {
                if let Some((_, r)) = mesh.locate(p, -1e-3) {
                    debug_assert!(mesh.shape.outside(&r) <= -1e-3);
                    report.missing += 1;
                }
                continue;
            }
            if texel[3] < 0.0 {
                report.overdraw += 1;
                continue;
            }
            report.covered += 1;
            let e = texel[3] as usize;
            let guess = [f64::from(texel[1]), f64::from(texel[2])];
            let Some(r) = mesh.inverse_map(e, p, guess).filter(|r| mesh.shape.outside(r) <= slack) else {
                report.wrong_element += 1;
                continue;
            };
            let r = mesh.shape.clamp(r);
            let (value, bound) = reference(e, r);
            if !bound.is_finite() || !value.is_finite() {
                report.uncomparable += 1;
                continue;
            }
            report.compare((px, py), texel[0], value, bound);
        }
    }
    report
}

/// [`rounding_bound`] for hexahedra at r = (ξ, η, ζ): the triple sum's rounding,
/// 12m ε Σ|ℓ_i ℓ_j ℓ_k F_ijk|, plus the field's change over the reference-point error that the
/// f32 point on the cut plane causes, |∇_r f| ‖J⁻¹‖ (64 |x| + 12(g + 1) Σ|g g g X|) ε (the
/// point is interpolated across the drawn rectangle: tens of ulps), times 4.
pub fn rounding_bound_hex(mesh: &SpectralMesh, field: usize, step: usize, e: usize, r: [f64; 3]) -> f64 {
    if mesh.shape == super::mesh::Shape::Tetrahedron {
        return rounding_bound_tetra(mesh, field, step, e, r);
    }
    let eps = f64::from(f32::EPSILON);
    let (fb, gb) = (&mesh.basis, &mesh.geometry);
    let (m, gm) = (fb.len(), gb.len());
    let mut v = [[0.0; 16]; 3];
    let mut d = [[0.0; 16]; 3];
    for a in 0..3 {
        fb.eval(r[a], &mut v[a], Some(&mut d[a]));
    }
    let f = mesh.element_values(field, step, e);
    let weights = mesh.element_weights(e);
    let wk = |k: usize| weights.map_or(1.0, |w| w[k]);
    let (mut s, mut grad) = (0.0, [0.0; 3]);
    let (mut n, mut ws, mut ws_abs, mut wgrad) = (0.0, 0.0, 0.0, [0.0; 3]);
    for k in 0..m {
        for j in 0..m {
            for i in 0..m {
                let node = (k * m + j) * m + i;
                let c = f[node] * wk(node);
                s += (v[0][i] * v[1][j] * v[2][k] * c).abs();
                let tensor =
                    [d[0][i] * v[1][j] * v[2][k], v[0][i] * d[1][j] * v[2][k], v[0][i] * v[1][j] * d[2][k]];
                for a in 0..3 {
                    grad[a] += tensor[a] * c;
                    wgrad[a] += tensor[a] * wk(node);
                }
                n += v[0][i] * v[1][j] * v[2][k] * c;
                ws += v[0][i] * v[1][j] * v[2][k] * wk(node);
                ws_abs += (v[0][i] * v[1][j] * v[2][k] * wk(node)).abs();
            }
        }
    }
    if weights.is_some() {
        // f = N / W, as rounding_bound.
        let value = n / ws;
        s = (s + value.abs() * ws_abs) / ws;
        grad = std::array::from_fn(|a| (grad[a] - value * wgrad[a]) / ws);
    }
    let mut g = [[0.0; 16]; 3];
    for a in 0..3 {
        gb.eval(r[a], &mut g[a], None);
    }
    let pts = mesh.element_points(e);
    let mut gs: f64 = 0.0;
    for k in 0..gm {
        for j in 0..gm {
            for i in 0..gm {
                let node = (k * gm + j) * gm + i;
                let p = pts[node];
                gs += (g[0][i] * g[1][j] * g[2][k] * wk(node)).abs()
                    * p[0].abs().max(p[1].abs()).max(p[2].abs());
            }
        }
    }
    let (x, j) = mesh.map_hex(e, r);
    if weights.is_some() {
        gs = (gs + x[0].abs().max(x[1].abs()).max(x[2].abs()) * ws_abs) / ws;
    }
    let jm = glam::DMat3::from_cols(j[0].into(), j[1].into(), j[2].into());
    let jinv = jm.inverse();
    let norm =
        (jinv.x_axis.length_squared() + jinv.y_axis.length_squared() + jinv.z_axis.length_squared()).sqrt();
    let position = 64.0 * x[0].abs().max(x[1].abs()).max(x[2].abs()) + 12.0 * gm as f64 * gs;
    let gradient = (grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]).sqrt();
    4.0 * (12.0 * m as f64 * eps * s + gradient * norm * position * eps)
}

/// [`rounding_bound_hex`] on a Lagrange tetrahedron of order n: the same terms with Silvester's
/// basis (products of n factors, summed as one run of (n + 1)(n + 2)(n + 3)/6 terms in layers:
/// within 12(n + 1) ε Σ|L F| as for a hexahedron of m = n + 1), times 4.
fn rounding_bound_tetra(mesh: &SpectralMesh, field: usize, step: usize, e: usize, r: [f64; 3]) -> f64 {
    let eps = f64::from(f32::EPSILON);
    let f = mesh.element_values(field, step, e);
    let (mut s, mut grad) = (0.0, [0.0; 3]);
    super::simplex::tetra_terms(mesh.basis.order, r, |k, l, dl| {
        s += (l * f[k]).abs();
        for a in 0..3 {
            grad[a] += dl[a] * f[k];
        }
    });
    let pts = mesh.element_points(e);
    let mut gs = 0.0;
    super::simplex::tetra_terms(mesh.geometry.order, r, |k, l, _| {
        gs += l.abs() * pts[k][0].abs().max(pts[k][1].abs()).max(pts[k][2].abs())
    });
    let (x, j) = mesh.map_hex(e, r);
    let jinv = glam::DMat3::from_cols(j[0].into(), j[1].into(), j[2].into()).inverse();
    let norm =
        (jinv.x_axis.length_squared() + jinv.y_axis.length_squared() + jinv.z_axis.length_squared()).sqrt();
    let position =
        64.0 * x[0].abs().max(x[1].abs()).max(x[2].abs()) + 12.0 * (mesh.geometry.order + 1) as f64 * gs;
    let gradient = (grad[0] * grad[0] + grad[1] * grad[1] + grad[2] * grad[2]).sqrt();
    4.0 * (12.0 * (mesh.basis.order + 1) as f64 * eps * s + gradient * norm * position * eps)
}

/// The point of cut plane `plane` (n · x = d, any normal length) that the camera sees through
/// the centre of pixel (`px`, `py`) of a `width` × `height` image: the f64 ray met with the
/// plane, as a cut-plane fragment interpolates it.
pub fn plane_point(
    camera: &Camera,
    plane: [f64; 4],
    px: u32,
    py: u32,
    (width, height): (u32, u32),
) -> [f64; 3] {
    let (o, d) = camera.pixel_ray(px, py, width, height);
    let n = glam::DVec3::new(plane[0], plane[1], plane[2]);
    let s = (plane[3] - n.dot(o)) / n.dot(d);
    (o + s * d).to_array()
}

/// [`check_pixels`] for cut planes through hexahedra or tetrahedra (`cut.frag`): every covered pixel of a
/// `(value, plane, ζ, element)` image shows its element's polynomial at the reference point of
/// the pixel's point on its plane ([`plane_point`], pulled back in f64) within
/// [`rounding_bound_hex`]; with a single plane, every pixel whose point lies inside an element
/// (by 10⁻³ of its reference cube or tetrahedron) is covered. Edge overdraw does not apply to cut planes.
pub fn check_cut_pixels(
    mesh: &SpectralMesh,
    field: usize,
    step: usize,
    camera: &Camera,
    planes: &[[f64; 4]],
    size: (u32, u32),
    pixels: &[f32],
) -> PixelReport {
    check_cut_pixels_of(mesh, camera, planes, size, pixels, |e, r| {
        (mesh.value_hex(field, step, e, r), rounding_bound_hex(mesh, field, step, e, r))
    })
}

/// [`check_cut_pixels`] for a derived field: the expression in f64 at the pixel's reference
/// point within [`DerivedField::rounding_bound_hex`] (infinite bounds counted as
/// uncomparable).
///
/// [`DerivedField::rounding_bound_hex`]: crate::expression::spectral::DerivedField::rounding_bound_hex
pub fn check_derived_cut_pixels(
    mesh: &SpectralMesh,
    derived: &crate::expression::spectral::DerivedField,
    (field, step): (usize, usize),
    (camera, planes): (&Camera, &[[f64; 4]]),
    size: (u32, u32),
    pixels: &[f32],
) -> PixelReport {
    check_cut_pixels_of(mesh, camera, planes, size, pixels, |e, r| {
        (derived.value_at_hex(mesh, field, step, e, r), derived.rounding_bound_hex(mesh, field, step, e, r))
    })
}

/// The per-pixel comparison of [`check_cut_pixels`] with the reference value and bound at
/// hexahedron e's reference point r given by `reference(e, r)`.
fn check_cut_pixels_of(
    mesh: &SpectralMesh,
    camera: &Camera,
    planes: &[[f64; 4]],
    size: (u32, u32),
    pixels: &[f32],
    reference: impl Fn(usize, [f64; 3]) -> (f64, f64),
) -> PixelReport {
    let mut report = PixelReport::default();
    let slack = 1e-4;
    for py in 0..size.1 {
        for px in 0..size.0 {
            let texel = &pixels[4 * (py * size.0 + px) as usize..][..4];
            if texel[3].is_nan() {
                if let [plane] = planes {
                    if mesh.locate_hex(plane_point(camera, *plane, px, py, size), -1e-3).is_some() {
                        report.missing += 1;
                    }
                }
                continue;
            }
            report.covered += 1;
            let (e, k) = (texel[3] as usize, texel[1] as usize);
            let Some(&plane) = planes.get(k) else {
                report.wrong_element += 1;
                continue;
            };
            let p = plane_point(camera, plane, px, py, size);
            let centre = if mesh.shape == super::mesh::Shape::Tetrahedron { [0.25; 3] } else { [0.5; 3] };
            let Some(r) = mesh.inverse_map_hex(e, p, centre).filter(|r| mesh.shape.outside(r) <= slack)
            else {
                report.wrong_element += 1;
                continue;
            };
            let r = mesh.shape.clamp(r);
            let (value, bound) = reference(e, r);
            if !bound.is_finite() || !value.is_finite() {
                report.uncomparable += 1;
                continue;
            }
            report.compare((px, py), texel[0], value, bound);
        }
    }
    report
}
