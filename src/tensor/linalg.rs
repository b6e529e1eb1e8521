//! Small dense matrix operations in f64, through faer: the matrix inverse of §4 (ii) applied as
//! a solve — never an explicit inverse where a solve will do — and the SPD matrix powers of
//! §4 (iii), `Q^(1/n)` and `Q^(-1/2)`, by symmetric eigendecomposition.

use faer::linalg::solvers::Solve;
use faer::Mat;

use super::dense::Tensor;
use super::error::TensorError;

fn square(what: &str, m: &Tensor) -> Result<usize, TensorError> {
    match m.shape() {
        [a, b] if a == b => Ok(*a),
        s => Err(TensorError::NotSquare { what: what.into(), shape: s.to_vec() }),
    }
}

/// Checks that `q x = b` is a square system with finite values; returns `n`. Shared by the
/// CPU solve and the device's batched solve ([`crate::tensor::gpu::BatchedSolve`]).
pub(crate) fn check_system(what: &str, q: &Tensor, b: &[f64]) -> Result<usize, TensorError> {
    let n = square(what, q)?;
    q.expect_axis(what, 1, b.len())?;
    if let Some(i) = q.data().iter().chain(b).position(|v| !v.is_finite()) {
        return Err(TensorError::NotFinite {
            what: what.into(),
            detail: format!("element {i} is not finite"),
        });
    }
    Ok(n)
}

/// The magnitude at or below which an LU pivot of `q` counts as zero at working precision
/// `epsilon`: `n·ε·max|q|`.
pub(crate) fn pivot_tolerance(q: &Tensor, epsilon: f64) -> f64 {
    q.shape()[0] as f64 * epsilon * q.max_abs().max(f64::MIN_POSITIVE)
}

fn to_faer(m: &Tensor) -> Mat<f64> {
    let (r, c) = (m.shape()[0], m.shape()[1]);
    Mat::from_fn(r, c, |i, j| m.data()[i * c + j])
}

fn from_faer(m: faer::MatRef<'_, f64>) -> Tensor {
    let (r, c) = (m.nrows(), m.ncols());
    let mut data = Vec::with_capacity(r * c);
    for i in 0..r {
        for j in 0..c {
            data.push(m[(i, j)]);
        }
    }
    Tensor::from_vec(&[r, c], data).expect("shape matches")
}

/// `Q⁻¹ b`: solves `Q y = b` by LU with partial pivoting. A pivot below `n·ε·max|Q|` is
/// reported as [`TensorError::Singular`].
pub fn solve(what: &str, q: &Tensor, b: &[f64]) -> Result<Vec<f64>, TensorError> {
    let mut x = solve_many(what, q, &[b])?;
    Ok(x.pop().expect("one right-hand side"))
}

/// [`solve`] for several right-hand sides with one factorisation.
pub fn solve_many(what: &str, q: &Tensor, rhs: &[&[f64]]) -> Result<Vec<Vec<f64>>, TensorError> {
    let mut n = square(what, q)?;
    for b in rhs {
        n = check_system(what, q, b)?;
    }
    let a = to_faer(q);
    let lu = a.partial_piv_lu();
    let tolerance = pivot_tolerance(q, f64::EPSILON);
    let u = lu.U();
    for i in 0..n {
        if u[(i, i)].abs() <= tolerance {
            return Err(TensorError::Singular { what: what.into(), row: i, pivot: u[(i, i)] });
        }
    }
    let b = Mat::from_fn(n, rhs.len(), |i, j| rhs[j][i]);
    let y = lu.solve(&b);
    Ok((0..rhs.len()).map(|j| (0..n).map(|i| y[(i, j)]).collect()).collect())
}

