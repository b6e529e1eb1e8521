//! The matrix exponential (scaling and squaring with Padé, and Krylov `e^{tA}v`) against
//! nalgebra's `Matrix::exp` and closed forms.
//!
//! Tolerances: Padé 13 with Higham's θ bounds has backward error at the unit roundoff, so
//! for matrices of norm ≤ 10 the results agree with an independent implementation to about
//! `n·ε·e^{‖A‖}` — we allow 1e-12 relative to the largest entry; the badly scaled case
//! (entries from 1e-6 to 1e3) is compared relative to each entry's scale, 1e-9. Krylov is run
//! at tolerance 1e-12 and compared to 1e-10 of ‖v‖.
#![allow(clippy::needless_range_loop)]

use galerkin::tensor::{expm, expm_krylov, Tensor};
use nalgebra::DMatrix;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

fn random(n: usize, scale: f64, seed: u64) -> Tensor {
    let mut rng = Lcg(seed);
    Tensor::from_vec(&[n, n], (0..n * n).map(|_| scale * rng.next()).collect()).unwrap()
}

fn nalgebra_exp(a: &Tensor) -> Tensor {
    let n = a.shape()[0];
    let m = DMatrix::from_row_slice(n, n, a.data()).exp();
    Tensor::from_vec(&[n, n], (0..n * n).map(|k| m[(k / n, k % n)]).collect()).unwrap()
}

fn matmul(a: &Tensor, b: &Tensor) -> Tensor {
    galerkin::tensor::matmul(a, b).unwrap()
}

#[test]
fn pade_agrees_with_nalgebra_at_every_degree_and_with_scaling() {
    // Norms from 1e-3 (degree 3) to ~40 (degree 13 with squarings).
    for (k, scale) in [1e-3, 2e-2, 0.1, 0.3, 0.6, 1.5, 4.0, 10.0].into_iter().enumerate() {
        for n in [1, 2, 5, 17, 40] {
            let a = random(n, scale / (n as f64).sqrt(), 11 + k as u64 * 7 + n as u64);
            let ours = expm("A", &a).unwrap();
            let theirs = nalgebra_exp(&a);
            let err = ours.max_abs_diff(&theirs) / theirs.max_abs();
            assert!(err < 1e-12, "n {n} scale {scale}: relative difference {err:e}");
        }
    }
}

#[test]
fn closed_forms_rotation_skew_orthogonal_and_inverse() {
    // A rotation: exp([[0, −θ], [θ, 0]]) = [[cos θ, −sin θ], [sin θ, cos θ]].
    for theta in [0.0, 0.3, 2.0, 7.5, 40.0] {
        let a = Tensor::from_vec(&[2, 2], vec![0.0, -theta, theta, 0.0]).unwrap();
        let e = expm("rotation", &a).unwrap();
        let want = [theta.cos(), -theta.sin(), theta.sin(), theta.cos()];
        for (x, w) in e.data().iter().zip(want) {
            assert!((x - w).abs() < 1e-13 * (1.0 + theta), "θ {theta}: {x} vs {w}");
        }
    }
    // e^S orthogonal for skew S; e^A e^{−A} = I.
    for n in [3, 10, 30] {
        let m = random(n, 2.0, 5 + n as u64);
        let s = m.add_scaled(&galerkin::tensor::transpose(&m), -1.0).unwrap();
        let q = expm("skew", &s).unwrap();
        let qtq = matmul(&galerkin::tensor::transpose(&q), &q);
        assert!(qtq.max_abs_diff(&Tensor::identity(n)) < 1e-12, "e^S is not orthogonal");
        let a = random(n, 3.0 / (n as f64).sqrt(), 9 + n as u64);
        let (ea, ema) = (expm("A", &a).unwrap(), expm("-A", &a.scale(-1.0)).unwrap());
        let err = matmul(&ea, &ema).max_abs_diff(&Tensor::identity(n));
        // Rounding in the product itself is n·ε·‖e^A‖‖e^-A‖.
        let bound = 1e-13 * n as f64 * ea.max_abs() * ema.max_abs();
        assert!(err < bound, "n {n}: e^A e^-A − I = {err:e} > {bound:e}");
    }
}

