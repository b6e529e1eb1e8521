//! The element field of seed 003 §4.2.1: a 2-vector displacement as a complete cubic in the
//! element's local spacetime coordinates, and the fields derived from it exactly — velocity
//! `v = ∂u/∂t` and its magnitude (the height), strain `ε = ½(∇u + ∇uᵀ)`, strain energy density
//! `U = ½ ε : C ε` (isotropic, plane strain), and the exact normal of the height field.
//!
//! This is the CPU f64 reference; `shaders-glsl/include/spacetime_cubic.glsl` is its GLSL twin
//! (same monomial order, same formulas) and `tests/spacetime_fields.rs` checks they agree.

use serde::{Deserialize, Serialize};

/// Exponents `(x, y, t)` of the 20 cubic monomials in the seed's order:
/// 1, x, y, t, x², xy, xt, y², yt, t², x³, x²y, x²t, xy², xyt, xt², y³, y²t, yt², t³.
pub const MONOMIALS: [[u32; 3]; 20] = [
    [0, 0, 0],
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
    [2, 0, 0],
    [1, 1, 0],
    [1, 0, 1],
    [0, 2, 0],
    [0, 1, 1],
    [0, 0, 2],
    [3, 0, 0],
    [2, 1, 0],
    [2, 0, 1],
    [1, 2, 0],
    [1, 1, 1],
    [1, 0, 2],
    [0, 3, 0],
    [0, 2, 1],
    [0, 1, 2],
    [0, 0, 3],
];

/// An element's local frame (seed 003 §4.2.1): `p = diag(1/w) (p̂ − c)`, with `c` the centre
/// and `w` the extents along x, y and t.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LocalFrame {
    /// Centre `c` (x, y, t) in global coordinates.
    pub centre: [f64; 3],
    /// Extents `w_x, w_y, w_t` (positive).
    pub extent: [f64; 3],
}

impl LocalFrame {
    /// The frame of a set of points: the centre and extents of their bounding box.
    pub fn bounding(points: &[[f64; 3]]) -> Self {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        Self {
            centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])],
            extent: [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]],
        }
    }

    /// Local coordinates of a global point.
    pub fn local(&self, p: [f64; 3]) -> [f64; 3] {
        [
            (p[0] - self.centre[0]) / self.extent[0],
            (p[1] - self.centre[1]) / self.extent[1],
            (p[2] - self.centre[2]) / self.extent[2],
        ]
    }
}

/// An isotropic linear elastic material: Lamé parameters λ and μ.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// First Lamé parameter λ.
    pub lambda: f64,
    /// Shear modulus μ.
    pub mu: f64,
    /// Density ρ (sets the wave speeds `c_p = √((λ + 2μ)/ρ)`, `c_s = √(μ/ρ)`).
    pub density: f64,
}

impl Material {
    /// What makes this material unusable, if anything: the strain energy of plane strain is
    /// positive definite and the wave speeds real only for μ > 0, λ + μ > 0 and ρ > 0 (and
    /// each finite).
    pub fn problem(&self) -> Option<String> {
        let finite = [self.lambda, self.mu, self.density].iter().all(|v| v.is_finite());
        (!(finite && self.mu > 0.0 && self.lambda + self.mu > 0.0 && self.density > 0.0))
            .then(|| format!("needs μ > 0, λ + μ > 0 and ρ > 0, each finite (got {self:?})"))
    }

    /// Pressure-wave speed `√((λ + 2μ)/ρ)`.
    pub fn p_wave_speed(&self) -> f64 {
        ((self.lambda + 2.0 * self.mu) / self.density).sqrt()
    }

    /// Shear-wave speed `√(μ/ρ)`.
    pub fn s_wave_speed(&self) -> f64 {
        (self.mu / self.density).sqrt()
    }

    /// Strain energy density `U = ½ ε : C ε` of plane strain, `ε = (ε_xx, ε_yy, ε_xy)`:
    /// `½ (λ (ε_xx + ε_yy)² + 2μ (ε_xx² + ε_yy² + 2 ε_xy²))`.
    pub fn strain_energy_density(&self, strain: [f64; 3]) -> f64 {
        let [exx, eyy, exy] = strain;
        let tr = exx + eyy;
        0.5 * (self.lambda * tr * tr + 2.0 * self.mu * (exx * exx + eyy * eyy + 2.0 * exy * exy))
    }
}

