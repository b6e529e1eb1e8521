//! Exact form factors between planar polygons for the near field (issue 28): where two faces
//! are close — neighbours sharing an edge or a corner, faces a few of their sizes apart — the
//! centroid sampling of Eq. 15 is biased (printed, it diverges as the faces meet; regularised,
//! it is always low). The double area integral
//!
//! ```text
//! Aᵢ F_ij = ∫_{Aᵢ} ∫_{Aⱼ} cos θᵢ cos θⱼ / (π r²) dAⱼ dAᵢ
//! ```
//!
//! becomes by Stokes' theorem twice (Sparrow 1963; Modest, *Radiative Heat Transfer*, §4.4)
//! the double contour integral
//!
//! ```text
//! Aᵢ F_ij = 1/(2π) ∮_{∂Aᵢ} ∮_{∂Aⱼ} ln|p − q| dp · dq
//! ```
//!
//! with both boundaries oriented counter-clockwise about their own normals (`nᵢ` towards
//! `Aⱼ` and `nⱼ` towards `Aᵢ`). For polygons it is a sum over pairs of edges
//! `(tₑ·t_f) ∫ₑ ∫_f ln|p − q| dt ds`; the inner integral over a straight edge is in closed form
//! ([`log_distance_integral`]), the outer is Gauss–Legendre on pieces graded geometrically
//! towards the edge's ends, where the integrand has its `s ln s` behaviour when the edges
//! touch (a shared corner or a shared edge). So faces sharing an edge, where the point formula
//! is worst, are integrated to about 1e-9. The formula holds when each polygon lies in front
//! of the other's plane (or in it): [`exact_form_factor`] checks that and returns `None`
//! otherwise.

use glam::DVec3;

/// Gauss–Legendre points per graded piece of an edge.
const POINTS: usize = 8;
/// Pieces of an edge: its middle and geometric gradings of ratio 1/4 towards each end.
const GRADING: usize = 12;

/// `∫₀ᴸ ln|p − (a + t u)| dt` over the edge from `a` along the unit vector `u`, length `len`,
/// in closed form: with `τ = (p − a)·u` and `h` the distance from `p` to the edge's line,
/// `½ ∫ ln(x² + h²) dx = ½ [x ln(x² + h²) − 2x + 2h atan(x/h)]` from `x = −τ` to `len − τ`
/// (the `h → 0` limit, `x ln|x| − x`, included).
pub fn log_distance_integral(p: DVec3, a: DVec3, u: DVec3, len: f64) -> f64 {
    let d = p - a;
    let tau = d.dot(u);
    // The perpendicular part's length, not sqrt(|d|² − τ²): that cancels to ~1e-8 of |d| for
    // points on the line, and 2h·atan(x/h) would keep the error.
    let h = (d - u * tau).length();
    let antiderivative = |x: f64| {
        let log_term = if x == 0.0 { 0.0 } else { x * (x * x + h * h).ln() };
        0.5 * (log_term - 2.0 * x + 2.0 * h * x.atan2(h))
    };
    antiderivative(len - tau) - antiderivative(-tau)
}

/// The pieces `[t₀, t₁]` of `[0, 1]` the outer integral is split into: geometrically graded
/// (ratio ¼, [`GRADING`] levels) towards each end that touches or nearly touches the other
/// edge — so that an `s ln s` end behaves like a smooth function on every piece — and two
/// plain halves where the integrand is smooth. The four variants are built once.
fn graded_pieces(graded_start: bool, graded_end: bool) -> &'static [(f64, f64)] {
    static PIECES: std::sync::OnceLock<[Vec<(f64, f64)>; 4]> = std::sync::OnceLock::new();
    let all = PIECES.get_or_init(|| {
        let levels: Vec<f64> = (1..=GRADING).map(|k| 0.5 * 0.25f64.powi(k as i32)).collect();
        let build = |start: bool, end: bool| {
            let mut cuts = vec![0.0];
            if start {
                cuts.extend(levels.iter().rev());
            }
            cuts.push(0.5);
            if end {
                cuts.extend(levels.iter().map(|t| 1.0 - t));
            }
            cuts.push(1.0);
            cuts.windows(2).map(|w| (w[0], w[1])).collect()
        };
        [build(false, false), build(true, false), build(false, true), build(true, true)]
    });
    &all[usize::from(graded_start) + 2 * usize::from(graded_end)]
}

/// The distance from `p` to the segment `[c, d]`.
fn distance_to_segment(p: DVec3, c: DVec3, d: DVec3) -> f64 {
    let cd = d - c;
    let t = ((p - c).dot(cd) / cd.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (p - (c + cd * t)).length()
}

/// The Gauss–Legendre rule of [`POINTS`] points on `[0, 1]`: nodes and weights, computed once.
fn gauss_rule() -> &'static (Vec<f64>, Vec<f64>) {
    static RULE: std::sync::OnceLock<(Vec<f64>, Vec<f64>)> = std::sync::OnceLock::new();
    RULE.get_or_init(|| crate::spectral::basis::gauss_rule(POINTS))
}

