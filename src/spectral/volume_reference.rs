//! The f64 reference of volume rendering (`volume.frag`), computed plainly: for every pixel
//! the ray from the eye through the pixel centre ([`Camera::pixel_ray`]); for every element
//! whose box it crosses, `samples_per_order` × (n + 1) uniform samples along the crossing, each
//! pulled back by Newton's method in f64, the element's entry and exit bisected to 10⁻¹⁴ of the
//! crossing where the samples go in or out; each inside interval split where the field (linear
//! between its ends) crosses an opacity point and integrated by the midpoint rule in
//! [`REFERENCE_SUBSTEPS`] sub-steps with the field exact at each midpoint and the exponential
//! exact. Sheets (isosurfaces in the volume pass, [`Sheets`]): each value the field crosses
//! within an inside interval is bisected to its root, and the sheet, lit with the exact normal,
//! composited there with its opacity. The elements' parts are composited in order of entry. The quadrature converges at
//! second order: the tests check that doubling `samples_per_order` changes no channel by more
//! than a small fraction of 1/255.

use rayon::prelude::*;

use super::iso_reference::{
    parabola_pair, physical_gradient, pull_back, reference_boxes, reference_centre, slab,
};
use super::mesh::SpectralMesh;
use super::transfer::{Sheets, TransferFunction};
use crate::render::{phong, ramp_coordinate, Camera, Colormap};

/// Midpoint sub-steps per piece (the device takes 2).
pub const REFERENCE_SUBSTEPS: usize = 8;

/// What the volume of one pixel's ray composites to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeSample {
    /// Emitted colour reaching the eye (over black).
    pub colour: [f64; 3],
    /// Light let through, T = e^{−∫σ} (times 1 − α per sheet crossed).
    pub transmittance: f64,
    /// The ray grazes a sheet, where the device's coarser sampling may see a different number
    /// of crossings: within one element two roots of one sheet value lie closer than two of the
    /// device's sample intervals ([`device_samples`]), or three consecutive samples' f − c keep
    /// their sign while the parabola through them turns toward zero and comes within a quarter
    /// of the smallest (the isosurface pass's pair test). Never set without sheets.
    pub grazing: bool,
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
/// samples per element crossing, with `sheets` composited where the ray crosses their values.
#[allow(clippy::too_many_arguments)]
pub fn volume_reference(
    mesh: &SpectralMesh,
    (field, step): (usize, usize),
    camera: &Camera,
    tf: &TransferFunction,
    sheets: &Sheets,
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
            let mut parts: Vec<(f64, Composite)> = Vec::new();
            for (e, (lo, hi)) in boxes.iter().enumerate() {
                let Some((t0, t1)) = slab(eye, d, *lo, *hi) else { continue };
                let caster = Caster { mesh, field, step, e, eye, d, t0, t1, tf, sheets, colours };
                if let Some(part) = caster.element_part(samples_per_order) {
                    parts.push(part);
                }
            }
            if parts.is_empty() {
                return None;
            }
            parts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (mut colour, mut transmittance, mut grazing) = ([0.0; 3], 1.0, false);
            for (_, part) in parts {
                for (c, p) in colour.iter_mut().zip(part.colour) {
                    *c += transmittance * p;
                }
                transmittance *= part.transmittance;
                grazing |= part.grazing;
            }
            Some(VolumeSample { colour, transmittance, grazing })
        })
        .collect()
}

/// Samples the device takes along an element's box crossing (`SPECTRAL_VOLUME_SAMPLES`,
/// volume.frag): 8 + 4 n, n the higher of the field's and the geometry's orders.
pub fn device_samples(mesh: &SpectralMesh) -> usize {
    8 + 4 * mesh.basis.order.max(mesh.geometry.order)
}

/// The colour and light let through of one element's part of a ray, composited from T = 1.
struct Composite {
    colour: [f64; 3],
    transmittance: f64,
    /// A sheet met twice within two of the device's sample intervals, or approached without
    /// crossing (see [`VolumeSample::grazing`]).
    grazing: bool,
}