/// The 2-vector coefficients `c_α` of the displacement `u = Σ c_α m^α(p)` (local `p`).
pub type CubicCoefficients = [[f64; 2]; 20];

/// Everything the renderer shows at one spacetime point, in global units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointFields {
    /// Displacement u.
    pub displacement: [f64; 2],
    /// Velocity v = ∂u/∂t.
    pub velocity: [f64; 2],
    /// |v|: the height of the height field (before the height scale).
    pub speed: f64,
    /// ∂|v|/∂x, ∂|v|/∂y (zero where |v| = 0).
    pub speed_gradient: [f64; 2],
    /// Strain (ε_xx, ε_yy, ε_xy).
    pub strain: [f64; 3],
    /// Strain energy density U.
    pub strain_energy_density: f64,
}

impl PointFields {
    /// Unit normal of the height field `z = height_scale · |v|` (seed 003 §4.2.3): from the
    /// exact spatial derivatives, `(0, 0, 1)` where |v| = 0.
    pub fn normal(&self, height_scale: f64) -> [f64; 3] {
        let (gx, gy) = (height_scale * self.speed_gradient[0], height_scale * self.speed_gradient[1]);
        let len = (gx * gx + gy * gy + 1.0).sqrt();
        [-gx / len, -gy / len, 1.0 / len]
    }
}

/// Evaluates the element field at the global point `(x, y, t)` (seed 003 §4.2.1–4.2.3).
pub fn evaluate(frame: &LocalFrame, material: &Material, c: &CubicCoefficients, p: [f64; 3]) -> PointFields {
    let q = frame.local(p);
    let [wx, wy, wt] = frame.extent;
    // Powers 0..3 of each local coordinate; a negative exponent (a derivative of a constant)
    // contributes 0.
    let pw = |v: f64| [1.0, v, v * v, v * v * v];
    let (px, py, pt) = (pw(q[0]), pw(q[1]), pw(q[2]));
    let at = |p: &[f64; 4], e: i32| if e < 0 { 0.0 } else { p[e as usize] };
    let mut u = [0.0; 2];
    let mut du = [[0.0; 2]; 3]; // ∂/∂x, ∂/∂y, ∂/∂t (local)
    let mut dtd = [[0.0; 2]; 2]; // ∂²/∂t∂x, ∂²/∂t∂y (local)
    for (alpha, e) in MONOMIALS.iter().enumerate() {
        let (a, b, d) = (e[0] as i32, e[1] as i32, e[2] as i32);
        let (fa, fb, fd) = (f64::from(a), f64::from(b), f64::from(d));
        let m = at(&px, a) * at(&py, b) * at(&pt, d);
        let mx = fa * at(&px, a - 1) * at(&py, b) * at(&pt, d);
        let my = fb * at(&px, a) * at(&py, b - 1) * at(&pt, d);
        let mt = fd * at(&px, a) * at(&py, b) * at(&pt, d - 1);
        let mtx = fa * fd * at(&px, a - 1) * at(&py, b) * at(&pt, d - 1);
        let mty = fb * fd * at(&px, a) * at(&py, b - 1) * at(&pt, d - 1);
        for i in 0..2 {
            let ci = c[alpha][i];
            u[i] += ci * m;
            du[0][i] += ci * mx;
            du[1][i] += ci * my;
            du[2][i] += ci * mt;
            dtd[0][i] += ci * mtx;
            dtd[1][i] += ci * mty;
        }
    }
    // Derivatives in global units: ∂/∂x = (1/w_x) ∂/∂x̂, v = (1/w_t) ∂u/∂t̂.
    fields_from_derivatives(
        material,
        u,
        [du[0][0] / wx, du[0][1] / wx],
        [du[1][0] / wy, du[1][1] / wy],
        [du[2][0] / wt, du[2][1] / wt],
        [dtd[0][0] / (wt * wx), dtd[0][1] / (wt * wx)],
        [dtd[1][0] / (wt * wy), dtd[1][1] / (wt * wy)],
    )
}

