//! The f64 reference of volume rendering (`volume.frag`), computed plainly: for every pixel
//! the ray from the eye through the pixel centre ([`Camera::pixel_ray`]); for every element
//! whose box it crosses, `samples_per_order` × (n + 1) uniform samples along the crossing, each
//! pulled back by Newton's method in f64, the element's entry and exit bisected to 10⁻¹⁴ of the
//! crossing where the samples go in or out; each inside interval split where the field (linear
//! between its ends) crosses an opacity point and integrated by the midpoint rule in
//! [`REFERENCE_SUBSTEPS`] sub-steps with the field exact at each midpoint and the exponential
//! exact. The elements' parts are composited in order of entry. The quadrature converges at
//! second order: the tests check that doubling `samples_per_order` changes no channel by more
//! than a small fraction of 1/255.

use rayon::prelude::*;

use super::iso_reference::{pull_back, reference_boxes, reference_centre, slab};
use super::mesh::SpectralMesh;
use super::transfer::TransferFunction;
use crate::render::{ramp_coordinate, Camera, Colormap};

/// Midpoint sub-steps per piece (the device takes 2).
pub const REFERENCE_SUBSTEPS: usize = 8;

/// What the volume of one pixel's ray composites to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSample {
    /// Emitted colour reaching the eye (over black).
    pub colour: [f64; 3],
    /// Light let through, T = e^{−∫σ}.
    pub transmittance: f64,
}

/// The colour scale of a volume: the colour map over [lo, hi], linear or logarithmic.
#[derive(Clone, Debug)]
pub struct VolumeColours<'a> {
    /// The colour map.
    pub colormap: &'a Colormap,
    /// Its range.
    pub range: (f64, f64),
    /// Logarithmic.
    pub log: bool,
}

impl VolumeColours<'_> {
    fn colour(&self, f: f64) -> [f64; 3] {
        let c = self.colormap.sample(ramp_coordinate(f, self.range.0, self.range.1, self.log));
        [c[0], c[1], c[2]]
    }
}

/// The composited volume along each pixel's ray of a `width` × `height` picture through
/// `camera` (row-major; `None` where the ray meets no element), `samples_per_order` × (n + 1)
/// samples per element crossing.
pub fn volume_reference(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    camera: &Camera,
    tf: &TransferFunction,
    colours: &VolumeColours<'_>,
    (width, height): (u32, u32),
    samples_per_order: usize,
) -> Vec<Option<VolumeSample>> {
    let Some(boxes) = reference_boxes(mesh) else { return vec![None; (width * height) as usize] };
    let eye = camera.eye;
    (0..width * height)
        .into_par_iter()
        .map(|k| {
            let (_, d) = camera.pixel_ray(k % width, k / width, width, height);
            let d = d.to_array();
            let mut parts: Vec<(f64, [f64; 3], f64)> = Vec::new();
            for (e, (lo, hi)) in boxes.iter().enumerate() {
                let Some((t0, t1)) = slab(eye, d, *lo, *hi) else { continue };
                let ray = Ray { eye, d, t0, t1 };
                if let Some(part) = element_part(mesh, (field, step), e, &ray, tf, colours, samples_per_order)
                {
                    parts.push(part);
                }
            }
            if parts.is_empty() {
                return None;
            }
            parts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut colour, mut transmittance) = ([0.0; 3], 1.0);
            for (_, c, t) in parts {
                for a in 0..3 {
                    colour[a] += transmittance * c[a];
                }
                transmittance *= t;
            }
            Some(VolumeSample { colour, transmittance })
        })
        .collect()
}

/// A ray and its crossing [t0, t1] of one element's box.
struct Ray {
    eye: [f64; 3],
    d: [f64; 3],
    t0: f64,
    t1: f64,
}

