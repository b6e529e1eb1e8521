//! The f64 reference of isosurfaces (`iso.frag`), computed plainly: for every pixel the ray
//! from the eye through the pixel centre ([`Camera::pixel_ray`]), for every element whose box
//! (of its Bernstein control points) it crosses, [`REFERENCE_SAMPLES_PER_ORDER`] × (n + 1)
//! uniform samples along the crossing (four times the device's density), each pulled back by
//! Newton's method in f64; every sign change of f − c between two samples within the margin
//! of the element is bisected to 10⁻¹⁵ of the segment, as is a pair of roots between two
//! samples that the parabola through three samples foresees (the device's test, at four times
//! its density), and the nearest root inside an element, over elements and iso values, is the
//! pixel's.

use rayon::prelude::*;

use super::mesh::SpectralMesh;
use crate::render::Camera;

/// Samples per order along an element's crossing (n + 1 of these per segment).
pub const REFERENCE_SAMPLES_PER_ORDER: usize = 16;

/// How far outside its element (reference units) a sample still brackets roots, the
/// polynomial continued there (the device's `SPECTRAL_ISO_MARGIN`).
const MARGIN: f64 = 0.25;

/// A pixel's isosurface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IsoHit {
    /// The element it lies in.
    pub element: usize,
    /// Which iso value.
    pub value_index: usize,
    /// Its distance from the eye along the ray.
    pub distance: f64,
    /// Its reference point.
    pub reference: [f64; 3],
    /// The ray's direction (unit).
    pub direction: [f64; 3],
}

/// The nearest isosurface point of `values` of `field` at `step` along each pixel's ray of a
/// `width` × `height` picture through `camera` (row-major, `None` where the ray meets none).
pub fn iso_reference(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    camera: &Camera,
    values: &[f64],
    (width, height): (u32, u32),
) -> Vec<Option<IsoHit>> {
    let Some(boxes) = reference_boxes(mesh) else { return vec![None; (width * height) as usize] };
    let eye = camera.eye;
    (0..width * height)
        .into_par_iter()
        .map(|k| {
            let (_, d) = camera.pixel_ray(k % width, k / width, width, height);
            let d = d.to_array();
            let mut best: Option<IsoHit> = None;
            for (e, (lo, hi)) in boxes.iter().enumerate() {
                let Some((t0, t1)) = slab(eye, d, *lo, *hi) else { continue };
                if best.is_some_and(|b| b.distance < t0) {
                    continue;
                }
                if let Some(hit) = first_root(mesh, (field, step), e, eye, d, (t0, t1), values) {
                    if best.is_none_or(|b| hit.distance < b.distance) {
                        best = Some(hit);
                    }
                }
            }
            best
        })
        .collect()
}

/// The isosurface's element-edge width in pixels (`SPECTRAL_ISO_EDGE_PX`): a surface point
/// this close to a face of its element, along the surface, is drawn dark with `--edges`.
pub const ISO_EDGE_PX: f64 = 1.0;

/// How far, in pixels along the isosurface, `hit` lies from the nearest face of its element
/// when seen through `camera` in a picture `height` pixels tall: for each face, its reference
/// coordinate's distance (r_a, 1 − r_a, or a tetrahedron's 1 − Σr) over the part of that
/// coordinate's physical gradient J⁻ᵀe_a tangent to the surface (normal ∇f/|∇f|), in pixels of
/// world size depth / focal (focal = height / (2 tan(fov/2))). Twin of
/// `iso_face_distance_px` (spectral_iso_frag.glsl).
pub fn face_distance_px(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    hit: &IsoHit,
    camera: &Camera,
    height: u32,
) -> f64 {
    let r = hit.reference;
    let (x, jac) = mesh.map_hex(hit.element, r);
    let inverse_t = glam::DMat3::from_cols(jac[0].into(), jac[1].into(), jac[2].into()).inverse().transpose();
    let (_, dr) = mesh.value_gradient_at(field, step, hit.element, r);
    let n = (inverse_t * glam::DVec3::from(dr)).normalize_or_zero();
    let along = |delta: f64, g: glam::DVec3| {
        let gt = g - g.dot(n) * n;
        if gt.length() > 0.0 {
            delta.max(0.0) / gt.length()
        } else {
            f64::INFINITY
        }
    };
    let simplex = mesh.shape == super::Shape::Tetrahedron;
    let mut best = f64::INFINITY;
    for (&ra, axis) in r.iter().zip(glam::DVec3::AXES) {
        let delta = if simplex { ra } else { ra.min(1.0 - ra) };
        best = best.min(along(delta, inverse_t * axis));
    }
    if simplex {
        best = best.min(along(1.0 - r[0] - r[1] - r[2], inverse_t * glam::DVec3::ONE));
    }
    let depth = -(camera.view().transform_point3(glam::DVec3::from(x))).z;
    best * camera.pixels_per_unit(height) / depth
}