/// The derived fields of seed 003 §4.2.3 from the displacement `u`, its spatial derivatives
/// `gx = ∂u/∂x`, `gy = ∂u/∂y`, the velocity `v` and its derivatives `dvx`, `dvy` (global
/// units): strain, |v| and its gradient (zero where |v| = 0), U. Shared by [`evaluate`] and
/// [`SliceCubic::evaluate`]; `spacetime_fields` in GLSL is its twin.
pub fn fields_from_derivatives(
    material: &Material,
    u: [f64; 2],
    gx: [f64; 2],
    gy: [f64; 2],
    v: [f64; 2],
    dvx: [f64; 2],
    dvy: [f64; 2],
) -> PointFields {
    let strain = [gx[0], gy[1], 0.5 * (gy[0] + gx[1])];
    let speed = v[0].hypot(v[1]);
    let speed_gradient = if speed > 0.0 {
        [(v[0] * dvx[0] + v[1] * dvx[1]) / speed, (v[0] * dvy[0] + v[1] * dvy[1]) / speed]
    } else {
        [0.0, 0.0]
    };
    PointFields {
        displacement: u,
        velocity: v,
        speed,
        speed_gradient,
        strain,
        strain_energy_density: material.strain_energy_density(strain),
    }
}

/// Position of the 2D monomial `x^a y^b` (`a + b ≤ 3`) in the order 1, x, y, x², xy, y², x³,
/// x²y, xy², y³ (the seed's order with t dropped).
pub fn slice_monomial_index(a: usize, b: usize) -> usize {
    let n = a + b;
    n * (n + 1) / 2 + b
}

/// An element's cubic restricted to one time plane (seed 003 §4.2.3 evaluates every pixel of a
/// slice at the same t): the displacement as a cubic and the velocity as a quadratic in the
/// local (x, y). Computed once per element and slice, it makes the per-pixel evaluation a 2D
/// one. `SpacetimeSliceCubic` in `include/spacetime_cubic.glsl` is its twin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SliceCubic {
    /// Frame centre (x, y).
    pub centre: [f64; 2],
    /// Frame extents (x, y).
    pub extent: [f64; 2],
    /// `u = Σ a_k x^i y^j` over 1, x, y, x², xy, y², x³, x²y, xy², y³ (local coordinates).
    pub a: [[f64; 2]; 10],
    /// `v = ∂u/∂t = Σ b_k x^i y^j` over 1, x, y, x², xy, y² (global time units).
    pub b: [[f64; 2]; 6],
}

impl SliceCubic {
    /// The restriction of the element (`frame`, `c`) to the plane at time `t`.
    pub fn restrict(frame: &LocalFrame, c: &CubicCoefficients, t: f64) -> Self {
        let qt = (t - frame.centre[2]) / frame.extent[2];
        let pt = [1.0, qt, qt * qt, qt * qt * qt];
        let (mut a, mut b) = ([[0.0; 2]; 10], [[0.0; 2]; 6]);
        for (k, e) in MONOMIALS.iter().enumerate() {
            let i = slice_monomial_index(e[0] as usize, e[1] as usize);
            let d = e[2] as usize;
            for comp in 0..2 {
                a[i][comp] += c[k][comp] * pt[d];
                if d >= 1 {
                    b[i][comp] += c[k][comp] * d as f64 * pt[d - 1] / frame.extent[2];
                }
            }
        }
        Self { centre: [frame.centre[0], frame.centre[1]], extent: [frame.extent[0], frame.extent[1]], a, b }
    }

