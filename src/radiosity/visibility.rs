//! Learned visibility (seed 000 §8.3, Eq. 17): the reduced visibility of a new configuration
//! is the convex combination of the training visibilities whose reduced geometries best
//! predict the new reduced geometry,
//!
//! ```text
//! x = argmin_{x ≥ 0, Σx = 1} ‖ĝ − (B_gᵀ G) x‖² + μ Σ_t ‖ĝ − ĝ_t‖² x_t²,    v̂ = (B_vᵀ V) x,
//! ```
//!
//! with `B_gᵀ G` and `B_vᵀ V` precomputed (their sizes do not depend on the mesh). The second
//! term (μ = [`LOCALITY`]) is ours: the two-room scene's vertex positions are affine in a few
//! functions of the design parameters (`[1, w, s, d, tan θ, s·tan θ, d·tan θ]`), so ĝ lives in
//! a six-dimensional space, interior samples are (nearly) convex combinations of others and
//! Eq. 17 alone has many (near-)minimisers; the term breaks the tie towards nearby samples, so
//! a training configuration gets its own visibility back.
//!
//! The solver is exact: since `Σx = 1`, the residual is `(B_gᵀG − ĝ 1ᵀ) x`, homogeneous in
//! `x`, so with `M` the stacked residual and locality rows, `y = argmin_{y ≥ 0} ‖[M; 1ᵀ] y −
//! [0; 1]‖` (Lawson–Hanson non-negative least squares, which terminates with the optimum) gives
//! `x = y / Σy`: for a direction `x` on the simplex the best scale is `1/(1 + ‖Mx‖²)` with
//! value `‖Mx‖²/(1 + ‖Mx‖²)`, increasing in `‖Mx‖²`.

use crate::tensor::Tensor;

/// Weight μ of the locality term.
pub const LOCALITY: f64 = 1e-2;
/// Training configurations considered per query: the nearest in reduced geometry. The
/// locality term gives farther ones weights that vanish with their distance; measured on the
/// small scene (540 samples), all 540 against the nearest 48 changed the radiosity by less
/// than the reduction's own error while cutting Eq. 17's time.
pub const CANDIDATES: usize = 48;

/// Which form of Eq. 17 the weights come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Eq17 {
    /// Ours: the [`CANDIDATES`] training geometries nearest to ĝ, with the locality term
    /// μ = [`LOCALITY`] (a training configuration gets its own visibility back).
    #[default]
    Local,
    /// As printed: every training configuration, no locality term.
    Printed,
}

/// The learned visibility model: `B_gᵀ G` (m_g × T) and `B_vᵀ V` (m_v × T).
#[derive(Clone, Debug, PartialEq)]
pub struct LearnedVisibility {
    geometry: Tensor,
    visibility: Tensor,
    /// `(B_gᵀG)ᵀ(B_gᵀG)`, T × T.
    gram: Vec<f64>,
    /// The form of Eq. 17 the weights are solved in (a run-time choice, not stored).
    form: Eq17,
}

impl LearnedVisibility {
    /// From the reduced training geometries and visibilities (one column per configuration).
    pub fn new(geometry: Tensor, visibility: Tensor) -> Result<Self, crate::tensor::TensorError> {
        if geometry.order() != 2 || visibility.order() != 2 || geometry.shape()[1] != visibility.shape()[1] {
            return Err(crate::tensor::TensorError::NotFinite {
                what: "learned visibility".into(),
                detail: format!(
                    "needs two matrices with one column per training configuration, got {:?} and {:?}",
                    geometry.shape(),
                    visibility.shape()
                ),
            });
        }
        let mut v = Self { geometry, visibility, gram: Vec::new(), form: Eq17::default() };
        v.gram = v.compute_gram();
        Ok(v)
    }

    /// Solves Eq. 17 in `form` from now on.
    pub fn set_form(&mut self, form: Eq17) {
        self.form = form;
    }

    /// The form of Eq. 17 in use.
    pub fn form(&self) -> Eq17 {
        self.form
    }

