//! The bivariate cubic evaluated by the demo field pass. Twin of
//! `shaders-glsl/include/polynomial.glsl`: same coefficient order, same Horner scheme, f64.

use serde::Deserialize;

/// p(x, y) = Σ_{i+j≤3} c_ij xⁱ yʲ, coefficients in graded order
/// c00 c10 c01 c20 c11 c02 c30 c21 c12 c03.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(transparent)]
pub struct BivariateCubic {
    /// The ten coefficients.
    pub coefficients: [f64; 10],
}

impl BivariateCubic {
    /// p(x, y) by Horner in x over polynomials in y (as the GLSL twin).
    pub fn eval(&self, x: f64, y: f64) -> f64 {
        let c = &self.coefficients;
        let a0 = c[0] + y * (c[2] + y * (c[5] + y * c[9]));
        let a1 = c[1] + y * (c[4] + y * c[8]);
        let a2 = c[3] + y * c[7];
        let a3 = c[6];
        a0 + x * (a1 + x * (a2 + x * a3))
    }

    /// |∇p| at (x, y), for error bounds: how much p moves per unit of position error.
    pub fn gradient_norm(&self, x: f64, y: f64) -> f64 {
        let c = &self.coefficients;
        let px = c[1] + 2.0 * c[3] * x + c[4] * y + 3.0 * c[6] * x * x + 2.0 * c[7] * x * y + c[8] * y * y;
        let py = c[2] + c[4] * x + 2.0 * c[5] * y + c[7] * x * x + 2.0 * c[8] * x * y + 3.0 * c[9] * y * y;
        px.hypot(py)
    }

    /// Σ |c_ij| |x|ⁱ |y|ʲ: the scale of the rounding error of an f32 evaluation at (x, y).
    pub fn abs_sum(&self, x: f64, y: f64) -> f64 {
        let abs = BivariateCubic { coefficients: self.coefficients.map(f64::abs) };
        abs.eval(x.abs(), y.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horner_matches_the_monomial_sum() {
        let p = BivariateCubic { coefficients: [0.3, -1.2, 0.7, 0.25, 1.5, -0.8, 0.4, -0.6, 0.9, 0.35] };
        let exps = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3)];
        for &(x, y) in &[(0.0, 0.0), (0.5, -0.25), (-1.0, 1.0), (0.9, 0.3)] {
            let direct: f64 = exps
                .iter()
                .zip(p.coefficients)
                .map(|(&(i, j), c)| c * f64::powi(x, i) * f64::powi(y, j))
                .sum();
            assert!((p.eval(x, y) - direct).abs() < 1e-14, "({x}, {y})");
        }
    }
}