    /// The fields at `(x, y)` on the plane (the same as [`evaluate`] there).
    pub fn evaluate(&self, material: &Material, x: f64, y: f64) -> PointFields {
        let (qx, qy) = ((x - self.centre[0]) / self.extent[0], (y - self.centre[1]) / self.extent[1]);
        let (a, b) = (&self.a, &self.b);
        let (xx, xy, yy) = (qx * qx, qx * qy, qy * qy);
        let comb = |f: &dyn Fn(usize) -> f64| -> [f64; 2] { [f(0), f(1)] };
        let u = comb(&|i| {
            a[0][i]
                + a[1][i] * qx
                + a[2][i] * qy
                + a[3][i] * xx
                + a[4][i] * xy
                + a[5][i] * yy
                + a[6][i] * xx * qx
                + a[7][i] * xx * qy
                + a[8][i] * qx * yy
                + a[9][i] * yy * qy
        });
        let ux = comb(&|i| {
            (a[1][i]
                + 2.0 * a[3][i] * qx
                + a[4][i] * qy
                + 3.0 * a[6][i] * xx
                + 2.0 * a[7][i] * xy
                + a[8][i] * yy)
                / self.extent[0]
        });
        let uy = comb(&|i| {
            (a[2][i]
                + a[4][i] * qx
                + 2.0 * a[5][i] * qy
                + a[7][i] * xx
                + 2.0 * a[8][i] * xy
                + 3.0 * a[9][i] * yy)
                / self.extent[1]
        });
        let v = comb(&|i| b[0][i] + b[1][i] * qx + b[2][i] * qy + b[3][i] * xx + b[4][i] * xy + b[5][i] * yy);
        let vx = comb(&|i| (b[1][i] + 2.0 * b[3][i] * qx + b[4][i] * qy) / self.extent[0]);
        let vy = comb(&|i| (b[2][i] + b[4][i] * qx + 2.0 * b[5][i] * qy) / self.extent[1]);
        fields_from_derivatives(material, u, ux, uy, v, vx, vy)
    }
}