/// `∫ₑ ∫_f ln|p − q| dq ds` over the straight edges `e = [a, b]` and `f = [c, d]` (arc
/// lengths; not yet multiplied by `tₑ·t_f`). An end of `e` within half its length of `f` gets
/// the graded pieces.
fn edge_pair_integral(a: DVec3, b: DVec3, c: DVec3, d: DVec3, rule: &(Vec<f64>, Vec<f64>)) -> f64 {
    let (le, lf) = ((b - a).length(), (d - c).length());
    if le == 0.0 || lf == 0.0 {
        return 0.0;
    }
    let uf = (d - c) / lf;
    let near = |p: DVec3| distance_to_segment(p, c, d) < 0.5 * le;
    let mut sum = 0.0;
    for &(t0, t1) in graded_pieces(near(a), near(b)) {
        let w = t1 - t0;
        for (x, wx) in rule.0.iter().zip(&rule.1) {
            let t = t0 + w * x;
            sum += wx * w * log_distance_integral(a + (b - a) * t, c, uf, lf);
        }
    }
    sum * le
}

/// Whether every corner of `poly` lies in front of (or on) the plane through `origin` with
/// normal `normal`, to a tolerance relative to the polygon's size.
fn in_front(poly: &[DVec3], origin: DVec3, normal: DVec3) -> bool {
    let n = normal.normalize_or_zero();
    let size = poly.windows(2).map(|w| (w[1] - w[0]).length()).fold(0.0, f64::max);
    poly.iter().all(|p| (*p - origin).dot(n) >= -1e-9 * size.max(1e-300))
}

/// The unnormalised normal of a planar polygon (`|n| = 2A`), by Newell's method.
fn polygon_normal(poly: &[DVec3]) -> DVec3 {
    let k = poly.len();
    (0..k).map(|i| poly[i].cross(poly[(i + 1) % k])).sum()
}

/// `F_ij`, the exact form factor from polygon `i` to polygon `j` (corners counter-clockwise
/// about each one's normal, planar, without occlusion between them), or `None` where the
/// contour form does not hold: a polygon partly behind the other's plane, or a degenerate one.
pub fn exact_form_factor(pi: &[DVec3], pj: &[DVec3]) -> Option<f64> {
    let (ni, nj) = (polygon_normal(pi), polygon_normal(pj));
    let area_i = 0.5 * ni.length();
    if area_i.is_nan() || area_i <= 0.0 || nj.length() == 0.0 || pi.len() < 3 || pj.len() < 3 {
        return None;
    }
    if !in_front(pj, pi[0], ni) || !in_front(pi, pj[0], nj) {
        return None;
    }
    let rule = gauss_rule();
    let mut sum = 0.0;
    for e in 0..pi.len() {
        let (a, b) = (pi[e], pi[(e + 1) % pi.len()]);
        let te = (b - a).normalize_or_zero();
        for f in 0..pj.len() {
            let (c, d) = (pj[f], pj[(f + 1) % pj.len()]);
            let tf = (d - c).normalize_or_zero();
            let dot = te.dot(tf);
            if dot.abs() < 1e-15 {
                continue;
            }
            sum += dot * edge_pair_integral(a, b, c, d, rule);
        }
    }
    Some((sum / (2.0 * std::f64::consts::PI * area_i)).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed-form inner integral: against midpoint quadrature for a point off the line,
    /// and against `∫ ln|t − τ| dt` for points on the line, beyond the edge and on it.
    #[test]
    fn the_inner_integral_matches_quadrature_and_the_one_dimensional_form() {
        let (a, u, len) = (DVec3::new(0.2, -0.1, 0.3), DVec3::new(1.0, 2.0, 2.0) / 3.0, 1.7);
        let p = DVec3::new(1.0, 0.5, -0.4);
        let n = 200_000;
        let brute: f64 =
            (0..n).map(|k| (p - (a + u * (len * (k as f64 + 0.5) / n as f64))).length().ln()).sum::<f64>()
                * len
                / n as f64;
        let exact = log_distance_integral(p, a, u, len);
        assert!((exact - brute).abs() < 1e-9, "off the line: {exact} against {brute}");
        // ∫₀ᴸ ln|t − τ| dt = x ln|x| − x from x = −τ to L − τ.
        let f = |x: f64| if x == 0.0 { 0.0 } else { x * x.abs().ln() - x };
        for tau in [2.5, 0.6, 0.0, -0.3] {
            let one_d = f(len - tau) - f(-tau);
            let exact = log_distance_integral(a + u * tau, a, u, len);
            assert!((exact - one_d).abs() < 1e-12, "τ {tau}: {exact} against {one_d}");
        }
    }

    fn square(o: DVec3, u: DVec3, v: DVec3) -> Vec<DVec3> {
        vec![o, o + u, o + u + v, o + v]
    }

    /// Hottel's parallel unit squares one apart and perpendicular unit squares sharing an
    /// edge (Howell's catalogue, C-11 and C-14), as single polygons: the contour integral is
    /// exact, so only quadrature and rounding error remain (tolerance 1e-8).
    #[test]
    fn unit_squares_match_their_closed_forms() {
        use std::f64::consts::PI;
        let parallel_closed = {
            let s = 2.0f64.sqrt();
            2.0 / PI * ((4.0f64 / 3.0).sqrt().ln() + 2.0 * s * (1.0 / s).atan() - 2.0 * 1.0f64.atan())
        };
        let perpendicular_closed = {
            let s = 2.0f64.sqrt();
            (PI / 2.0 - s * (1.0 / s).atan() + 0.25 * (4.0f64 / 3.0 * 0.75 * 0.75).ln()) / PI
        };
        assert!((parallel_closed - 0.19982).abs() < 1e-5 && (perpendicular_closed - 0.20004).abs() < 1e-5);
        let floor = square(DVec3::ZERO, DVec3::X, DVec3::Y);
        let ceiling = square(DVec3::Z, DVec3::Y, DVec3::X);
        let wall = square(DVec3::ZERO, DVec3::Z, DVec3::X);
        let parallel = exact_form_factor(&floor, &ceiling).expect("facing");
        let perpendicular = exact_form_factor(&floor, &wall).expect("facing");
        assert!((parallel - parallel_closed).abs() < 1e-8, "parallel {parallel} against {parallel_closed}");
        assert!(
            (perpendicular - perpendicular_closed).abs() < 1e-8,
            "perpendicular {perpendicular} against {perpendicular_closed}"
        );
        // A square behind the other's plane is refused, not integrated wrongly.
        let below = square(-DVec3::Z, DVec3::X, DVec3::Y);
        assert!(exact_form_factor(&floor, &below).is_none());
    }
}

/// How far the exact near field reaches by default: pairs whose centroids are closer than
/// this many times the larger face's diameter (the root of its summed squared edge lengths).
/// Beyond it the centroid formula's relative error is below about 1 % and falls as the
/// distance squared.
pub const DEFAULT_REACH: f64 = 4.0;

/// Whether faces `i` and `j` are near: centroids closer than `reach` times the larger face's
/// diameter (the root of its summed squared edge lengths).
pub fn is_near(g: &super::FaceGeometry, i: usize, j: usize, reach: f64) -> bool {
    let diameter = g.edge_squares[i].max(g.edge_squares[j]).sqrt();
    (g.centroids[j] - g.centroids[i]).length() < reach * diameter
}

/// How the full solve's form factors treat near pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum FormFactorMethod {
    /// Centroid sampling under a [`NearField`] treatment for every pair (Eq. 15, what the
    /// reduced model's Table 2 chain computes).
    #[default]
    Centroid,
    /// The exact polygon form factor ([`exact_form_factor`]) for visible pairs within `reach`
    /// face diameters of each other, Eq. 15 as printed beyond (the accurate ground truth).
    ExactNear {
        /// Reach in face diameters ([`DEFAULT_REACH`]).
        reach: f64,
    },
}

