//! Learned visibility (seed 000 §8.3, Eq. 17): the reduced visibility of a new configuration
//! is the convex combination of the training visibilities whose reduced geometries best
//! predict the new reduced geometry,
//!
//! ```text
//! x = argmin_{x ≥ 0, Σx = 1} ‖ĝ − (B_gᵀ G) x‖² + μ Σ_t ‖ĝ − ĝ_t‖² x_t²,    v̂ = (B_vᵀ V) x,
//! ```
//!
//! with `B_gᵀ G` and `B_vᵀ V` precomputed (their sizes do not depend on the mesh). The second
//! term (μ = [`LOCALITY`]) is ours: the two-room scene's vertex positions are affine in the
//! design parameters (the ceiling in `tan(tilt)`), so every interior sample is *exactly* a
//! convex combination of others and Eq. 17 alone has many minimisers; the term breaks the tie
//! towards nearby samples, so a training configuration gets its own visibility back.
//!
//! The solver is exact: since `Σx = 1`, the residual is `(B_gᵀG − ĝ 1ᵀ) x`, homogeneous in
//! `x`, so with `M` the stacked residual and locality rows, `y = argmin_{y ≥ 0} ‖[M; 1ᵀ] y −
//! [0; 1]‖` (Lawson–Hanson non-negative least squares, which terminates with the optimum) gives
//! `x = y / Σy`: for a direction `x` on the simplex the best scale is `1/(1 + ‖Mx‖²)` with
//! value `‖Mx‖²/(1 + ‖Mx‖²)`, increasing in `‖Mx‖²`.

use crate::tensor::Tensor;

/// Weight μ of the locality term.
pub const LOCALITY: f64 = 1e-2;

/// The learned visibility model: `B_gᵀ G` (m_g × T) and `B_vᵀ V` (m_v × T).
#[derive(Clone, Debug, PartialEq)]
pub struct LearnedVisibility {
    /// Reduced training geometries, one column per configuration.
    pub geometry: Tensor,
    /// Reduced training visibilities, one column per configuration.
    pub visibility: Tensor,
}

impl LearnedVisibility {
    /// The convex weights `x` of Eq. 17 for reduced geometry `ghat`.
    pub fn weights(&self, ghat: &[f64]) -> Vec<f64> {
        let (m, t) = (self.geometry.shape()[0], self.geometry.shape()[1]);
        let a = self.geometry.data();
        // Rows: the residual (B_gᵀG − ĝ1ᵀ), one locality row per sample (diagonal), the sum.
        let rows = m + t + 1;
        let mut aug = vec![0.0; rows * t];
        let mut rhs = vec![0.0; rows];
        for i in 0..m {
            for j in 0..t {
                aug[i * t + j] = a[i * t + j] - ghat[i];
            }
        }
        for j in 0..t {
            let d2: f64 = (0..m).map(|i| (ghat[i] - a[i * t + j]).powi(2)).sum();
            aug[(m + j) * t + j] = (LOCALITY * d2).sqrt();
            aug[(m + t) * t + j] = 1.0;
        }
        rhs[m + t] = 1.0;
        let y = nnls(&aug, rows, t, &rhs);
        let sum: f64 = y.iter().sum();
        if sum > 0.0 {
            y.iter().map(|v| v / sum).collect()
        } else {
            vec![1.0 / t as f64; t]
        }
    }

    /// `v̂ = (B_vᵀ V) x` for reduced geometry `ghat`, and the weights.
    pub fn predict(&self, ghat: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let x = self.weights(ghat);
        let (mv, t) = (self.visibility.shape()[0], self.visibility.shape()[1]);
        let v = self.visibility.data();
        let vhat = (0..mv).map(|i| (0..t).map(|j| v[i * t + j] * x[j]).sum()).collect();
        (vhat, x)
    }
}

/// Least squares `min ‖A x − b‖` over the columns `cols` of row-major `a` (`rows × n`), by
/// Householder QR of the selected columns.
fn least_squares(a: &[f64], rows: usize, n: usize, cols: &[usize], b: &[f64]) -> Vec<f64> {
    let k = cols.len();
    let mut q: Vec<Vec<f64>> = cols.iter().map(|&j| (0..rows).map(|i| a[i * n + j]).collect()).collect();
    let mut y = b.to_vec();
    let mut r_diag = vec![0.0; k];
    for c in 0..k {
        let norm = q[c][c..].iter().map(|x| x * x).sum::<f64>().sqrt();
        let alpha = if q[c][c] > 0.0 { -norm } else { norm };
        r_diag[c] = alpha;
        if norm == 0.0 {
            continue;
        }
        let mut v: Vec<f64> = q[c][c..].to_vec();
        v[0] -= alpha;
        let vnorm2: f64 = v.iter().map(|x| x * x).sum();
        if vnorm2 == 0.0 {
            continue;
        }
        for col in q.iter_mut().skip(c + 1) {
            let d: f64 = v.iter().zip(&col[c..]).map(|(a, b)| a * b).sum::<f64>() * 2.0 / vnorm2;
            col[c..].iter_mut().zip(&v).for_each(|(x, vi)| *x -= d * vi);
        }
        let d: f64 = v.iter().zip(&y[c..]).map(|(a, b)| a * b).sum::<f64>() * 2.0 / vnorm2;
        y[c..].iter_mut().zip(&v).for_each(|(x, vi)| *x -= d * vi);
    }
    let mut x = vec![0.0; k];
    for c in (0..k).rev() {
        let s: f64 = (c + 1..k).map(|j| q[j][c] * x[j]).sum();
        x[c] = if r_diag[c].abs() > 1e-300 { (y[c] - s) / r_diag[c] } else { 0.0 };
    }
    x
}