/// The seed's colour coordinate `s = log(U + 1) / log(U_max + 1)`, clamped to [0, 1]
/// (seed 003 §4.2.3). It is the render module's log ramp over `[1, U_max + 1]` applied to
/// `U + 1`, which is how the shader computes it (`include/colormap.glsl`).
pub fn seed_log_coordinate(u: f64, u_max: f64) -> f64 {
    crate::render::ramp_coordinate(u + 1.0, 1.0, u_max + 1.0, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_slice_restriction_evaluates_as_the_full_cubic() {
        let frame = LocalFrame { centre: [0.3, -0.2, 0.7], extent: [0.11, 0.07, 0.05] };
        let material = Material { lambda: 2.5, mu: 1.3, density: 1.0 };
        let mut c = [[0.0; 2]; 20];
        for (k, v) in c.iter_mut().enumerate() {
            *v = [((k * 7919) % 13) as f64 / 13.0 - 0.4, ((k * 104_729) % 17) as f64 / 17.0 - 0.6];
        }
        for t in [0.68, 0.7, 0.7249] {
            let s = SliceCubic::restrict(&frame, &c, t);
            for (x, y) in [(0.3, -0.2), (0.26, -0.17), (0.35, -0.23)] {
                let full = evaluate(&frame, &material, &c, [x, y, t]);
                let slice = s.evaluate(&material, x, y);
                let near = |a: f64, b: f64, what: &str| {
                    assert!((a - b).abs() <= 1e-12 * (1.0 + b.abs()), "{what} at t = {t}: {a} vs {b}")
                };
                near(slice.strain_energy_density, full.strain_energy_density, "U");
                near(slice.speed, full.speed, "|v|");
                for k in 0..2 {
                    near(slice.displacement[k], full.displacement[k], "u");
                    near(slice.velocity[k], full.velocity[k], "v");
                    near(slice.speed_gradient[k], full.speed_gradient[k], "∇|v|");
                }
                for k in 0..3 {
                    near(slice.strain[k], full.strain[k], "ε");
                }
            }
        }
    }

    const STEEL: Material = Material { lambda: 2.0, mu: 1.0, density: 1.0 };

    fn frame() -> LocalFrame {
        LocalFrame { centre: [0.3, -0.2, 1.5], extent: [0.5, 0.25, 0.125] }
    }

    /// A field given in global coordinates, converted to local coefficients by expansion:
    /// u_x = x̂·t̂ (so v_x = x̂), u_y = ŷ² (no velocity).
    fn global_bilinear() -> CubicCoefficients {
        let f = frame();
        let [cx, cy, ct] = f.centre;
        let [wx, wy, wt] = f.extent;
        let mut c = [[0.0; 2]; 20];
        // x̂ t̂ = (cx + wx x)(ct + wt t) = cx ct + wx ct x + cx wt t + wx wt x t
        c[0][0] = cx * ct;
        c[1][0] = wx * ct;
        c[3][0] = cx * wt;
        c[6][0] = wx * wt;
        // ŷ² = cy² + 2 cy wy y + wy² y²
        c[0][1] = cy * cy;
        c[2][1] = 2.0 * cy * wy;
        c[7][1] = wy * wy;
        c
    }

    #[test]
    fn derived_fields_of_a_known_field() {
        let c = global_bilinear();
        let p = [0.7, 0.1, 1.6];
        let f = evaluate(&frame(), &STEEL, &c, p);
        let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        close(f.displacement[0], p[0] * p[2]);
        close(f.displacement[1], p[1] * p[1]);
        close(f.velocity[0], p[0]);
        close(f.velocity[1], 0.0);
        close(f.speed, p[0]);
        close(f.speed_gradient[0], 1.0);
        close(f.speed_gradient[1], 0.0);
        // ε_xx = t̂, ε_yy = 2ŷ, ε_xy = 0.
        close(f.strain[0], p[2]);
        close(f.strain[1], 2.0 * p[1]);
        close(f.strain[2], 0.0);
        let tr = p[2] + 2.0 * p[1];
        close(f.strain_energy_density, 0.5 * (2.0 * tr * tr + 2.0 * (p[2] * p[2] + 4.0 * p[1] * p[1])));
        let n = f.normal(2.0);
        let l = (4.0f64 + 1.0).sqrt();
        close(n[0], -2.0 / l);
        close(n[2], 1.0 / l);
    }

    #[test]
    fn flat_normal_where_the_speed_vanishes() {
        let c = global_bilinear();
        let f = evaluate(&frame(), &STEEL, &c, [0.0, 0.1, 1.6]);
        assert_eq!(f.speed, 0.0);
        assert_eq!(f.normal(3.0), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let mut c = [[0.0; 2]; 20];
        for (a, ca) in c.iter_mut().enumerate() {
            *ca = [((a * 7 + 3) % 11) as f64 / 11.0 - 0.5, ((a * 5 + 1) % 13) as f64 / 13.0 - 0.5];
        }
        let p = [0.4, -0.1, 1.55];
        let h = 1e-6;
        let f = evaluate(&frame(), &STEEL, &c, p);
        let at =
            |dx: f64, dy: f64, dt: f64| evaluate(&frame(), &STEEL, &c, [p[0] + dx, p[1] + dy, p[2] + dt]);
        for i in 0..2 {
            let fd = (at(0.0, 0.0, h).displacement[i] - at(0.0, 0.0, -h).displacement[i]) / (2.0 * h);
            assert!((fd - f.velocity[i]).abs() < 1e-5 * (1.0 + fd.abs()), "v{i}: {fd} vs {}", f.velocity[i]);
        }
        let gx = (at(h, 0.0, 0.0).speed - at(-h, 0.0, 0.0).speed) / (2.0 * h);
        let gy = (at(0.0, h, 0.0).speed - at(0.0, -h, 0.0).speed) / (2.0 * h);
        assert!((gx - f.speed_gradient[0]).abs() < 1e-4 * (1.0 + gx.abs()));
        assert!((gy - f.speed_gradient[1]).abs() < 1e-4 * (1.0 + gy.abs()));
        let exx = (at(h, 0.0, 0.0).displacement[0] - at(-h, 0.0, 0.0).displacement[0]) / (2.0 * h);
        assert!((exx - f.strain[0]).abs() < 1e-5 * (1.0 + exx.abs()));
    }

    #[test]
    fn the_seed_log_coordinate() {
        assert_eq!(seed_log_coordinate(0.0, 10.0), 0.0);
        assert!((seed_log_coordinate(10.0, 10.0) - 1.0).abs() < 1e-15);
        assert!((seed_log_coordinate(2.0, 8.0) - 3f64.ln() / 9f64.ln()).abs() < 1e-15);
        assert_eq!(seed_log_coordinate(100.0, 10.0), 1.0);
    }
}