/// Each element's box ([`super::render::element_boxes`]) in f64: (lo, hi); `None` when the
/// mesh has none (the ray casters then see nothing).
pub(super) fn reference_boxes(mesh: &SpectralMesh) -> Option<Vec<([f64; 3], [f64; 3])>> {
    let f3 = |p: [f32; 4]| [p[0], p[1], p[2]].map(f64::from);
    let boxes = super::render::element_boxes(mesh).ok()?;
    Some(boxes.chunks_exact(2).map(|p| (f3(p[0]), f3(p[1]))).collect())
}

/// The centre of the reference cube or tetrahedron: where a pull-back starts afresh.
pub(super) fn reference_centre(shape: super::Shape) -> [f64; 3] {
    if shape == super::Shape::Tetrahedron {
        [0.25; 3]
    } else {
        [0.5; 3]
    }
}

/// The reference point of element `e` that maps to `x`, by Newton's method from `guess`, once
/// more from the centre if that fails. Twin of `spectral_pull_hex` (spectral_ray.glsl).
pub(super) fn pull_back(mesh: &SpectralMesh, e: usize, x: [f64; 3], guess: [f64; 3]) -> Option<[f64; 3]> {
    mesh.inverse_map_hex(e, x, guess).or_else(|| mesh.inverse_map_hex(e, x, reference_centre(mesh.shape)))
}

/// The ray's parameters (from `o` along unit `d`, t ≥ 0) inside the box [lo, hi]. Twin of
/// `spectral_ray_box` (spectral_ray.glsl).
pub(super) fn slab(o: [f64; 3], d: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 < t1).then_some((t0, t1))
}

/// The parabola test for a pair of roots between samples without a sign change (touching
/// sheets, a surface the ray barely enters): three equally spaced samples a of f − c keep one
/// sign while the parabola through them turns toward zero between the outer two and comes
/// within a quarter of the smallest. Then its turning point u (in sample intervals from the
/// first), where the value decides. Twin of the test in spectral_iso_frag.glsl.
pub(super) fn parabola_pair([a0, a1, a2]: [f64; 3]) -> Option<f64> {
    let sgn = if a1 < 0.0 { -1.0 } else { 1.0 };
    let (a, b) = (0.5 * (a0 - 2.0 * a1 + a2), 0.5 * (4.0 * a1 - 3.0 * a0 - a2));
    if a0 * sgn <= 0.0 || a2 * sgn <= 0.0 || a * sgn <= 0.0 {
        return None;
    }
    let u = -b / (2.0 * a);
    let q = a0 + u * (b + a * u);
    (u > 0.0 && u < 2.0 && q * sgn < 0.25 * a0.abs().min(a1.abs()).min(a2.abs())).then_some(u)
}

/// The physical gradient J⁻ᵀ∇_r f of `field` at `step` in element `e` at reference point `r`.
pub(super) fn physical_gradient(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    e: usize,
    r: [f64; 3],
) -> glam::DVec3 {
    let (_, g) = mesh.value_gradient_at(field, step, e, r);
    let (_, j) = mesh.map_hex(e, r);
    let jm = glam::DMat3::from_cols(j[0].into(), j[1].into(), j[2].into());
    jm.inverse().transpose() * glam::DVec3::from(g)
}