/// Element `e`'s part of the ray: where the ray first enters it, the colour it emits
/// (composited from T = 1) and the light it lets through; `None` when no sample lies inside.
fn element_part(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    e: usize,
    ray: &Ray,
    tf: &TransferFunction,
    colours: &VolumeColours<'_>,
    samples_per_order: usize,
) -> Option<(f64, [f64; 3], f64)> {
    let at = |t: f64| -> [f64; 3] { std::array::from_fn(|a| ray.eye[a] + t * ray.d[a]) };
    let centre = reference_centre(mesh.shape);
    let inside_tol = super::render::INSIDE_TOLERANCE;
    // The reference point of t, if Newton converges.
    let pull = |t: f64, guess: [f64; 3]| pull_back(mesh, e, at(t), guess);
    // The reference point of t, if inside the element.
    let inside = |t: f64, guess: [f64; 3]| pull(t, guess).filter(|r| mesh.shape.outside(r) <= inside_tol);
    let clamp = |r: [f64; 3]| mesh.shape.clamp(r);
    let value = |r: [f64; 3]| mesh.value_hex(field, step, e, clamp(r));
    // The boundary between t_in (inside at r_in) and t_out, bisected: (t, r) at the inside end.
    let boundary = |mut t_in: f64, mut t_out: f64, mut r_in: [f64; 3]| {
        for _ in 0..60 {
            if (t_in - t_out).abs() <= 1e-14 * (ray.t1 - ray.t0) {
                break;
            }
            let t = 0.5 * (t_in + t_out);
            match inside(t, r_in) {
                Some(r) => {
                    t_in = t;
                    r_in = r;
                }
                None => t_out = t,
            }
        }
        (t_in, r_in)
    };
    let (mut colour, mut transmittance) = ([0.0f64; 3], 1.0f64);
    // Composites [a, b] by the midpoint rule, the field exact at each midpoint.
    let mut piece = |a: f64, b: f64, r: &mut [f64; 3]| {
        let h = (b - a) / REFERENCE_SUBSTEPS as f64;
        for k in 0..REFERENCE_SUBSTEPS {
            let t = a + (k as f64 + 0.5) * h;
            if let Some(q) = mesh.inverse_map_hex(e, at(t), *r) {
                *r = q;
            }
            let f = value(*r);
            let absorbed = 1.0 - (-tf.sigma(f) * h).exp();
            let c = colours.colour(f);
            for ch in 0..3 {
                colour[ch] += transmittance * absorbed * c[ch];
            }
            transmittance *= 1.0 - absorbed;
        }
    };
    // [a, b] with the field fa at a and fb at b, split where it crosses an opacity point.
    let mut interval = |a: f64, b: f64, fa: f64, fb: f64, mut r: [f64; 3]| {
        if b.partial_cmp(&a) != Some(std::cmp::Ordering::Greater) {
            return;
        }
        let mut cuts: Vec<f64> = tf
            .opacity
            .iter()
            .filter(|p| (p.0 - fa) * (p.0 - fb) < 0.0)
            .map(|p| a + (b - a) * (p.0 - fa) / (fb - fa))
            .collect();
        cuts.sort_by(f64::total_cmp);
        let mut lo = a;
        for t in cuts {
            piece(lo, t, &mut r);
            lo = t;
        }
        piece(lo, b, &mut r);
    };
    let samples = samples_per_order * (mesh.basis.order.max(mesh.geometry.order) + 1);
    let mut first: Option<f64> = None;
    // The previous sample: (t, its reference point if Newton converged, the field there if
    // inside).
    let mut previous: Option<(f64, Option<[f64; 3]>, Option<f64>)> = None;
    let mut guess = centre;
    for s in 0..=samples {
        let t = ray.t0 + (ray.t1 - ray.t0) * s as f64 / samples as f64;
        let pulled = pull(t, guess);
        let here = pulled.filter(|r| mesh.shape.outside(r) <= inside_tol);
        if let Some(r) = pulled {
            guess = r;
        }
        match (previous, here) {
            (Some((tp, Some(rp), Some(fp))), Some(r)) => interval(tp, t, fp, value(r), rp),
            (previous, Some(r)) => {
                // Entering: at the box's entry, or bisected between the samples.
                let (a, ra) = match previous {
                    Some((tp, _, None)) => boundary(t, tp, r),
                    _ => (t, r),
                };
                first.get_or_insert(a);
                interval(a, t, value(ra), value(r), ra);
            }
            (Some((tp, Some(rp), Some(fp))), None) => {
                let (b, rb) = boundary(tp, t, rp);
                interval(tp, b, fp, value(rb), rp);
            }
            (Some((tp, Some(rp), None)), None) => {
                // Both outside: where the reference chord between them crosses the element, the
                // ray may clip a corner or edge; its middle decides.
                if let Some(r) = pulled {
                    let (u0, u1) = chord_inside(mesh.shape, rp, r);
                    let um = 0.5 * (u0 + u1);
                    let tm = tp + um * (t - tp);
                    let q0: [f64; 3] = std::array::from_fn(|a| rp[a] + um * (r[a] - rp[a]));
                    if let Some(q) = (u0 < u1).then(|| inside(tm, q0)).flatten() {
                        let ((a, qa), (b, qb)) = (boundary(tm, tp, q), boundary(tm, t, q));
                        first.get_or_insert(a);
                        let fm = value(q);
                        interval(a, tm, value(qa), fm, qa);
                        interval(tm, b, fm, value(qb), q);
                    }
                }
            }
            _ => {}
        }
        previous = Some((t, pulled, here.map(value)));
    }
    first.map(|t| (t, colour, transmittance))
}

