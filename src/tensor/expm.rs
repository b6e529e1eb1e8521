//! The matrix exponential, two ways, for the reduced fluid's advection–diffusion step (seed 000
//! §6.2: "we integrate advection and diffusion by matrix exponentiation").
//!
//! - [`expm`]: `e^A` of a dense square matrix by scaling and squaring with the diagonal Padé
//!   approximants of degree 3, 5, 7, 9 or 13 (Higham 2005, "The scaling and squaring method for
//!   the matrix exponential revisited", Algorithm 2.3: the degree and the number of squarings
//!   `s` chosen from `‖A‖₁` against the θ_m bounds of its Table 2.3, so the backward error is
//!   at most the unit roundoff).
//! - [`expm_krylov`]: `e^{tA} v` without forming `e^{tA}`, by the Arnoldi process
//!   (Saad 1992; Expokit's `expv`, Sidje 1998): `e^{tA} v ≈ β V_k e^{t H_k} e₁` with the
//!   Arnoldi basis `V_k` and Hessenberg `H_k = V_kᵀ A V_k`, time-stepped when one Krylov space
//!   does not reach the tolerance. When the symmetric part of `A` is negative semidefinite, so
//!   is that of every `H_k`, so every step is a contraction: `‖e^{tA} v‖ ≤ ‖v‖` holds for the
//!   approximation too, for any `t` — the energy property of §A.2 survives the approximation.

use faer::linalg::solvers::Solve;
use faer::Mat;

use super::dense::Tensor;
use super::error::TensorError;
use super::linalg::dot;

/// Padé coefficients b₀ … b_m (Higham 2005, Table 2.3's degrees).
const PADE3: [f64; 4] = [120.0, 60.0, 12.0, 1.0];
const PADE5: [f64; 6] = [30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0];
const PADE7: [f64; 8] = [17297280.0, 8648640.0, 1995840.0, 277200.0, 25200.0, 1512.0, 56.0, 1.0];
const PADE9: [f64; 10] = [
    17643225600.0,
    8821612800.0,
    2075673600.0,
    302702400.0,
    30270240.0,
    2162160.0,
    110880.0,
    3960.0,
    90.0,
    1.0,
];
const PADE13: [f64; 14] = [
    64764752532480000.0,
    32382376266240000.0,
    7771770303897600.0,
    1187353796428800.0,
    129060195264000.0,
    10559470521600.0,
    670442572800.0,
    33522128640.0,
    1323241920.0,
    40840800.0,
    960960.0,
    16380.0,
    182.0,
    1.0,
];
/// θ_m of Higham 2005 Table 2.3: the largest ‖A‖₁ for which degree m needs no scaling.
#[allow(clippy::excessive_precision)] // Higham's table, digit for digit.
const THETA: [(usize, f64); 5] = [
    (3, 1.495585217958292e-2),
    (5, 2.539398330063230e-1),
    (7, 9.504178996162932e-1),
    (9, 2.097847961257068e0),
    (13, 5.371920351148152e0),
];

fn to_faer(m: &Tensor) -> Mat<f64> {
    let n = m.shape()[1];
    Mat::from_fn(m.shape()[0], n, |i, j| m.data()[i * n + j])
}

fn norm1(a: &Mat<f64>) -> f64 {
    (0..a.ncols()).map(|j| (0..a.nrows()).map(|i| a[(i, j)].abs()).sum::<f64>()).fold(0.0, f64::max)
}

/// `e^A` of a square matrix `a` (see the module docs). Refuses non-square or non-finite input.
pub fn expm(what: &str, a: &Tensor) -> Result<Tensor, TensorError> {
    let n = match a.shape() {
        [r, c] if r == c => *r,
        s => return Err(TensorError::NotSquare { what: what.into(), shape: s.to_vec() }),
    };
    if let Some(i) = a.data().iter().position(|v| !v.is_finite()) {
        return Err(TensorError::NotFinite {
            what: what.into(),
            detail: format!("element {i} is not finite"),
        });
    }
    let e = expm_faer(what, &to_faer(a))?;
    let mut data = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            data.push(e[(i, j)]);
        }
    }
    Tensor::from_vec(&[n, n], data)
}

/// [`expm`] on a faer matrix (finite and square: the caller checks). The matrix is balanced
/// first (a diagonal similarity by powers of two, Parlett & Reinsch 1969, as LAPACK's gebal):
/// `e^A = D e^{D⁻¹AD} D⁻¹` exactly, and a badly scaled A no longer inflates ‖A‖₁ into
/// needless squarings, whose rounding grows with their number (Higham 2005 §6, overscaling).
pub fn expm_faer(what: &str, a: &Mat<f64>) -> Result<Mat<f64>, TensorError> {
    let (b, d) = balance(a);
    let mut e = expm_balanced(what, &b)?;
    let n = a.nrows();
    for i in 0..n {
        for j in 0..n {
            e[(i, j)] *= d[i] / d[j];
        }
    }
    Ok(e)
}