/// The first root inside element `e` of f − c (any c of `values`) along the ray on [t0, t1].
fn first_root(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    e: usize,
    o: [f64; 3],
    d: [f64; 3],
    (t0, t1): (f64, f64),
    values: &[f64],
) -> Option<IsoHit> {
    let at = |t: f64| -> [f64; 3] { std::array::from_fn(|a| o[a] + t * d[a]) };
    let centre = reference_centre(mesh.shape);
    let pull = |t: f64, guess: [f64; 3]| pull_back(mesh, e, at(t), guess);
    let samples = REFERENCE_SAMPLES_PER_ORDER * (mesh.basis.order.max(mesh.geometry.order) + 1);
    let value = |r: [f64; 3]| mesh.value_hex(field, step, e, r);
    // The first root of f − c in [lo, hi] (f − c of sign `lo_negative` at lo), bisected from
    // reference point q: its ray parameter and reference point, if inside the element.
    let bisect = |mut lo: f64, mut hi: f64, lo_negative: bool, c: f64, mut q: [f64; 3]| {
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if let Some(r) = pull(mid, q) {
                q = r;
            }
            if (value(q) - c < 0.0) == lo_negative {
                lo = mid;
            } else {
                hi = mid;
            }
            if hi - lo <= 1e-15 * (t1 - t0) {
                break;
            }
        }
        let root = 0.5 * (lo + hi);
        pull(root, q).filter(|r| mesh.shape.outside(r) <= 1e-9).map(|r| (root, r))
    };
    // The last two usable samples: (t, r, f).
    let mut previous: [Option<(f64, [f64; 3], f64)>; 2] = [None, None];
    let mut guess = centre;
    for s in 0..=samples {
        let t = t0 + (t1 - t0) * s as f64 / samples as f64;
        let Some(r) = pull(t, guess).filter(|r| mesh.shape.outside(r) <= MARGIN) else {
            previous = [None, None];
            continue;
        };
        guess = r;
        let f = value(r);
        let mut hits: Vec<(f64, [f64; 3], usize)> = Vec::new();
        // A pair of roots between samples without a sign change (touching sheets, a surface
        // the ray barely enters): the parabola through the last three samples of one sign
        // turns toward zero between them and reaches a quarter of the smallest; the value at
        // its turning point decides.
        if let [Some((ta, ra, fa)), Some((tb, rb, fb))] = previous {
            for (k, &c) in values.iter().enumerate() {
                let Some(u) = parabola_pair([fa - c, fb - c, f - c]) else { continue };
                let sgn = if fb - c < 0.0 { -1.0 } else { 1.0 };
                let (lo, rlo) = if u >= 1.0 { (tb, rb) } else { (ta, ra) };
                let tv = ta + u * (tb - ta);
                let Some(rv) = pull(tv, rlo).filter(|r| mesh.shape.outside(r) <= MARGIN) else { continue };
                if (value(rv) - c) * sgn < 0.0 {
                    if let Some((root, r)) = bisect(lo, tv, sgn < 0.0, c, rlo) {
                        hits.push((root, r, k));
                    }
                }
            }
        }
        if let Some((tp, rp, fp)) = previous[1] {
            // The value crossed first in this interval (linear estimate), then bisected.
            let first = values
                .iter()
                .enumerate()
                .filter(|(_, &c)| (fp - c < 0.0) != (f - c < 0.0))
                .min_by(|a, b| ((fp - a.1) / (fp - f)).total_cmp(&((fp - b.1) / (fp - f))));
            if let Some((k, &c)) = first {
                if let Some((root, r)) = bisect(tp, t, fp - c < 0.0, c, rp) {
                    hits.push((root, r, k));
                }
            }
        }
        if let Some(&(distance, reference, value_index)) = hits.iter().min_by(|a, b| a.0.total_cmp(&b.0)) {
            return Some(IsoHit { element: e, value_index, distance, reference, direction: d });
        }
        previous = [previous[1], Some((t, r, f))];
    }
    None
}

