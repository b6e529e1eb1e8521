//! The CPU f64 reference of a rendered slice, computed plainly per pixel: for a flat view
//! (height off), the point a pixel centre sees on the plane z = 0 lies in one slice polygon
//! (or on an edge shared by several), and the pixel must show that element's polynomial
//! evaluated there (seed 003 §4.2.3: U, |v| and the exact normal per pixel). Used by the tests
//! and by `galerkin demo`'s own check.

use super::cubic::{evaluate, PointFields};
use super::mesh::SpacetimeMesh;
use super::render::SpacetimeView;
use super::slice::{slice, SlicePolygon};

/// The outcome of comparing a data image `(U, |v|, n_x, n_y)` with the reference.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PixelCheck {
    /// Pixels compared.
    pub checked: usize,
    /// Pixels whose U or |v| is off by more than the tolerance, or not drawn inside the domain.
    pub failures: usize,
    /// The first failure, described.
    pub first_failure: Option<String>,
    /// The largest U error, relative to the largest U of the slice.
    pub worst_u: f64,
    /// The largest |v| error, relative to the largest |v| of the slice.
    pub worst_speed: f64,
    /// The largest error of the normal's x or y component where |v| is at least 1e-3 of its
    /// largest value (where |v| → 0 the normal's direction is undetermined).
    pub worst_normal: f64,
}

impl PixelCheck {
    /// No failures and something checked.
    pub fn passed(&self) -> bool {
        self.failures == 0 && self.checked > 0
    }
}

/// Whether `(x, y)` lies in polygon `p` or within `eps` of it.
fn contains(p: &SlicePolygon, x: f64, y: f64, eps: f64) -> bool {
    let c = &p.corners;
    let s: Vec<f64> = (0..c.len())
        .map(|i| {
            let (a, b) = (c[i], c[(i + 1) % c.len()]);
            let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt().max(1e-300);
            ((b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])) / len
        })
        .collect();
    s.iter().all(|&d| d >= -eps) || s.iter().all(|&d| d <= eps)
}

/// Compares `data` (a `width`×`height` RGBA32F image of `view`, which must be flat, drawn with
/// `height_scale`) with the f64 fields of `mesh` at every `step`-th pixel centre in both
/// directions. U and |v| must match within `tolerance` of their largest values over the slice
/// — f32 evaluation at f32 positions errs by about 1e-6 of a field's scale, so 1e-4 leaves a
/// wide margin — and the normal within 100 × `tolerance` where |v| is not tiny; pixel
/// centres within 1e-4 of the domain's boundary are skipped (rasterisation may go either way
/// there). Where several polygons contain a centre (a shared edge), the best match counts.
pub fn check_flat_pixels(
    mesh: &SpacetimeMesh,
    view: &SpacetimeView,
    height_scale: f64,
    size: (u32, u32),
    data: &[f32],
    step: u32,
    tolerance: f64,
) -> PixelCheck {
    check_flat_pixels_of(mesh, view, height_scale, size, data, (step, tolerance), |f, _, _| {
        f.strain_energy_density
    })
}

/// [`check_flat_pixels`] for a derived field (`--expr`): the first channel must show the
/// expression evaluated in f64 from the element's fields at the pixel's point
/// ([`SpacetimeExpression::value_at`]), within `tolerance` of the slice's largest |value|.
pub fn check_derived_flat_pixels(
    mesh: &SpacetimeMesh,
    expression: &crate::expression::spacetime::SpacetimeExpression,
    view: &SpacetimeView,
    height_scale: f64,
    size: (u32, u32),
    data: &[f32],
    (step, tolerance): (u32, f64),
) -> PixelCheck {
    let t = view.time;
    check_flat_pixels_of(mesh, view, height_scale, size, data, (step, tolerance), |f, x, y| {
        expression.value_at(f, x, y, t)
    })
}

/// The per-pixel comparison of [`check_flat_pixels`] with the first channel's reference
/// `shown(fields, x, y)` (U, or a derived field).
fn check_flat_pixels_of(
    mesh: &SpacetimeMesh,
    view: &SpacetimeView,
    height_scale: f64,
    (width, height): (u32, u32),
    data: &[f32],
    (step, tolerance): (u32, f64),
    shown: impl Fn(&PointFields, f64, f64) -> f64,
) -> PixelCheck {
    assert!(!view.height, "the flat reference needs the height field off");
    let t = view.time;
    let polys = slice(mesh, t);
    let field = |e: u32, x: f64, y: f64| -> PointFields {
        let f = &mesh.fields[e as usize];
        evaluate(&f.frame, &mesh.materials[f.material as usize], &f.coefficients, [x, y, t])
    };
    let (mut max_u, mut max_v) = (0f64, 0f64);
    for p in &polys {
        for q in &p.corners {
            let v = field(p.element, q[0], q[1]);
            max_u = max_u.max(shown(&v, q[0], q[1]).abs());
            max_v = max_v.max(v.speed);
        }
    }
    let (lo, hi) = mesh.space_bounds();
    let margin = 1e-4 * (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let mut check = PixelCheck::default();
    for py in (0..height).step_by(step.max(1) as usize) {
        for px in (0..width).step_by(step.max(1) as usize) {
            let Some(q) = view.camera.pixel_on_plane_z(px, py, width, height, 0.0) else { continue };
            if q.x < lo[0] + margin || q.x > hi[0] - margin || q.y < lo[1] + margin || q.y > hi[1] - margin {
                continue;
            }
            let candidates: Vec<&SlicePolygon> =
                polys.iter().filter(|p| contains(p, q.x, q.y, 1e-5)).collect();
            if candidates.is_empty() {
                continue; // a hole in the data's domain (not a rectangle)
            }
            let got = &data[4 * (py * width + px) as usize..][..4];
            check.checked += 1;
            let mut fail = |what: String| {
                check.failures += 1;
                check
                    .first_failure
                    .get_or_insert(format!("pixel ({px}, {py}) at ({:.6}, {:.6}): {what}", q.x, q.y));
            };
            if !got[0].is_finite() {
                fail("not drawn".into());
                continue;
            }
            let best = candidates
                .iter()
                .map(|p| {
                    let v = field(p.element, q.x, q.y);
                    let n = v.normal(height_scale);
                    let normal = if v.speed >= 1e-3 * max_v {
                        (f64::from(got[2]) - n[0]).abs().max((f64::from(got[3]) - n[1]).abs())
                    } else {
                        0.0
                    };
                    (
                        (f64::from(got[0]) - shown(&v, q.x, q.y)).abs() / max_u.max(f64::MIN_POSITIVE),
                        (f64::from(got[1]) - v.speed).abs() / max_v.max(f64::MIN_POSITIVE),
                        normal,
                    )
                })
                .fold((f64::INFINITY, f64::INFINITY, f64::INFINITY), |a, b| {
                    if b.0 + b.1 < a.0 + a.1 {
                        b
                    } else {
                        a
                    }
                });
            check.worst_u = check.worst_u.max(best.0);
            check.worst_speed = check.worst_speed.max(best.1);
            check.worst_normal = check.worst_normal.max(best.2);
            if best.0 > tolerance || best.1 > tolerance || best.2 > 100.0 * tolerance {
                fail(format!(
                    "U error {:.2e}, |v| error {:.2e} of the largest, normal error {:.2e}",
                    best.0, best.1, best.2
                ));
            }
        }
    }
    check
}