/// The part (u0, u1) of the chord from reference point `ra` to `rb` inside the reference
/// cube or tetrahedron (u0 < u1 when it crosses). Twin of `volume_chord` (volume.frag).
pub fn chord_inside(shape: super::Shape, ra: [f64; 3], rb: [f64; 3]) -> (f64, f64) {
    let (mut u0, mut u1) = (0.0f64, 1.0f64);
    let mut clip = |ga: f64, gb: f64| {
        if ga > 0.0 && gb > 0.0 {
            u1 = -1.0;
        } else if ga > 0.0 {
            u0 = u0.max(ga / (ga - gb));
        } else if gb > 0.0 {
            u1 = u1.min(ga / (ga - gb));
        }
    };
    for a in 0..3 {
        clip(-ra[a], -rb[a]);
        if !shape.is_simplex() {
            clip(ra[a] - 1.0, rb[a] - 1.0);
        }
    }
    if shape.is_simplex() {
        clip(ra.iter().sum::<f64>() - 1.0, rb.iter().sum::<f64>() - 1.0);
    }
    (u0, u1)
}

/// How a device picture of a volume agrees with [`volume_reference`] ([`compare_volume`]).
#[derive(Clone, Debug, Default)]
pub struct VolumeAgreement {
    /// Pixels where the reference's ray meets an element.
    pub shown: usize,
    /// The largest difference of a colour channel or of the transmittance over pixels both
    /// drew.
    pub worst: f64,
    /// The mean difference over those pixels and channels.
    pub mean: f64,
    /// Pixels one side drew and the other not, where the other side's contribution exceeds
    /// `tolerance` (a silhouette ray that grazes a box: both see next to nothing otherwise).
    pub missing: usize,
    /// Pixels both drew that differ by more than `tolerance` in some channel: (pixel, what).
    pub mismatched: Vec<(usize, String)>,
}

/// Compares a data picture of a volume (per pixel, row-major: the composited colour over black
/// and the transmittance; NaN where the ray met no element — what `volume.frag` writes into a
/// float target) with the reference of the same view, per channel within `tolerance`.
pub fn compare_volume(pixels: &[f32], reference: &[Option<VolumeSample>], tolerance: f64) -> VolumeAgreement {
    let mut out = VolumeAgreement::default();
    let (mut sum, mut count) = (0.0, 0usize);
    let faint = |s: &VolumeSample| {
        s.colour.iter().all(|c| c.abs() <= tolerance) && 1.0 - s.transmittance <= tolerance
    };
    for (k, want) in reference.iter().enumerate() {
        let Some(p) = pixels.get(4 * k..4 * k + 4) else { break };
        let got = (!p[3].is_nan()).then(|| VolumeSample {
            colour: [p[0], p[1], p[2]].map(f64::from),
            transmittance: f64::from(p[3]),
        });
        out.shown += usize::from(want.is_some());
        match (got, *want) {
            (None, None) => {}
            (Some(g), Some(w)) => {
                let diffs = [
                    (g.colour[0] - w.colour[0]).abs(),
                    (g.colour[1] - w.colour[1]).abs(),
                    (g.colour[2] - w.colour[2]).abs(),
                    (g.transmittance - w.transmittance).abs(),
                ];
                let worst = diffs.iter().fold(0.0f64, |a, &b| a.max(b));
                out.worst = out.worst.max(worst);
                sum += diffs.iter().sum::<f64>();
                count += 4;
                if worst > tolerance {
                    out.mismatched.push((k, format!("device {g:?}, reference {w:?}")));
                }
            }
            (Some(s), None) | (None, Some(s)) => {
                if !faint(&s) {
                    out.missing += 1;
                    out.mismatched.push((k, format!("one side only: {s:?}")));
                }
            }
        }
    }
    out.mean = if count > 0 { sum / count as f64 } else { 0.0 };
    out
}