impl Composite {
    /// Composites a layer of opacity `alpha` and colour `c` behind what is there.
    fn layer(&mut self, alpha: f64, c: [f64; 3]) {
        for (out, c) in self.colour.iter_mut().zip(c) {
            *out += self.transmittance * alpha * c;
        }
        self.transmittance *= 1.0 - alpha;
    }
}

/// One ray through one element's box ([t0, t1]) and what it composites.
struct Caster<'a> {
    mesh: &'a SpectralMesh,
    field: usize,
    step: usize,
    e: usize,
    eye: [f64; 3],
    d: [f64; 3],
    t0: f64,
    t1: f64,
    tf: &'a TransferFunction,
    sheets: &'a Sheets,
    colours: &'a VolumeColours<'a>,
}

impl Caster<'_> {
    fn at(&self, t: f64) -> [f64; 3] {
        std::array::from_fn(|a| self.eye[a] + t * self.d[a])
    }

    /// The reference point of t, if Newton converges.
    fn pull(&self, t: f64, guess: [f64; 3]) -> Option<[f64; 3]> {
        pull_back(self.mesh, self.e, self.at(t), guess)
    }

    /// The reference point of t, if inside the element.
    fn inside(&self, t: f64, guess: [f64; 3]) -> Option<[f64; 3]> {
        self.pull(t, guess).filter(|r| self.mesh.shape.outside(r) <= super::render::INSIDE_TOLERANCE)
    }

    fn value(&self, r: [f64; 3]) -> f64 {
        self.mesh.value_hex(self.field, self.step, self.e, self.mesh.shape.clamp(r))
    }

    /// The boundary between t_in (inside at r_in) and t_out, bisected: (t, r) at the inside end.
    fn boundary(&self, mut t_in: f64, mut t_out: f64, mut r_in: [f64; 3]) -> (f64, [f64; 3]) {
        for _ in 0..60 {
            if (t_in - t_out).abs() <= 1e-14 * (self.t1 - self.t0) {
                break;
            }
            let t = 0.5 * (t_in + t_out);
            match self.inside(t, r_in) {
                Some(r) => {
                    t_in = t;
                    r_in = r;
                }
                None => t_out = t,
            }
        }
        (t_in, r_in)
    }

    /// Composites [a, b] by the midpoint rule, the field exact at each midpoint.
    fn piece(&self, out: &mut Composite, a: f64, b: f64, r: &mut [f64; 3]) {
        let h = (b - a) / REFERENCE_SUBSTEPS as f64;
        for k in 0..REFERENCE_SUBSTEPS {
            let t = a + (k as f64 + 0.5) * h;
            if let Some(q) = self.mesh.inverse_map_hex(self.e, self.at(t), *r) {
                *r = q;
            }
            let f = self.value(*r);
            let absorbed = 1.0 - (-self.tf.sigma(f) * h).exp();
            out.layer(absorbed, self.colours.colour(f));
        }
    }

    /// [a, b] with the field fa at a and fb at b, split where it crosses an opacity point.
    fn interval(&self, out: &mut Composite, a: f64, b: f64, fa: f64, fb: f64, mut r: [f64; 3]) {
        if b.partial_cmp(&a) != Some(std::cmp::Ordering::Greater) || self.tf.is_clear() {
            return;
        }
        let mut cuts: Vec<f64> = (self.tf.opacity.iter())
            .filter(|p| (p.0 - fa) * (p.0 - fb) < 0.0)
            .map(|p| a + (b - a) * (p.0 - fa) / (fb - fa))
            .collect();
        cuts.sort_by(f64::total_cmp);
        let mut lo = a;
        for t in cuts {
            self.piece(out, lo, t, &mut r);
            lo = t;
        }
        self.piece(out, lo, b, &mut r);
    }

    /// The lit colour of the sheet of value `c` at reference point `r`: the colour map at c,
    /// Phong-lit with the exact normal J⁻ᵀ∇_r f/|·|, the light from −d + (0.2, 0.3, 0.5).
    /// Twin of `volume_sheet_colour` (volume.frag).
    fn sheet_colour(&self, r: [f64; 3], c: f64) -> [f64; 3] {
        let r = self.mesh.shape.clamp(r);
        let d = glam::DVec3::from(self.d);
        let mut n = physical_gradient(self.mesh, (self.field, self.step), self.e, r).normalize_or_zero();
        if n == glam::DVec3::ZERO {
            n = -d;
        }
        let light = (-d + glam::DVec3::new(0.2, 0.3, 0.5)).normalize();
        phong(self.colours.colour(c), n.to_array(), light.to_array(), (-d).to_array())
    }

    /// [a, b] (inside, the field fa at a and fb at b, ra the reference point of a) with its
    /// sheets: each value the field crosses between the ends bisected to 10⁻¹⁴ of the crossing,
    /// in ray order, the volume between them and each sheet composited at its root. `last`
    /// holds each sheet value's previous root in this element (for [`Composite::grazing`]).
    #[allow(clippy::too_many_arguments)]
    fn span(&self, out: &mut Composite, a: f64, b: f64, fa: f64, fb: f64, ra: [f64; 3], last: &mut [f64]) {
        let mut roots: Vec<(f64, usize, [f64; 3])> = Vec::new();
        for (k, &c) in self.sheets.values.iter().enumerate() {
            if (fa - c) * (fb - c) >= 0.0 {
                continue;
            }
            let (mut lo, mut hi, mut r) = (a, b, ra);
            for _ in 0..80 {
                if hi - lo <= 1e-14 * (self.t1 - self.t0) {
                    break;
                }
                let t = 0.5 * (lo + hi);
                if let Some(q) = self.pull(t, r) {
                    r = q;
                }
                if (self.value(r) - c < 0.0) == (fa - c < 0.0) {
                    lo = t;
                } else {
                    hi = t;
                }
            }
            let t = 0.5 * (lo + hi);
            roots.push((t, k, self.pull(t, r).unwrap_or(r)));
        }
        roots.sort_by(|x, y| x.0.total_cmp(&y.0));
        let interval_t = (self.t1 - self.t0) / device_samples(self.mesh) as f64;
        let (mut lo, mut f_lo, mut r_lo) = (a, fa, ra);
        for (t, k, r) in roots {
            let c = self.sheets.values[k];
            self.interval(out, lo, t, f_lo, c, r_lo);
            out.layer(self.sheets.opacity, self.sheet_colour(r, c));
            if t - last[k] < 2.0 * interval_t {
                out.grazing = true;
            }
            last[k] = t;
            (lo, f_lo, r_lo) = (t, c, r);
        }
        self.interval(out, lo, b, f_lo, fb, r_lo);
    }

    /// Three consecutive inside samples' fields `f` (equally spaced): whether some sheet's
    /// f − c keeps its sign over them while the parabola through them turns toward zero between
    /// the outer two and comes within a quarter of the smallest (the isosurface pass's test for
    /// a pair of roots between samples): a ray that grazes the sheet.
    fn approaches(&self, f: [f64; 3]) -> bool {
        self.sheets.values.iter().any(|&c| parabola_pair(f.map(|v| v - c)).is_some())
    }

    /// The element's part of the ray: where the ray first enters it, and what it composites;
    /// `None` when no sample lies inside.
    fn element_part(&self, samples_per_order: usize) -> Option<(f64, Composite)> {
        let mut out = Composite { colour: [0.0; 3], transmittance: 1.0, grazing: false };
        let mut last = vec![f64::NEG_INFINITY; self.sheets.values.len()];
        let samples = samples_per_order * (self.mesh.basis.order.max(self.mesh.geometry.order) + 1);
        let mut first: Option<f64> = None;
        // The fields at the last inside samples in a row (for the grazing test).
        let mut run: Vec<f64> = Vec::new();
        // The previous sample: (t, its reference point if Newton converged, the field there if
        // inside).
        let mut previous: Option<(f64, Option<[f64; 3]>, Option<f64>)> = None;
        let mut guess = reference_centre(self.mesh.shape);
        for s in 0..=samples {
            let t = self.t0 + (self.t1 - self.t0) * s as f64 / samples as f64;
            let pulled = self.pull(t, guess);
            let here = pulled.filter(|r| self.mesh.shape.outside(r) <= super::render::INSIDE_TOLERANCE);
            if let Some(r) = pulled {
                guess = r;
            }
            match here {
                Some(r) => {
                    run.push(self.value(r));
                    let n = run.len();
                    if n >= 3 && self.approaches([run[n - 3], run[n - 2], run[n - 1]]) {
                        out.grazing = true;
                    }
                }
                None => run.clear(),
            }
            match (previous, here) {
                (Some((tp, Some(rp), Some(fp))), Some(r)) => {
                    self.span(&mut out, tp, t, fp, self.value(r), rp, &mut last)
                }
                (previous, Some(r)) => {
                    // Entering: at the box's entry, or bisected between the samples.
                    let (a, ra) = match previous {
                        Some((tp, _, None)) => self.boundary(t, tp, r),
                        _ => (t, r),
                    };
                    first.get_or_insert(a);
                    self.span(&mut out, a, t, self.value(ra), self.value(r), ra, &mut last);
                }
                (Some((tp, Some(rp), Some(fp))), None) => {
                    let (b, rb) = self.boundary(tp, t, rp);
                    self.span(&mut out, tp, b, fp, self.value(rb), rp, &mut last);
                }
                (Some((tp, Some(rp), None)), None) => {
                    // Both outside: where the reference chord between them crosses the element,
                    // the ray may clip a corner or edge; its middle decides.
                    if let Some(r) = pulled {
                        let (u0, u1) = chord_inside(self.mesh.shape, rp, r);
                        let um = 0.5 * (u0 + u1);
                        let tm = tp + um * (t - tp);
                        let q0: [f64; 3] = std::array::from_fn(|a| rp[a] + um * (r[a] - rp[a]));
                        if let Some(q) = (u0 < u1).then(|| self.inside(tm, q0)).flatten() {
                            let ((a, qa), (b, qb)) = (self.boundary(tm, tp, q), self.boundary(tm, t, q));
                            first.get_or_insert(a);
                            let fm = self.value(q);
                            self.span(&mut out, a, tm, self.value(qa), fm, qa, &mut last);
                            self.span(&mut out, tm, b, fm, self.value(qb), q, &mut last);
                        }
                    }
                }
                _ => {}
            }
            previous = Some((t, pulled, here.map(|r| self.value(r))));
        }
        first.map(|t| (t, out))
    }
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
    /// drew (grazing ones left out).
    pub worst: f64,
    /// The mean difference over those pixels and channels.
    pub mean: f64,
    /// Pixels one side drew and the other not, where the other side's contribution exceeds
    /// `tolerance` (a silhouette ray that grazes a box: both see next to nothing otherwise).
    pub missing: usize,
    /// Pixels both drew that differ by more than `tolerance` in some channel: (pixel, what).
    pub mismatched: Vec<(usize, String)>,
    /// Pixels whose reference ray grazes a sheet ([`VolumeSample::grazing`]): compared like
    /// the others, but a difference beyond `tolerance` there is counted in
    /// `grazing_mismatched`, not `mismatched`.
    pub grazing: usize,
    /// Grazing pixels beyond `tolerance`.
    pub grazing_mismatched: usize,
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
            grazing: false,
        });
        out.shown += usize::from(want.is_some());
        let grazing = want.is_some_and(|w| w.grazing);
        out.grazing += usize::from(grazing);
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
                if grazing {
                    out.grazing_mismatched += usize::from(worst > tolerance);
                    continue;
                }
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