    /// `B_gᵀ G`.
    pub fn geometry(&self) -> &Tensor {
        &self.geometry
    }

    /// `B_vᵀ V`.
    pub fn visibility(&self) -> &Tensor {
        &self.visibility
    }

    /// The convex weights `x` of Eq. 17 for reduced geometry `ghat`.
    ///
    /// The normal equations of the homogenised system over the [`CANDIDATES`] nearest
    /// training configurations are formed from the precomputed `(B_gᵀG)ᵀ(B_gᵀG)` and solved
    /// by the Lawson–Hanson active set in normal-equation form (Bro & de Jong's FNNLS), whose
    /// inner solves are on the passive set only: independent of the mesh.
    pub fn weights(&self, ghat: &[f64]) -> Vec<f64> {
        self.weights_without(ghat, None)
    }

    /// [`Self::weights`] with training configuration `left_out` not a candidate (its weight
    /// 0): Eq. 17 as if it had not been trained on — the error estimate's cross-validation
    /// ([`super::estimate`]).
    pub fn weights_without(&self, ghat: &[f64], left_out: Option<usize>) -> Vec<f64> {
        let (m, t) = (self.geometry.shape()[0], self.geometry.shape()[1]);
        let a = self.geometry.data();
        // c_j = ĝ·ĝ_j, gram_ij = ĝ_i·ĝ_j.
        let c: Vec<f64> = (0..t).map(|j| (0..m).map(|i| a[i * t + j] * ghat[i]).sum()).collect();
        let gg: f64 = ghat.iter().map(|x| x * x).sum();
        let gram = &self.gram;
        // Q = MᵀM + 11ᵀ with M = [B_gᵀG − ĝ1ᵀ; √(μ d)]: (ĝ_i − ĝ)·(ĝ_j − ĝ) + μ d_i δ_ij + 1.
        // Candidates: the CANDIDATES training geometries nearest to ĝ (all when fewer).
        let d: Vec<f64> = (0..t).map(|i| (gram[i * t + i] - 2.0 * c[i] + gg).max(0.0)).collect();
        let (candidates, locality) = match self.form {
            Eq17::Local => (CANDIDATES, LOCALITY),
            Eq17::Printed => (t, 0.0),
        };
        let mut order: Vec<usize> = (0..t).filter(|&i| Some(i) != left_out).collect();
        if order.len() > candidates {
            order.select_nth_unstable_by(candidates, |&p, &q| d[p].total_cmp(&d[q]));
            order.truncate(candidates);
        }
        let k = order.len();
        let mut q = vec![0.0; k * k];
        for (a, &i) in order.iter().enumerate() {
            for (b, &j) in order.iter().enumerate() {
                q[a * k + b] = gram[i * t + j] - c[i] - c[j] + gg + 1.0;
            }
            q[a * k + a] += locality * d[i];
        }
        let y = nnls_normal(&q, &vec![1.0; k], k);
        let sum: f64 = y.iter().sum();
        let mut x = vec![0.0; t];
        for (&i, &v) in order.iter().zip(&y) {
            x[i] = if sum > 0.0 { v / sum } else { 1.0 / k as f64 };
        }
        x
    }

    /// `(B_gᵀG)ᵀ(B_gᵀG)` (T × T).
    fn compute_gram(&self) -> Vec<f64> {
        let (m, t) = (self.geometry.shape()[0], self.geometry.shape()[1]);
        let a = self.geometry.data();
        let mut g = vec![0.0; t * t];
        for k in 0..m {
            let row = &a[k * t..(k + 1) * t];
            for i in 0..t {
                let ri = row[i];
                for j in 0..t {
                    g[i * t + j] += ri * row[j];
                }
            }
        }
        g
    }

    /// `v̂ = (B_vᵀ V) x` for reduced geometry `ghat`, and the weights.
    pub fn predict(&self, ghat: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.predict_without(ghat, None)
    }