#[test]
fn a_badly_scaled_matrix_is_exact_entry_by_entry() {
    // Upper triangular with entries spanning nine orders of magnitude: e^A in closed form
    // for the 2 × 2 case [[a, b], [0, c]] = [[e^a, b (e^a − e^c)/(a − c)], [0, e^c]].
    for (a, b, c) in [(1e-6, 1e3, -2.0), (3.0, 1e-6, -1e-3), (-20.0, 5e2, 1.0)] {
        let m = Tensor::from_vec(&[2, 2], vec![a, b, 0.0, c]).unwrap();
        let e = expm("badly scaled", &m).unwrap();
        let want = [a.exp(), b * (a.exp() - c.exp()) / (a - c), 0.0, c.exp()];
        for (x, w) in e.data().iter().zip(want) {
            assert!((x - w).abs() <= 1e-9 * w.abs().max(1e-300), "{x} vs {w} for ({a}, {b}, {c})");
        }
    }
    // A similarity by D = diag(10^i) of condition 1e7: e^{DAD⁻¹} = D e^A D⁻¹ exactly, so
    // every entry is known from the well-scaled e^A; we ask for each entry to 1e-9 of its
    // scale 10^(i−j)·max|e^A|.
    let n = 8;
    let a = random(n, 1.0, 3);
    let ea = expm("well scaled", &a).unwrap();
    let mut scaled = a.clone();
    for i in 0..n {
        for j in 0..n {
            scaled.set(&[i, j], a.get(&[i, j]) * 10f64.powi(i as i32 - j as i32));
        }
    }
    let ours = expm("badly scaled", &scaled).unwrap();
    for i in 0..n {
        for j in 0..n {
            let s = 10f64.powi(i as i32 - j as i32);
            let (x, want) = (ours.get(&[i, j]), s * ea.get(&[i, j]));
            assert!((x - want).abs() <= 1e-9 * s * ea.max_abs(), "({i}, {j}): {x} vs {want}");
        }
    }
}

#[test]
fn krylov_agrees_with_the_dense_exponential_and_contracts_dissipative_operators() {
    for (n, scale, t) in [(5, 1.0, 1.0), (60, 0.5, 3.0), (120, 2.0, 10.0), (30, 5.0, 100.0)] {
        let a = random(n, scale / (n as f64).sqrt(), 17 + n as u64);
        // Make it dissipative: A − AᵀA/‖A‖ has a negative semidefinite symmetric part after
        // subtracting the symmetric part of A and adding −BᵀB.
        let at = galerkin::tensor::transpose(&a);
        let skew = a.add_scaled(&at, -1.0).unwrap().scale(0.5);
        let damping = matmul(&at, &a).scale(-0.1);
        let op = skew.add_scaled(&damping, 1.0).unwrap();
        let v: Vec<f64> = (0..n).map(|i| ((i * 7 % 13) as f64 - 6.0) / 6.0).collect();
        let mut apply = |x: &[f64], y: &mut [f64]| {
            for i in 0..n {
                y[i] = (0..n).map(|j| op.get(&[i, j]) * x[j]).sum();
            }
        };
        let (w, report) = expm_krylov("op", &mut apply, &v, t, 1e-12).unwrap();
        let e = expm("t·op", &op.scale(t)).unwrap();
        let dense: Vec<f64> = (0..n).map(|i| (0..n).map(|j| e.get(&[i, j]) * v[j]).sum()).collect();
        let norm_v = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let err = w.iter().zip(&dense).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt() / norm_v;
        assert!(err < 1e-10, "n {n} t {t}: Krylov vs dense {err:e} ({report:?})");
        let norm_w = w.iter().map(|x| x * x).sum::<f64>().sqrt();
        assert!(norm_w <= norm_v * (1.0 + 1e-13), "the dissipative exponential grew: {norm_w} > {norm_v}");
    }
}

#[test]
fn bad_input_is_refused() {
    assert!(expm("not square", &Tensor::zeros(&[2, 3])).is_err());
    let nan = Tensor::from_vec(&[2, 2], vec![0.0, f64::NAN, 0.0, 0.0]).unwrap();
    assert!(expm("nan", &nan).is_err());
    let mut apply = |x: &[f64], y: &mut [f64]| y.copy_from_slice(x);
    assert!(expm_krylov("nan t", &mut apply, &[1.0, 2.0], f64::NAN, 1e-12).is_err());
}