/// Every `F_ij` with visibility, the pairs within `reach` face diameters by the exact polygon
/// form factor (`F_ji` from reciprocity, so `Aᵢ F_ij = Aⱼ F_ji` exactly) and the rest by
/// Eq. 15 as printed; a near pair the contour form cannot take (one face partly behind the
/// other's plane) keeps the regularised centroid value. Returns the form factors and the
/// number of pairs integrated exactly.
pub fn form_factors_exact_near(
    mesh: &super::SceneMesh,
    reach: f64,
) -> (super::form_factor::FormFactors, usize) {
    use super::form_factor::{unoccluded_form_factor, visible_pairs, FormFactors, NearField};
    use rayon::prelude::*;
    let n = mesh.len();
    let g = mesh.geometry();
    let vis = visible_pairs(mesh, &g);
    let rows: Vec<Vec<(usize, f64, f64, bool)>> = vis
        .par_iter()
        .enumerate()
        .map(|(i, row)| {
            row.iter()
                .map(|&j| {
                    let j = j as usize;
                    let near = is_near(&g, i, j, reach);
                    let exact =
                        if near { exact_form_factor(&mesh.corners(i), &mesh.corners(j)) } else { None };
                    match exact {
                        Some(fij) => (j, fij, fij * g.areas[i] / g.areas[j], true),
                        None => {
                            let treatment = if near { NearField::Regularised } else { NearField::Eq15 };
                            (
                                j,
                                unoccluded_form_factor(&g, i, j, treatment),
                                unoccluded_form_factor(&g, j, i, treatment),
                                false,
                            )
                        }
                    }
                })
                .collect()
        })
        .collect();
    let mut values = vec![0.0; n * n];
    let mut exact = 0;
    for (i, row) in rows.iter().enumerate() {
        for &(j, fij, fji, was_exact) in row {
            values[i * n + j] = fij;
            values[j * n + i] = fji;
            exact += usize::from(was_exact);
        }
    }
    (FormFactors { n, values }, exact)
}