/// How a device picture of isosurfaces agrees with [`iso_reference`] ([`compare`]).
#[derive(Clone, Debug, Default)]
pub struct IsoAgreement {
    /// Pixels where the reference finds a surface.
    pub shown: usize,
    /// Pixels where both find the same iso value's surface.
    pub matched: usize,
    /// The largest distance along the ray between the two points of a matched pixel, as a
    /// fraction of its bound.
    pub worst_of_bound: f64,
    /// The largest and the mean distance along the ray of matched pixels (world units).
    pub worst_along_ray: f64,
    /// See `worst_along_ray`.
    pub mean_along_ray: f64,
    /// Pixels where one side finds a surface and the other none or another value's, where the
    /// ray grazes the reference's surface (|cos| between ray and normal below 0.1).
    pub grazing: usize,
    /// Every other disagreement, and matched pixels past their bound: (pixel, what).
    pub mismatched: Vec<(usize, String)>,
}

/// |∂f/∂t| along unit ray `d` at element `e`'s reference point `r`, and |∇f|.
fn slope(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    e: usize,
    r: [f64; 3],
    d: [f64; 3],
) -> (f64, f64) {
    let grad = physical_gradient(mesh, (field, step), e, r);
    (grad.dot(glam::DVec3::from(d)).abs(), grad.length())
}

/// Compares a data picture of isosurfaces (per pixel, row-major: the value at the root, its
/// distance from the eye, the iso value's index, the element; NaN in the fourth where none —
/// what `iso.frag` writes into a float target) with the reference of the same view. A matched
/// pixel's distance along the ray must be within |Δt| ≤ 4 (δf / |∂f/∂t| + 2⁻²² ℓ + 16 ε t):
/// δf the f32 rounding bound of the value there ([`super::reference::rounding_bound_hex`]), ℓ
/// the mesh's bounding-box diagonal (the bisection's resolution is 2⁻²⁴ of a segment inside
/// it), ε t the f32 position's rounding.
pub fn compare(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    pixels: &[f32],
    reference: &[Option<IsoHit>],
) -> IsoAgreement {
    let diag = mesh.diagonal();
    let mut out = IsoAgreement::default();
    let mut sum = 0.0;
    for (k, want) in reference.iter().enumerate() {
        let Some(t) = pixels.get(4 * k..4 * k + 4) else { break };
        let got = (!t[3].is_nan()).then(|| (t[3] as usize, t[2] as usize, f64::from(t[1])));
        out.shown += usize::from(want.is_some());
        match (got, want) {
            (None, None) => {}
            (Some((e, vk, dist)), Some(h)) if vk == h.value_index => {
                let (ft, grad) = slope(mesh, (field, step), h.element, h.reference, h.direction);
                let delta_f = super::reference::rounding_bound_hex(mesh, field, step, h.element, h.reference);
                let bound = 4.0
                    * (delta_f / ft.max(1e-12 * grad)
                        + diag * 2f64.powi(-22)
                        + 16.0 * f64::from(f32::EPSILON) * h.distance);
                let err = (dist - h.distance).abs();
                out.matched += 1;
                out.worst_of_bound = out.worst_of_bound.max(err / bound);
                out.worst_along_ray = out.worst_along_ray.max(err);
                sum += err;
                if err > bound {
                    out.mismatched.push((
                        k,
                        format!("element {e} at {dist} vs {} at {} (bound {bound:e})", h.element, h.distance),
                    ));
                }
            }
            (got, want) => {
                let grazing = want.is_some_and(|h| {
                    let (ft, grad) = slope(mesh, (field, step), h.element, h.reference, h.direction);
                    ft < 0.1 * grad
                });
                if grazing {
                    out.grazing += 1;
                } else {
                    out.mismatched.push((k, format!("device {got:?}, reference {want:?}")));
                }
            }
        }
    }
    out.mean_along_ray = if out.matched > 0 { sum / out.matched as f64 } else { 0.0 };
    out
}
