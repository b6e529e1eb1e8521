//! The f64 reference of isosurfaces (`iso.frag`), computed plainly: for every pixel the ray
//! from the eye through the pixel centre ([`Camera::pixel_ray`]), for every element whose box
//! (of its Bernstein control points) it crosses, [`REFERENCE_SAMPLES_PER_ORDER`] × (n + 1)
//! uniform samples along the crossing (four times the device's density), each pulled back by
//! Newton's method in f64; every sign change of f − c between two samples within the margin
//! of the element is bisected to 10⁻¹⁵ of the segment, and the nearest root inside an
//! element, over elements and iso values, is the pixel's.

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
    let boxes: Vec<([f64; 3], [f64; 3])> = match super::render::element_boxes(mesh) {
        Ok(b) => b.chunks_exact(2).map(|p| (p[0], p[1])).map(|(a, b)| (f3(a), f3(b))).collect(),
        Err(_) => return vec![None; (width * height) as usize],
    };
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

fn f3(p: [f32; 4]) -> [f64; 3] {
    [p[0], p[1], p[2]].map(f64::from)
}

/// The ray's parameters (from `o` along unit `d`, t ≥ 0) inside the box [lo, hi].
fn slab(o: [f64; 3], d: [f64; 3], lo: [f64; 3], hi: [f64; 3]) -> Option<(f64, f64)> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for a in 0..3 {
        let (ta, tb) = ((lo[a] - o[a]) / d[a], (hi[a] - o[a]) / d[a]);
        t0 = t0.max(ta.min(tb));
        t1 = t1.min(ta.max(tb));
    }
    (t0 < t1).then_some((t0, t1))
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
    let centre = if mesh.shape == super::Shape::Tetrahedron { [0.25; 3] } else { [0.5; 3] };
    let pull = |t: f64, guess: [f64; 3]| -> Option<[f64; 3]> {
        mesh.inverse_map_hex(e, at(t), guess).or_else(|| mesh.inverse_map_hex(e, at(t), centre))
    };
    let samples = REFERENCE_SAMPLES_PER_ORDER * (mesh.basis.order.max(mesh.geometry.order) + 1);
    let mut previous: Option<(f64, [f64; 3], f64)> = None;
    let mut guess = centre;
    for s in 0..=samples {
        let t = t0 + (t1 - t0) * s as f64 / samples as f64;
        let Some(r) = pull(t, guess).filter(|r| mesh.shape.outside(r) <= MARGIN) else {
            previous = None;
            continue;
        };
        guess = r;
        let f = mesh.value_hex(field, step, e, r);
        if let Some((tp, rp, fp)) = previous {
            // The value crossed first in this interval (linear estimate), then bisected.
            let first = values
                .iter()
                .enumerate()
                .filter(|(_, &c)| (fp - c < 0.0) != (f - c < 0.0))
                .min_by(|a, b| ((fp - a.1) / (fp - f)).total_cmp(&((fp - b.1) / (fp - f))));
            if let Some((k, &c)) = first {
                let (mut lo, mut hi, mut q) = (tp, t, rp);
                let lo_negative = fp - c < 0.0;
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if let Some(r) = pull(mid, q) {
                        q = r;
                    }
                    if (mesh.value_hex(field, step, e, q) - c < 0.0) == lo_negative {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                    if hi - lo <= 1e-15 * (t1 - t0) {
                        break;
                    }
                }
                let root = 0.5 * (lo + hi);
                if let Some(r) = pull(root, q).filter(|r| mesh.shape.outside(r) <= 1e-9) {
                    return Some(IsoHit {
                        element: e,
                        value_index: k,
                        distance: root,
                        reference: r,
                        direction: d,
                    });
                }
            }
        }
        previous = Some((t, r, f));
    }
    None
}
