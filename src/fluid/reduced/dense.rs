//! Dense helpers of the reduced step ([`super::step`]): a row-major matrix stored in f64 or
//! f32 whose products accumulate in f64, symmetric-axis folding, and Cholesky.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Accum, Mat, MatRef, Par};

use crate::fluid::FluidError;
use crate::tensor::{distinct_permutations, Tensor};

use super::induced::sorted_tuples;

/// How the step stores the advection tensors `Â` and `Â_h`, which every step reads whole to
/// assemble K̂ (the step's largest, memory-bound contraction).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AdvectionStorage {
    /// f64, as premultiplied (the default).
    #[default]
    F64,
    /// Rounded to f32 (half the memory traffic); the products still accumulate in f64, and
    /// Â's skew packing keeps `Â ⊗ f̂` exactly skew, so the energy argument of §A.2 holds
    /// unchanged. K̂ then carries a relative error of about 2⁻²⁴ ≈ 6·10⁻⁸ per entry.
    F32,
}

/// A row-major `rows × cols` matrix in the precision [`AdvectionStorage`] asks for.
#[derive(Clone, Debug)]
pub(super) enum RowMajor {
    F64(Vec<f64>),
    F32(Vec<f32>),
}

impl RowMajor {
    /// The same values in `storage`'s precision.
    pub(super) fn stored(self, storage: AdvectionStorage) -> Self {
        match (self, storage) {
            (RowMajor::F64(v), AdvectionStorage::F32) => RowMajor::F32(v.iter().map(|&x| x as f32).collect()),
            (RowMajor::F32(v), AdvectionStorage::F64) => RowMajor::F64(v.iter().map(|&x| x as f64).collect()),
            (same, _) => same,
        }
    }

    /// Its precision.
    pub(super) fn storage(&self) -> AdvectionStorage {
        match self {
            RowMajor::F64(_) => AdvectionStorage::F64,
            RowMajor::F32(_) => AdvectionStorage::F32,
        }
    }

    /// `y = M x` with the rows split in two halves run by rayon (memory-bound: two cores read
    /// it twice as fast).
    pub(super) fn matvec_split(&self, rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
        let half = if rows < 1024 { rows } else { rows / 2 };
        let run = |lo: usize, hi: usize| match self {
            RowMajor::F64(m) => matvec(&m[lo * cols..hi * cols], hi - lo, cols, x),
            RowMajor::F32(m) => matvec_f32(&m[lo * cols..hi * cols], hi - lo, cols, x),
        };
        if half == rows {
            return run(0, rows);
        }
        let (mut top, bottom) = rayon::join(|| run(0, half), || run(half, rows));
        top.extend(bottom);
        top
    }
}

/// `y = M x` for a row-major f32 `M`, accumulated in f64 over eight lanes (so the compiler
/// vectorises the widening multiply–add).
fn matvec_f32(m: &[f32], rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
    const LANES: usize = 8;
    let split = cols - cols % LANES;
    (0..rows)
        .map(|r| {
            let row = &m[r * cols..][..cols];
            let mut acc = [0.0f64; LANES];
            for (chunk, xs) in row[..split].chunks_exact(LANES).zip(x[..split].chunks_exact(LANES)) {
                for l in 0..LANES {
                    acc[l] += chunk[l] as f64 * xs[l];
                }
            }
            let tail: f64 = row[split..].iter().zip(&x[split..]).map(|(a, b)| *a as f64 * b).sum();
            acc.iter().sum::<f64>() + tail
        })
        .collect()
}

/// A tensor whose last `d` axes (length `m` each) are symmetric, as `rows × monomials`: one
/// column per sorted index tuple `i₁ ≤ … ≤ i_d`, its entry times the tuple's number of distinct
/// permutations, so that contracting with `Π x_{i_k}` per column equals the full contraction
/// with `x` on every symmetric axis. Returns the values and the tuples.
pub(super) fn fold_symmetric(data: &[f64], rows: usize, m: usize, d: usize) -> (Vec<f64>, Vec<Vec<usize>>) {
    let tuples = sorted_tuples(m, d);
    let nm = tuples.len();
    let block = m.pow(d as u32);
    let stride: Vec<usize> = (0..d).map(|k| m.pow((d - 1 - k) as u32)).collect();
    let mut out = vec![0.0; rows * nm];
    for (c, idx) in tuples.iter().enumerate() {
        let sorted: Vec<u32> = idx.iter().map(|&i| i as u32).collect();
        let mult = distinct_permutations(&sorted).len() as f64;
        let offset: usize = idx.iter().zip(&stride).map(|(i, s)| i * s).sum();
        for r in 0..rows {
            out[r * nm + c] = mult * data[r * block + offset];
        }
    }
    (out, tuples)
}