/// Lawson–Hanson non-negative least squares: `min ‖A x − b‖, x ≥ 0` for row-major `a`
/// (`rows × n`).
pub fn nnls(a: &[f64], rows: usize, n: usize, b: &[f64]) -> Vec<f64> {
    let mut x = vec![0.0; n];
    let mut passive = vec![false; n];
    let residual = |x: &[f64]| -> Vec<f64> {
        (0..rows).map(|i| b[i] - (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>()).collect()
    };
    let scale =
        a.iter().fold(0.0f64, |m, v| m.max(v.abs())) * b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1.0);
    let tol = 1e-12 * scale * rows as f64;
    for _ in 0..3 * n + 10 {
        let r = residual(&x);
        let w: Vec<f64> = (0..n).map(|j| (0..rows).map(|i| a[i * n + j] * r[i]).sum()).collect();
        let Some(t) = (0..n).filter(|&j| !passive[j] && w[j] > tol).max_by(|&p, &q| w[p].total_cmp(&w[q]))
        else {
            break;
        };
        passive[t] = true;
        loop {
            let cols: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
            let z = least_squares(a, rows, n, &cols, b);
            if z.iter().all(|&v| v > 0.0) {
                for (&j, &v) in cols.iter().zip(&z) {
                    x[j] = v;
                }
                break;
            }
            // Step towards z until a passive variable reaches zero; drop those.
            let alpha = cols
                .iter()
                .zip(&z)
                .filter(|(_, &zj)| zj <= 0.0)
                .map(|(&j, &zj)| x[j] / (x[j] - zj))
                .fold(f64::INFINITY, f64::min);
            for (&j, &zj) in cols.iter().zip(&z) {
                x[j] += alpha * (zj - x[j]);
                if x[j] <= 1e-15 {
                    x[j] = 0.0;
                    passive[j] = false;
                }
            }
            if !passive.iter().any(|&p| p) {
                break;
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_matches_a_known_solution() {
        // min ‖A x − b‖ with x ≥ 0: the unconstrained solution has a negative entry.
        let a = [1.0, 0.0, 0.0, 1.0, 1.0, 1.0];
        let b = [2.0, -1.0, 1.0];
        let x = nnls(&a, 3, 2, &b);
        // With x₁ = 0: min (x₀ − 2)² + (x₀ − 1)² → x₀ = 1.5.
        assert!((x[0] - 1.5).abs() < 1e-12 && x[1] == 0.0, "{x:?}");
    }

    #[test]
    fn a_training_geometry_gets_its_own_weights() {
        // Four samples on a line: the middle ones are convex combinations of the ends, yet
        // the locality term picks each sample itself.
        let g = Tensor::from_vec(&[2, 4], vec![0.0, 1.0, 2.0, 3.0, 1.0, 1.0, 1.0, 1.0]).unwrap();
        let v = Tensor::from_vec(&[1, 4], vec![10.0, 20.0, 30.0, 40.0]).unwrap();
        let model = LearnedVisibility { geometry: g, visibility: v };
        for t in 0..4 {
            let (vhat, x) = model.predict(&[t as f64, 1.0]);
            assert!((x[t] - 1.0).abs() < 1e-6, "sample {t}: {x:?}");
            assert!((vhat[0] - 10.0 * (t + 1) as f64).abs() < 1e-4, "{vhat:?}");
        }
        // Between samples 1 and 2: convex weights, mostly on those two, nearer one heavier,
        // reproducing the geometry.
        let (_, x) = model.predict(&[1.25, 1.0]);
        assert!((x.iter().sum::<f64>() - 1.0).abs() < 1e-12 && x.iter().all(|&v| v >= 0.0), "{x:?}");
        assert!(x[1] + x[2] > 0.9 && x[1] > x[2], "{x:?}");
        let g: f64 = x.iter().enumerate().map(|(t, v)| t as f64 * v).sum();
        assert!((g - 1.25).abs() < 0.01, "{g}");
    }
}