    /// [`Self::predict`] with training configuration `left_out` not a candidate
    /// ([`Self::weights_without`]).
    pub fn predict_without(&self, ghat: &[f64], left_out: Option<usize>) -> (Vec<f64>, Vec<f64>) {
        let x = self.weights_without(ghat, left_out);
        let (mv, t) = (self.visibility.shape()[0], self.visibility.shape()[1]);
        let v = self.visibility.data();
        let vhat = (0..mv).map(|i| (0..t).map(|j| v[i * t + j] * x[j]).sum()).collect();
        (vhat, x)
    }
}

/// Non-negative least squares from the normal equations (`ata = AᵀA`, `atb = Aᵀb`, `n`
/// unknowns): the Lawson–Hanson active set in Bro & de Jong's form, the passive-set systems
/// solved by Cholesky. The same iterates as [`nnls`] on `A` itself.
pub fn nnls_normal(ata: &[f64], atb: &[f64], n: usize) -> Vec<f64> {
    let scale = ata.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let gradient = |x: &[f64]| -> Vec<f64> {
        (0..n)
            .map(|i| atb[i] - (0..n).filter(|&j| x[j] != 0.0).map(|j| ata[i * n + j] * x[j]).sum::<f64>())
            .collect()
    };
    lawson_hanson(n, 1e-13 * scale * (n as f64).sqrt(), gradient, |cols| cholesky_solve(ata, n, cols, atb))
}

