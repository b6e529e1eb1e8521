//! The radiosity equation (seed 000 Eq. 14), `b = (I − ρF)⁻¹ e`, per colour channel: directly
//! (LU, the reference for small scenes) and iteratively (Jacobi sweeps `b ← e + ρ F b`, what
//! the device runs). Jacobi converges because every row of `ρF` sums to at most
//! `max ρ < 1` (rows of `F` sum to at most 1, up to the centroid sampling's error).

use faer::linalg::solvers::Solve;
use faer::Mat;
use rayon::prelude::*;

use super::error::RadiosityError;
use super::form_factor::FormFactors;

/// RGB per face.
pub type Rgb = [f64; 3];

fn check(f: &FormFactors, albedo: &[Rgb], e: &[Rgb]) -> Result<(), RadiosityError> {
    if albedo.len() != f.n || e.len() != f.n {
        return Err(RadiosityError::Mesh(format!(
            "radiosity: {} albedos and {} emissions for {} faces",
            albedo.len(),
            e.len(),
            f.n
        )));
    }
    if let Some(i) = e.iter().position(|v| v.iter().any(|x| !x.is_finite())) {
        return Err(RadiosityError::NotFinite { what: format!("emission of face {i}") });
    }
    Ok(())
}

/// `b = (I − ρF)⁻¹ e` by LU with partial pivoting (one factorisation per channel).
pub fn solve_direct(f: &FormFactors, albedo: &[Rgb], e: &[Rgb]) -> Result<Vec<Rgb>, RadiosityError> {
    check(f, albedo, e)?;
    let n = f.n;
    let mut b = vec![[0.0; 3]; n];
    for c in 0..3 {
        let a = Mat::from_fn(n, n, |i, j| f64::from(u8::from(i == j)) - albedo[i][c] * f.values[i * n + j]);
        let lu = a.partial_piv_lu();
        let u = lu.U();
        if let Some(i) = (0..n).find(|&i| u[(i, i)].is_nan() || u[(i, i)].abs() <= 1e-12) {
            return Err(RadiosityError::Solve(format!("I − ρF is singular (channel {c}, pivot {i})")));
        }
        let rhs = Mat::from_fn(n, 1, |i, _| e[i][c]);
        let x = lu.solve(&rhs);
        for i in 0..n {
            b[i][c] = x[(i, 0)];
        }
    }
    Ok(b)
}

/// Jacobi sweeps `b ← e + ρ F b` from `b = e` until the largest change is at most
/// `tolerance · max|b|`; returns `b` and the number of sweeps. Fails (naming the residual) if
/// `max_sweeps` are not enough.
pub fn solve_jacobi(
    f: &FormFactors,
    albedo: &[Rgb],
    e: &[Rgb],
    tolerance: f64,
    max_sweeps: usize,
) -> Result<(Vec<Rgb>, usize), RadiosityError> {
    check(f, albedo, e)?;
    let n = f.n;
    let mut b = e.to_vec();
    for sweep in 1..=max_sweeps {
        let next: Vec<Rgb> = (0..n)
            .into_par_iter()
            .map(|i| {
                let row = f.row(i);
                let mut s = [0.0; 3];
                for (j, &fij) in row.iter().enumerate() {
                    if fij != 0.0 {
                        for c in 0..3 {
                            s[c] += fij * b[j][c];
                        }
                    }
                }
                [0, 1, 2].map(|c| e[i][c] + albedo[i][c] * s[c])
            })
            .collect();
        let change = next
            .iter()
            .zip(&b)
            .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
            .fold(0.0, f64::max);
        let top = next.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        b = next;
        if change <= tolerance * top {
            return Ok((b, sweep));
        }
        if !change.is_finite() {
            return Err(RadiosityError::Solve(format!("Jacobi diverged at sweep {sweep}")));
        }
    }
    Err(RadiosityError::Solve(format!("Jacobi did not converge to {tolerance:e} in {max_sweeps} sweeps")))
}