/// Eigenvalues (ascending) and eigenvectors (columns) of the symmetric part of `q`.
pub fn symmetric_eigen(what: &str, q: &Tensor) -> Result<(Vec<f64>, Tensor), TensorError> {
    let n = square(what, q)?;
    let a = Mat::from_fn(n, n, |i, j| 0.5 * (q.data()[i * n + j] + q.data()[j * n + i]));
    // Reduced models decompose small matrices many times a second: threads cost more than
    // they save below a few hundred rows.
    let par = if n < 256 { faer::Par::Seq } else { faer::get_global_parallelism() };
    let mut u = Mat::<f64>::zeros(n, n);
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let scratch = faer::linalg::evd::self_adjoint_evd_scratch::<f64>(
        n,
        faer::linalg::evd::ComputeEigenvectors::Yes,
        par,
        Default::default(),
    );
    faer::linalg::evd::self_adjoint_evd(
        a.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        par,
        faer::dyn_stack::MemStack::new(&mut faer::dyn_stack::MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|e| TensorError::NotFinite {
        what: what.into(),
        detail: format!("eigendecomposition failed: {e:?}"),
    })?;
    let s = s.column_vector();
    let values = (0..n).map(|i| s[i]).collect();
    Ok((values, from_faer(u.as_ref())))
}

/// `Q^p` of a symmetric positive semidefinite `q` (positive definite when `p < 0`), by
/// eigendecomposition: `U diag(λᵢ^p) Uᵀ`. With `p = 1/n` this is the unique PSD n-th root of
/// §4 (iii); with `p = -1/2` the inverse square root. Eigenvalues down to
/// `-n·ε·max|λ|` count as zero; anything more negative is [`TensorError::NotSpd`].
pub fn spd_power(what: &str, q: &Tensor, p: f64) -> Result<Tensor, TensorError> {
    let n = square(what, q)?;
    let (values, u) = symmetric_eigen(what, q)?;
    let top = values.iter().fold(0f64, |m, v| m.max(v.abs()));
    let floor = n as f64 * f64::EPSILON * top;
    let mut powered = Vec::with_capacity(n);
    for &l in &values {
        if l < -floor || (p < 0.0 && l <= floor) {
            let kind = if p < 0.0 { "definite" } else { "semidefinite" };
            return Err(TensorError::NotSpd { what: what.into(), kind, eigenvalue: l });
        }
        powered.push(if l <= floor { 0.0 } else { l.powf(p) });
    }
    let mut out = Tensor::zeros(&[n, n]);
    for i in 0..n {
        for j in 0..n {
            let v: f64 = (0..n).map(|k| u.data()[i * n + k] * powered[k] * u.data()[j * n + k]).sum();
            out.set(&[i, j], v);
        }
    }
    Ok(out)
}

/// `Q^p x` for a symmetric positive (semi)definite `q` without forming `Q^p`:
/// `U diag(λᵢ^p) Uᵀ x`, `O(n²)` after the eigendecomposition instead of `O(n³)`. The same
/// eigenvalue rules as [`spd_power`].
pub fn spd_power_apply(what: &str, q: &Tensor, p: f64, x: &[f64]) -> Result<Vec<f64>, TensorError> {
    let n = square(what, q)?;
    q.expect_axis(what, 1, x.len())?;
    let (values, u) = symmetric_eigen(what, q)?;
    let top = values.iter().fold(0f64, |m, v| m.max(v.abs()));
    let floor = n as f64 * f64::EPSILON * top;
    let ud = u.data();
    let mut coeff = vec![0.0; n];
    for (k, &l) in values.iter().enumerate() {
        if l < -floor || (p < 0.0 && l <= floor) {
            let kind = if p < 0.0 { "definite" } else { "semidefinite" };
            return Err(TensorError::NotSpd { what: what.into(), kind, eigenvalue: l });
        }
        let lp = if l <= floor { 0.0 } else { l.powf(p) };
        let dot: f64 = (0..n).map(|i| ud[i * n + k] * x[i]).sum();
        coeff[k] = lp * dot;
    }
    Ok((0..n).map(|i| (0..n).map(|k| ud[i * n + k] * coeff[k]).sum()).collect())
}

/// Matrix product `a · b` (plain triple loop: a reference, not a fast path).
pub fn matmul(a: &Tensor, b: &Tensor) -> Result<Tensor, TensorError> {
    if a.order() != 2 || b.order() != 2 {
        return Err(TensorError::NotSquare { what: "matmul operand".into(), shape: a.shape().to_vec() });
    }
    b.expect_axis("matmul", 0, a.shape()[1])?;
    let (r, k, c) = (a.shape()[0], a.shape()[1], b.shape()[1]);
    let mut out = vec![0.0; r * c];
    for i in 0..r {
        for l in 0..k {
            let ail = a.data()[i * k + l];
            for j in 0..c {
                out[i * c + j] += ail * b.data()[l * c + j];
            }
        }
    }
    Tensor::from_vec(&[r, c], out)
}

/// The transpose of a matrix.
pub fn transpose(a: &Tensor) -> Tensor {
    assert_eq!(a.order(), 2, "transpose of a non-matrix");
    a.permute(&[1, 0])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spd(n: usize) -> Tensor {
        // A = Mᵀ M + n I for a fixed M.
        let m = Tensor::from_vec(&[n, n], (0..n * n).map(|i| ((i * 37 % 11) as f64 - 5.0) / 7.0).collect())
            .unwrap();
        let mut a = matmul(&transpose(&m), &m).unwrap();
        for i in 0..n {
            let v = a.get(&[i, i]) + n as f64;
            a.set(&[i, i], v);
        }
        a
    }

    #[test]
    fn solve_inverts() {
        let a = spd(6);
        let b: Vec<f64> = (0..6).map(|i| i as f64 - 2.5).collect();
        let y = solve("A", &a, &b).unwrap();
        let back = a.contract(1, &y).unwrap();
        assert!(back.data().iter().zip(&b).all(|(u, v)| (u - v).abs() < 1e-12));
        let singular = Tensor::from_vec(&[2, 2], vec![1.0, 2.0, 2.0, 4.0]).unwrap();
        assert!(matches!(solve("S", &singular, &[1.0, 1.0]), Err(TensorError::Singular { .. })));
    }

    #[test]
    fn roots_are_spd_and_power_back() {
        let a = spd(5);
        let r = spd_power("A", &a, 1.0 / 3.0).unwrap();
        assert!(r.max_abs_diff(&transpose(&r)) < 1e-12);
        let cube = matmul(&matmul(&r, &r).unwrap(), &r).unwrap();
        assert!(cube.max_abs_diff(&a) < 1e-10 * a.max_abs());
        let is = spd_power("A", &a, -0.5).unwrap();
        let x: Vec<f64> = (0..5).map(|i| i as f64 - 1.5).collect();
        let applied = spd_power_apply("A", &a, -0.5, &x).unwrap();
        let formed = is.contract(1, &x).unwrap();
        assert!(applied.iter().zip(formed.data()).all(|(p, q)| (p - q).abs() < 1e-12));
        let id = matmul(&matmul(&is, &a).unwrap(), &is).unwrap();
        assert!(id.max_abs_diff(&Tensor::identity(5)) < 1e-12);
        let indefinite = Tensor::from_vec(&[2, 2], vec![1.0, 0.0, 0.0, -1.0]).unwrap();
        assert!(matches!(spd_power("I", &indefinite, 0.5), Err(TensorError::NotSpd { .. })));
    }
}