/// The Lawson–Hanson active-set iteration for `min ‖Ax − b‖, x ≥ 0` over `n` unknowns, given
/// the negative gradient `Aᵀ(b − Ax)` and the unconstrained least-squares solution on a set of
/// passive columns; `tol` is the gradient below which a variable stays at zero.
fn lawson_hanson(
    n: usize,
    tol: f64,
    gradient: impl Fn(&[f64]) -> Vec<f64>,
    passive_solve: impl Fn(&[usize]) -> Vec<f64>,
) -> Vec<f64> {
    let mut x = vec![0.0; n];
    let mut passive = vec![false; n];
    for _ in 0..3 * n + 10 {
        let w = gradient(&x);
        let Some(t) = (0..n).filter(|&j| !passive[j] && w[j] > tol).max_by(|&p, &q| w[p].total_cmp(&w[q]))
        else {
            break;
        };
        passive[t] = true;
        loop {
            let cols: Vec<usize> = (0..n).filter(|&j| passive[j]).collect();
            let z = passive_solve(&cols);
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

/// Solves `ata[cols, cols] z = atb[cols]` by Cholesky (a tiny diagonal shift if a pivot is
/// not positive: the passive columns of a rank-deficient `A`).
fn cholesky_solve(ata: &[f64], n: usize, cols: &[usize], atb: &[f64]) -> Vec<f64> {
    let k = cols.len();
    let mut l = vec![0.0; k * k];
    let shift = 1e-14 * cols.iter().map(|&c| ata[c * n + c]).fold(0.0f64, f64::max);
    for i in 0..k {
        for j in 0..=i {
            let mut s = ata[cols[i] * n + cols[j]];
            for p in 0..j {
                s -= l[i * k + p] * l[j * k + p];
            }
            if i == j {
                l[i * k + i] = if s > shift { s.sqrt() } else { (s.abs() + shift).sqrt().max(1e-300) };
            } else {
                l[i * k + j] = s / l[j * k + j];
            }
        }
    }
    let mut y: Vec<f64> = cols.iter().map(|&c| atb[c]).collect();
    for i in 0..k {
        for p in 0..i {
            y[i] -= l[i * k + p] * y[p];
        }
        y[i] /= l[i * k + i];
    }
    for i in (0..k).rev() {
        for p in i + 1..k {
            y[i] -= l[p * k + i] * y[p];
        }
        y[i] /= l[i * k + i];
    }
    y
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
/// (`rows × n`), by Householder QR of the passive columns: the reference for
/// [`nnls_normal`].
pub fn nnls(a: &[f64], rows: usize, n: usize, b: &[f64]) -> Vec<f64> {
    let residual = |x: &[f64]| -> Vec<f64> {
        (0..rows).map(|i| b[i] - (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>()).collect()
    };
    let gradient = |x: &[f64]| -> Vec<f64> {
        let r = residual(x);
        (0..n).map(|j| (0..rows).map(|i| a[i * n + j] * r[i]).sum()).collect()
    };
    let scale =
        a.iter().fold(0.0f64, |m, v| m.max(v.abs())) * b.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1.0);
    lawson_hanson(n, 1e-12 * scale * rows as f64, gradient, |cols| least_squares(a, rows, n, cols, b))
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
    fn the_normal_equation_form_agrees_with_the_dense_one() {
        let (rows, n) = (30, 12);
        let a: Vec<f64> = (0..rows * n).map(|i| ((i * 7919 % 101) as f64 / 50.0) - 1.0).collect();
        let b: Vec<f64> = (0..rows).map(|i| ((i * 31 % 17) as f64 / 8.0) - 1.0).collect();
        let dense = nnls(&a, rows, n, &b);
        let ata: Vec<f64> =
            (0..n * n).map(|k| (0..rows).map(|r| a[r * n + k / n] * a[r * n + k % n]).sum()).collect();
        let atb: Vec<f64> = (0..n).map(|j| (0..rows).map(|r| a[r * n + j] * b[r]).sum()).collect();
        let normal = nnls_normal(&ata, &atb, n);
        assert!(dense.contains(&0.0) && dense.iter().any(|&v| v > 0.0), "{dense:?}");
        for (p, q) in dense.iter().zip(&normal) {
            assert!((p - q).abs() < 1e-9, "{dense:?} vs {normal:?}");
        }
    }

    #[test]
    fn a_training_geometry_gets_its_own_weights() {
        // Four samples on a line: the middle ones are convex combinations of the ends, yet
        // the locality term picks each sample itself.
        let g = Tensor::from_vec(&[2, 4], vec![0.0, 1.0, 2.0, 3.0, 1.0, 1.0, 1.0, 1.0]).unwrap();
        let v = Tensor::from_vec(&[1, 4], vec![10.0, 20.0, 30.0, 40.0]).unwrap();
        let model = LearnedVisibility::new(g, v).unwrap();
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

    #[test]
    fn the_printed_form_fits_the_geometry_at_least_as_well_over_all_samples() {
        // 60 samples of a 3-parameter geometry; the printed form minimises the geometric
        // residual over every sample, ours over the 48 nearest with a locality penalty.
        let t = 60;
        let mut data = vec![0.0; 4 * t];
        for j in 0..t {
            let (a, b, c) =
                ((j * 7 % 11) as f64 / 10.0, (j * 5 % 13) as f64 / 12.0, (j * 3 % 7) as f64 / 6.0);
            for (i, v) in [a, b, c, 1.0].iter().enumerate() {
                data[i * t + j] = *v;
            }
        }
        let g = Tensor::from_vec(&[4, t], data.clone()).unwrap();
        let v = Tensor::from_vec(&[1, t], (0..t).map(|j| j as f64).collect()).unwrap();
        let mut model = LearnedVisibility::new(g, v).unwrap();
        let query = [0.43, 0.61, 0.29, 1.0];
        let residual = |x: &[f64]| -> f64 {
            (0..4).map(|i| ((0..t).map(|j| data[i * t + j] * x[j]).sum::<f64>() - query[i]).powi(2)).sum()
        };
        let local = model.weights(&query);
        model.set_form(Eq17::Printed);
        assert_eq!(model.form(), Eq17::Printed);
        let printed = model.weights(&query);
        for x in [&local, &printed] {
            assert!((x.iter().sum::<f64>() - 1.0).abs() < 1e-12 && x.iter().all(|&v| v >= 0.0), "{x:?}");
        }
        assert!(local.iter().filter(|&&v| v > 0.0).count() <= CANDIDATES);
        assert!(
            residual(&printed) <= residual(&local) + 1e-12,
            "{} > {}",
            residual(&printed),
            residual(&local)
        );
    }
}