/// `(D⁻¹AD, diag D)` with D a power of two per row, balancing off-diagonal row and column norms.
fn balance(a: &Mat<f64>) -> (Mat<f64>, Vec<f64>) {
    let n = a.nrows();
    let mut b = a.clone();
    let mut d = vec![1.0f64; n];
    for _sweep in 0..100 {
        let mut converged = true;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&j| j != i).map(|j| b[(j, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&j| j != i).map(|j| b[(i, j)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let (mut cc, mut rr, mut f) = (c, r, 1.0f64);
            let s = c + r;
            while cc < rr / 2.0 {
                cc *= 2.0;
                rr /= 2.0;
                f *= 2.0;
            }
            while cc >= rr * 2.0 {
                cc /= 2.0;
                rr *= 2.0;
                f /= 2.0;
            }
            if (cc + rr) < 0.95 * s {
                converged = false;
                d[i] *= f;
                for j in 0..n {
                    b[(i, j)] /= f;
                    b[(j, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
    (b, d)
}

fn expm_balanced(what: &str, a: &Mat<f64>) -> Result<Mat<f64>, TensorError> {
    let n = a.nrows();
    let eye = Mat::<f64>::identity(n, n);
    let norm = norm1(a);
    for &(m, theta) in &THETA[..4] {
        if norm <= theta {
            let b: &[f64] = match m {
                3 => &PADE3,
                5 => &PADE5,
                7 => &PADE7,
                _ => &PADE9,
            };
            return pade_low(what, a, b, &eye);
        }
    }
    let s = if norm > THETA[4].1 { (norm / THETA[4].1).log2().ceil().max(0.0) as i32 } else { 0 };
    let scaled = a * faer::Scale(0.5f64.powi(s));
    let mut r = pade13(what, &scaled, &eye)?;
    for _ in 0..s {
        r = &r * &r;
    }
    Ok(r)
}

/// `r_m(A) = (V − U)⁻¹ (V + U)` for m ∈ {3, 5, 7, 9}: U the odd part, V the even part.
fn pade_low(what: &str, a: &Mat<f64>, b: &[f64], eye: &Mat<f64>) -> Result<Mat<f64>, TensorError> {
    let a2 = a * a;
    let mut power = eye.clone();
    let mut odd = eye * faer::Scale(b[1]);
    let mut even = eye * faer::Scale(b[0]);
    for j in 1..b.len() / 2 {
        power = &power * &a2;
        odd += &power * faer::Scale(b[2 * j + 1]);
        even += &power * faer::Scale(b[2 * j]);
    }
    let u = a * &odd;
    finish(what, &u, &even)
}

/// Degree 13 with A², A⁴, A⁶ only (Higham 2005, Eq. 2.2's grouping: six products in all).
fn pade13(what: &str, a: &Mat<f64>, eye: &Mat<f64>) -> Result<Mat<f64>, TensorError> {
    let b = &PADE13;
    let a2 = a * a;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let s = |m: &Mat<f64>, c: f64| m * faer::Scale(c);
    let inner_u = s(&a6, b[13]) + s(&a4, b[11]) + s(&a2, b[9]);
    let u = a * (&a6 * &inner_u + s(&a6, b[7]) + s(&a4, b[5]) + s(&a2, b[3]) + s(eye, b[1]));
    let inner_v = s(&a6, b[12]) + s(&a4, b[10]) + s(&a2, b[8]);
    let v = &a6 * &inner_v + s(&a6, b[6]) + s(&a4, b[4]) + s(&a2, b[2]) + s(eye, b[0]);
    finish(what, &u, &v)
}

fn finish(what: &str, u: &Mat<f64>, v: &Mat<f64>) -> Result<Mat<f64>, TensorError> {
    let p = v + u;
    let q = v - u;
    let lu = q.partial_piv_lu();
    let r = lu.solve(&p);
    if (0..r.nrows()).any(|i| (0..r.ncols()).any(|j| !r[(i, j)].is_finite())) {
        return Err(TensorError::NotFinite {
            what: what.into(),
            detail: "the Padé denominator is singular".into(),
        });
    }
    Ok(r)
}

/// What [`expm_krylov`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KrylovReport {
    /// Time steps taken (one when a single Krylov space reached the tolerance).
    pub steps: usize,
    /// Matrix–vector products.
    pub products: usize,
}

/// Largest Krylov space [`expm_krylov`] builds per time step.
pub const KRYLOV_MAX_DIM: usize = 40;
/// [`expm_krylov`] checks whether its Krylov space is large enough every this many dimensions.
pub const KRYLOV_CHECK_EVERY: usize = 4;
/// Cap on [`expm_krylov`]'s time steps (each at least `t / KRYLOV_MAX_STEPS`).
pub const KRYLOV_MAX_STEPS: usize = 10_000;

/// `e^{tA} v` for the operator `apply(x, y)` (`y = A x`, n = `v.len()`) by Arnoldi with time
/// stepping (see the module docs): each step's local error estimate
/// `β τ h_{k+1,k} |[e^{τH_k}]_{k,1}|` (Saad 1992's a-posteriori estimate, the first
/// neglected term) is held below `tol · ‖v‖ · τ / t`.
pub fn expm_krylov(
    what: &str,
    apply: &mut dyn FnMut(&[f64], &mut [f64]),
    v: &[f64],
    t: f64,
    tol: f64,
) -> Result<(Vec<f64>, KrylovReport), TensorError> {
    let n = v.len();
    let mut report = KrylovReport::default();
    let mut w = v.to_vec();
    let beta0 = norm2(&w);
    if beta0 == 0.0 || t == 0.0 {
        return Ok((w, report));
    }
    if !(t.is_finite() && beta0.is_finite() && tol > 0.0) {
        return Err(TensorError::NotFinite {
            what: what.into(), detail: format!("t = {t}, ‖v‖ = {beta0}")
        });
    }
    let kmax = KRYLOV_MAX_DIM.min(n);
    let mut done = 0.0;
    let mut tau = t;
    let mut basis: Vec<Vec<f64>> = Vec::with_capacity(kmax + 1);
    let mut y = vec![0.0; n];
    while done < t {
        if report.steps >= KRYLOV_MAX_STEPS {
            return Err(TensorError::NotFinite {
                what: what.into(),
                detail: format!("e^(tA)v did not converge in {KRYLOV_MAX_STEPS} time steps"),
            });
        }
        let beta = norm2(&w);
        if beta == 0.0 {
            break;
        }
        basis.clear();
        basis.push(w.iter().map(|x| x / beta).collect());
        let mut h = Mat::<f64>::zeros(kmax + 1, kmax + 1);
        let mut k = 0;
        let mut breakdown = false;
        while k < kmax {
            apply(&basis[k], &mut y);
            report.products += 1;
            // Modified Gram–Schmidt, twice (the second pass is cheap at these sizes).
            for _ in 0..2 {
                for (i, q) in basis.iter().enumerate() {
                    let c = dot(q, &y);
                    h[(i, k)] += c;
                    y.iter_mut().zip(q).for_each(|(a, b)| *a -= c * b);
                }
            }
            let norm = norm2(&y);
            h[(k + 1, k)] = norm;
            k += 1;
            if norm <= 1e-14 * beta.max(1.0) * (1.0 + h[(k - 1, k - 1)].abs()) {
                breakdown = true;
                break;
            }
            basis.push(y.iter().map(|x| x / norm).collect());
            // Stop growing the space once this step's error estimate already passes
            // (checked every few dimensions: each check exponentiates the k × k Hessenberg).
            if k % KRYLOV_CHECK_EVERY == 0 && k < kmax {
                let tau_try = tau.min(t - done);
                let hk = Mat::from_fn(k, k, |i, j| tau_try * h[(i, j)]);
                let e = expm_faer(what, &hk)?;
                let err = beta * tau_try * h[(k, k - 1)] * e[(k - 1, 0)].abs();
                if err <= tol * beta0 * tau_try / t {
                    break;
                }
            }
        }
        // Shrink τ until the error estimate passes (an invariant subspace is exact).
        let remaining = t - done;
        tau = tau.min(remaining);
        loop {
            let hk = Mat::from_fn(k, k, |i, j| tau * h[(i, j)]);
            let e = expm_faer(what, &hk)?;
            let err = if breakdown { 0.0 } else { beta * tau * h[(k, k - 1)] * e[(k - 1, 0)].abs() };
            let allowed = tol * beta0 * tau / t;
            if err <= allowed || tau <= t / KRYLOV_MAX_STEPS as f64 {
                w.iter_mut().for_each(|x| *x = 0.0);
                for (j, q) in basis.iter().take(k).enumerate() {
                    let c = beta * e[(j, 0)];
                    w.iter_mut().zip(q).for_each(|(a, b)| *a += c * b);
                }
                done += tau;
                report.steps += 1;
                // Grow the next step when this one was easy (Expokit's safety factor 0.9).
                if err < 0.5 * allowed {
                    let ratio = if err > 0.0 { (allowed / err).powf(1.0 / k as f64) } else { 2.0 };
                    tau *= (0.9 * ratio).clamp(1.0, 2.0);
                }
                break;
            }
            tau *= 0.5;
        }
    }
    Ok((w, report))
}

fn norm2(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}
