//! Bases: for each axis name, an orthonormal `n × m` matrix `B` with `x = B x̂`, `x̂ = Bᵀ x`
//! (§3).

use std::collections::BTreeMap;

use super::error::ReduceError;
use crate::tensor::Tensor;

/// An orthonormal basis: `n` full dimensions, `m ≤ n` reduced ones, stored as `n × m`.
#[derive(Clone, Debug, PartialEq)]
pub struct Basis {
    matrix: Tensor,
}

impl Basis {
    /// Wraps an `n × m` matrix whose columns are orthonormal to within `tolerance`
    /// (max |BᵀB − I|); `name` is used in errors.
    pub fn new(name: &str, matrix: Tensor, tolerance: f64) -> Result<Self, ReduceError> {
        let bad = |detail: String| ReduceError::BadBasis { basis: name.to_string(), detail };
        if matrix.order() != 2 {
            return Err(bad(format!("needs a matrix, got shape {:?}", matrix.shape())));
        }
        let (n, m) = (matrix.shape()[0], matrix.shape()[1]);
        if m > n || m == 0 {
            return Err(bad(format!("shape {n}×{m}: needs 1 ≤ columns ≤ rows")));
        }
        let b = Self { matrix };
        let err = b.orthonormality_error();
        if err.is_nan() || err > tolerance {
            return Err(bad(format!("columns are not orthonormal: max |BᵀB − I| = {err:e} > {tolerance:e}")));
        }
        Ok(b)
    }

    /// An orthonormal basis of the span of `columns` (`n × k`) by Gram–Schmidt done twice
    /// ("twice is enough": the second pass removes what rounding left of the first). Columns
    /// whose remainder falls below `1e-12` of their norm are dependent and dropped.
    pub fn orthonormalize(name: &str, columns: &Tensor) -> Result<Self, ReduceError> {
        Self::orthonormalize_at_most(name, columns, usize::MAX)
    }

    /// [`Self::orthonormalize`] stopped once `cap` columns are kept: the same columns as the
    /// whole basis's first `cap` (Gram–Schmidt keeps each column against the ones before it
    /// only), for a fraction of the work when most columns would be cut anyway.
    pub fn orthonormalize_at_most(name: &str, columns: &Tensor, cap: usize) -> Result<Self, ReduceError> {
        let bad = |detail: String| ReduceError::BadBasis { basis: name.to_string(), detail };
        if columns.order() != 2 {
            return Err(bad(format!("needs a matrix, got shape {:?}", columns.shape())));
        }
        let (n, k) = (columns.shape()[0], columns.shape()[1]);
        let mut kept: Vec<Vec<f64>> = Vec::new();
        for j in 0..k {
            if kept.len() >= cap {
                break;
            }
            let mut v: Vec<f64> = (0..n).map(|i| columns.data()[i * k + j]).collect();
            let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !norm0.is_finite() {
                return Err(bad(format!("column {j} is not finite")));
            }
            for _ in 0..2 {
                for q in &kept {
                    let d: f64 = q.iter().zip(&v).map(|(a, b)| a * b).sum();
                    v.iter_mut().zip(q).for_each(|(x, qi)| *x -= d * qi);
                }
            }
            let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if norm > 1e-12 * norm0 && norm > 0.0 {
                v.iter_mut().for_each(|x| *x /= norm);
                kept.push(v);
            }
        }
        if kept.is_empty() {
            return Err(bad("every column is zero or dependent".into()));
        }
        let m = kept.len();
        let mut data = vec![0.0; n * m];
        for (j, q) in kept.iter().enumerate() {
            for i in 0..n {
                data[i * m + j] = q[i];
            }
        }
        Ok(Self { matrix: Tensor::from_vec(&[n, m], data).expect("shape matches") })
    }

    /// One basis spanning both `a` and `b` (same full dimension), re-orthonormalised — how the
    /// paper makes the pairs that must share a basis, `B_u = B_p` and `B_s = B_h` (§6.1).
    pub fn merge(name: &str, a: &Basis, b: &Basis) -> Result<Self, ReduceError> {
        if a.full_dim() != b.full_dim() {
            return Err(ReduceError::BadBasis {
                basis: name.to_string(),
                detail: format!(
                    "cannot merge bases of {} and {} full dimensions",
                    a.full_dim(),
                    b.full_dim()
                ),
            });
        }
        let (n, ma, mb) = (a.full_dim(), a.reduced_dim(), b.reduced_dim());
        let mut data = Vec::with_capacity(n * (ma + mb));
        for i in 0..n {
            data.extend_from_slice(&a.matrix.data()[i * ma..(i + 1) * ma]);
            data.extend_from_slice(&b.matrix.data()[i * mb..(i + 1) * mb]);
        }
        Self::orthonormalize(name, &Tensor::from_vec(&[n, ma + mb], data).expect("shape matches"))
    }

    /// The identity basis of `n` dimensions (an axis left unreduced).
    pub fn identity(n: usize) -> Self {
        Self { matrix: Tensor::identity(n) }
    }

    /// Full dimension `n`.
    pub fn full_dim(&self) -> usize {
        self.matrix.shape()[0]
    }

    /// Reduced dimension `m`.
    pub fn reduced_dim(&self) -> usize {
        self.matrix.shape()[1]
    }

    /// The `n × m` matrix.
    pub fn matrix(&self) -> &Tensor {
        &self.matrix
    }

    /// max |BᵀB − I| over all entries (BᵀB by faer's blocked product on every core: a strided
    /// loop over column pairs took most of a minute for the cavity's B_u, 281,871 × 128).
    pub fn orthonormality_error(&self) -> f64 {
        use faer::linalg::matmul::matmul;
        use faer::{Accum, Mat, MatRef, Par};
        let (n, m) = (self.full_dim(), self.reduced_dim());
        let b = MatRef::from_row_major_slice(self.matrix.data(), n, m);
        let mut gram = Mat::<f64>::zeros(m, m);
        matmul(gram.as_mut(), Accum::Replace, b.transpose(), b, 1.0, Par::rayon(0));
        let mut worst = 0f64;
        for a in 0..m {
            for c in a..m {
                let want = if a == c { 1.0 } else { 0.0 };
                let e = (gram[(a, c)] - want).abs();
                // NaN propagates: max would drop it.
                if e.is_nan() {
                    return f64::NAN;
                }
                worst = worst.max(e);
            }
        }
        worst
    }

    /// `x̂ = Bᵀ x`.
    pub fn project(&self, x: &[f64]) -> Vec<f64> {
        let m = self.reduced_dim();
        let mut out = vec![0.0; m];
        for (i, &xi) in x.iter().enumerate().take(self.full_dim()) {
            for (o, &b) in out.iter_mut().zip(&self.matrix.data()[i * m..(i + 1) * m]) {
                *o += b * xi;
            }
        }
        out
    }

    /// `x = B x̂`.
    pub fn lift(&self, xhat: &[f64]) -> Vec<f64> {
        let m = self.reduced_dim();
        (0..self.full_dim())
            .map(|i| self.matrix.data()[i * m..(i + 1) * m].iter().zip(xhat).map(|(b, x)| b * x).sum())
            .collect()
    }
}

/// Bases by axis name.
pub type Bases = BTreeMap<String, Basis>;