/// `y = M x` for row-major `M` (rows × cols).
pub(super) fn matvec(m: &[f64], rows: usize, cols: usize, x: &[f64]) -> Vec<f64> {
    let mut y = Mat::<f64>::zeros(rows, 1);
    let mr = MatRef::from_row_major_slice(m, rows, cols);
    let xr = MatRef::from_column_major_slice(x, cols, 1);
    matmul(y.as_mut(), Accum::Replace, mr, xr, 1.0, Par::Seq);
    (0..rows).map(|i| y[(i, 0)]).collect()
}

/// A row-major `r × c` tensor as a matrix.
pub(super) fn row_major(t: &Tensor, r: usize, c: usize) -> Mat<f64> {
    Mat::from_fn(r, c, |i, j| t.data()[i * c + j])
}

/// `AᵀB` of two row-major matrices with the same rows.
pub(super) fn transpose_times(a: &Tensor, b: &Tensor) -> Mat<f64> {
    let (n, ma, mb) = (a.shape()[0], a.shape()[1], b.shape()[1]);
    let mut out = Mat::<f64>::zeros(ma, mb);
    matmul(
        out.as_mut(),
        Accum::Replace,
        MatRef::from_row_major_slice(a.data(), n, ma).transpose(),
        MatRef::from_row_major_slice(b.data(), n, mb),
        1.0,
        Par::rayon(0),
    );
    out
}

/// Lower Cholesky factor of an SPD matrix (faer's blocked factorisation, one thread: these
/// matrices are a few hundred rows); refuses one that is not positive definite, naming it.
pub(super) fn cholesky(a: &Mat<f64>, what: &str) -> Result<Mat<f64>, FluidError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch};
    let n = a.nrows();
    let mut l = a.clone();
    let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()));
    let refused = |detail: String| {
        FluidError::State(format!(
            "{what} is not positive definite ({detail}): the reduced geometry or basis is degenerate"
        ))
    };
    if (0..n).any(|i| !a[(i, i)].is_finite()) {
        return Err(refused("a diagonal entry is not finite".into()));
    }
    cholesky_in_place(l.as_mut(), Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default())
        .map_err(|e| refused(format!("{e:?}")))?;
    for j in 0..n {
        if !(l[(j, j)] > 0.0 && l[(j, j)].is_finite()) {
            return Err(refused(format!("pivot {j} of {n} is {:.3e}", l[(j, j)])));
        }
        for i in 0..j {
            l[(i, j)] = 0.0;
        }
    }
    Ok(l)
}

/// `x = (LLᵀ)⁻¹ b` for a lower Cholesky factor `L`.
pub(super) fn cholesky_solve(l: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let mut x = b.clone();
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
    solve_upper_triangular_in_place(l.transpose(), x.as_mut(), Par::Seq);
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The f32 product agrees with the f64 one to f32 rounding of the matrix, for a column
    /// count that is not a multiple of the lanes, and on both sides of the two-thread split.
    #[test]
    fn the_f32_product_matches_the_f64_product_to_f32_rounding() {
        for (rows, cols) in [(5, 3), (2000, 13), (1500, 64)] {
            let m: Vec<f64> = (0..rows * cols).map(|i| ((i * 7919) % 1000) as f64 / 500.0 - 1.0).collect();
            let x: Vec<f64> = (0..cols).map(|j| (j as f64 * 0.37).sin()).collect();
            let exact = RowMajor::F64(m.clone()).matvec_split(rows, cols, &x);
            let single = RowMajor::F64(m).stored(AdvectionStorage::F32);
            assert_eq!(single.storage(), AdvectionStorage::F32);
            let got = single.matvec_split(rows, cols, &x);
            let bound = cols as f64 * 2f64.powi(-24);
            for (r, (a, b)) in exact.iter().zip(&got).enumerate() {
                assert!((a - b).abs() <= bound, "row {r} of {rows}×{cols}: {a} vs {b}");
            }
        }
    }
}
