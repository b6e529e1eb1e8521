//! Conjugate gradients preconditioned by smoothed-aggregation algebraic multigrid (Vaněk,
//! Mandel & Brezina 1996), for large sparse symmetric positive semidefinite systems whose
//! values change every frame — the fluid projection's face system — where a sparse Cholesky
//! would have to be refactorised every frame at a cost growing much faster than the size.
//!
//! Setup, per matrix: rows are grouped into aggregates of strongly connected neighbours
//! (`|a_ij| > θ √(a_ii a_jj)`); the tentative prolongation `T` restricts the near-null vector
//! `b` (the constants, for a Laplacian-like matrix) to each aggregate, normalised; the
//! prolongation is `P = (I − ω D⁻¹A) T` with `ω = 4 / (3 ρ(D⁻¹A))`, and the coarse matrix is
//! `Pᵀ A P`, recursively until at most [`COARSE_SIZE`] rows remain, which are factorised
//! densely. When `b` spans the matrix's kernel exactly ([`Kernel::Exact`]), `P` maps the
//! coarse kernel vector onto it (`A T b_c = A b = 0`), so every level keeps a one-dimensional
//! kernel per connected component; the coarsest solve adds `α b bᵀ / ‖b‖²` on each component
//! and so returns the solution orthogonal to the kernel of a consistent right-hand side.
//! Where too few connections are strong to coarsen, every connection counts; a matrix that
//! still cannot coarsen (nearly diagonal) above a few thousand rows is refused rather than
//! factorised densely.
//!
//! One V-cycle (a forward Gauss–Seidel sweep before the coarse correction, a backward one
//! after: a symmetric preconditioner) preconditions each CG step.

// Graph passes index several per-row arrays by the same row.
#![allow(clippy::needless_range_loop)]

use faer::linalg::solvers::Solve;
use faer::{Mat, Side};

use super::csr::CsrMatrix;
use super::error::TensorError;
use super::linalg::dot;

/// The coarsest level is solved densely once it has at most this many rows.
pub const COARSE_SIZE: usize = 400;
/// Most rows of a coarsest level that stalled above [`COARSE_SIZE`] (its dense factor's
/// memory grows as the square).
const DENSE_MAX: usize = 4000;
/// Most levels (the coarsening stops earlier when it stalls).
const MAX_LEVELS: usize = 25;
/// Strength of connection on the finest level; halved on each coarser one.
const STRENGTH: f64 = 0.08;
/// Power iterations estimating ρ(D⁻¹A) for the prolongation smoother.
const POWER_STEPS: usize = 15;

/// How the near-null vector relates to the matrix.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// `A b = 0` exactly on every connected component (A is only semidefinite): solutions are
    /// defined up to a multiple of `b` per component and right-hand sides must be orthogonal
    /// to them.
    Exact,
    /// `A` is definite and `b` only nearly in its kernel (the smoothest mode).
    Near,
}

struct Level {
    /// The level's matrix (`None` on the finest level: the caller's).
    a: Option<CsrMatrix>,
    inv_diag: Vec<f64>,
    /// Prolongation from the next level, and its transpose (the restriction).
    p: CsrMatrix,
    r: CsrMatrix,
}

/// A smoothed-aggregation hierarchy for one matrix.
pub struct Amg {
    levels: Vec<Level>,
    /// The coarsest matrix's dense factor (the only level when the matrix is small), deflated
    /// on the kernel where that is exact.
    coarse: faer::linalg::solvers::Llt<f64>,
    coarse_n: usize,
    fine_n: usize,
    entries: usize,
    /// The kernel vector, normalised, where it is exact: conjugate gradients keep their
    /// residuals and preconditioned residuals orthogonal to it (rounding would otherwise
    /// feed the kernel until the iteration stalls).
    kernel: Option<Vec<f64>>,
}

impl std::fmt::Debug for Amg {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Amg").field("rows", &self.level_sizes()).finish()
    }
}

/// Forward (or backward) Gauss–Seidel sweep on `A x = b`.
fn gauss_seidel(a: &CsrMatrix, inv_diag: &[f64], b: &[f64], x: &mut [f64], backward: bool) {
    let mut relax = |i: usize| {
        let (cols, vals) = a.row(i);
        let s: f64 = cols.iter().zip(vals).map(|(&c, v)| v * x[c]).sum();
        x[i] += (b[i] - s) * inv_diag[i];
    };
    if backward {
        (0..a.rows()).rev().for_each(&mut relax);
    } else {
        (0..a.rows()).for_each(&mut relax);
    }
}

/// Groups the rows into aggregates (Vaněk et al.'s three passes); the aggregate of each row
/// and the number of aggregates.
fn aggregate(a: &CsrMatrix, theta: f64) -> (Vec<usize>, usize) {
    const NONE: usize = usize::MAX;
    let n = a.rows();
    let diag: Vec<f64> = a.diagonal().iter().map(|d| d.abs()).collect();
    let diag = &diag;
    let strong = |i: usize| {
        let (cols, vals) = a.row(i);
        cols.iter()
            .zip(vals)
            .filter(move |&(&j, &v)| j != i && v != 0.0 && v.abs() > theta * (diag[i] * diag[j]).sqrt())
            .map(|(&j, &v)| (j, v.abs()))
    };
    let mut agg = vec![NONE; n];
    let mut count = 0;
    // 1: a row whose strong neighbours are all free seeds an aggregate of its neighbourhood.
    for i in 0..n {
        if agg[i] == NONE && strong(i).next().is_some() && strong(i).all(|(j, _)| agg[j] == NONE) {
            agg[i] = count;
            for (j, _) in strong(i) {
                agg[j] = count;
            }
            count += 1;
        }
    }
    // 2: a free row joins the aggregate of its strongest aggregated neighbour.
    let first = agg.clone();
    for i in 0..n {
        if agg[i] == NONE {
            let best =
                strong(i).filter(|&(j, _)| first[j] != NONE).fold(None, |b: Option<(usize, f64)>, (j, v)| {
                    if b.is_none_or(|(_, w)| v > w) {
                        Some((j, v))
                    } else {
                        b
                    }
                });
            if let Some((j, _)) = best {
                agg[i] = first[j];
            }
        }
    }
    // 3: what is left seeds aggregates with its free strong neighbours (or alone).
    for i in 0..n {
        if agg[i] == NONE {
            agg[i] = count;
            for (j, _) in strong(i) {
                if agg[j] == NONE {
                    agg[j] = count;
                }
            }
            count += 1;
        }
    }
    (agg, count)
}

/// ρ(D⁻¹A) by power iteration (from below: the estimate is a Rayleigh-type quotient).
fn spectral_radius(a: &CsrMatrix, inv_diag: &[f64]) -> f64 {
    let n = a.rows();
    let mut x: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * ((i as f64) * 0.618_033_988_75).fract()).collect();
    let mut rho = 0.0;
    let mut y = vec![0.0; n];
    for _ in 0..POWER_STEPS {
        a.mul_into(&x, &mut y);
        for (yi, d) in y.iter_mut().zip(inv_diag) {
            *yi *= d;
        }
        let norm = dot(&y, &y).sqrt();
        let xn = dot(&x, &x).sqrt();
        if norm == 0.0 || xn == 0.0 {
            break;
        }
        rho = norm / xn;
        for (xi, yi) in x.iter_mut().zip(&y) {
            *xi = yi / norm;
        }
    }
    rho
}

/// Connected components of a symmetric matrix's graph: the component of each row and their
/// number.
fn components(a: &CsrMatrix) -> (Vec<usize>, usize) {
    const NONE: usize = usize::MAX;
    let mut comp = vec![NONE; a.rows()];
    let mut count = 0;
    let mut stack = Vec::new();
    for s in 0..a.rows() {
        if comp[s] != NONE {
            continue;
        }
        comp[s] = count;
        stack.push(s);
        while let Some(i) = stack.pop() {
            let (cols, vals) = a.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                if v != 0.0 && comp[j] == NONE {
                    comp[j] = count;
                    stack.push(j);
                }
            }
        }
        count += 1;
    }
    (comp, count)
}

impl Amg {
    /// The hierarchy of the symmetric positive (semi)definite matrix `fine` with near-null
    /// vector `near_null`.
    pub fn new(fine: &CsrMatrix, near_null: &[f64], kernel: Kernel) -> Result<Self, TensorError> {
        let a = fine;
        assert_eq!(a.rows(), a.cols(), "a square matrix");
        assert_eq!(near_null.len(), a.rows(), "one near-null entry per row");
        if let Some(i) = a.values().iter().position(|v| !v.is_finite()) {
            return Err(TensorError::NotFinite {
                what: "multigrid matrix".into(),
                detail: format!("entry {i}"),
            });
        }
        let fine_n = a.rows();
        let mut levels = Vec::new();
        let mut owned: Option<CsrMatrix> = None;
        let mut entries = 0;
        let mut b = near_null.to_vec();
        let mut theta = STRENGTH;
        loop {
            let a = owned.as_ref().unwrap_or(fine);
            if a.rows() <= COARSE_SIZE || levels.len() >= MAX_LEVELS {
                break;
            }
            let diag = a.diagonal();
            if let Some(i) = diag.iter().position(|&d| d <= 0.0) {
                return Err(TensorError::Factorisation {
                    what: "multigrid setup".into(),
                    detail: format!(
                        "level {} row {i} has diagonal {:e} (not positive)",
                        levels.len(),
                        diag[i]
                    ),
                });
            }
            let inv_diag: Vec<f64> = diag.iter().map(|d| 1.0 / d).collect();
            let (mut agg, mut count) = aggregate(a, theta);
            if count as f64 > 0.85 * a.rows() as f64 {
                // Too few strong connections to coarsen: every connection counts.
                (agg, count) = aggregate(a, 0.0);
                if count as f64 > 0.85 * a.rows() as f64 {
                    break;
                }
            }
            let mut norm2 = vec![0.0; count];
            for (i, &g) in agg.iter().enumerate() {
                norm2[g] += b[i] * b[i];
            }
            let b_coarse: Vec<f64> = norm2.iter().map(|v| v.sqrt()).collect();
            let tentative: Vec<(usize, usize, f64)> = agg
                .iter()
                .enumerate()
                .map(|(i, &g)| (i, g, if b_coarse[g] > 0.0 { b[i] / b_coarse[g] } else { 0.0 }))
                .collect();
            let t = CsrMatrix::from_triplets(a.rows(), count, &tentative);
            let omega = 4.0 / 3.0 / spectral_radius(a, &inv_diag).max(f64::MIN_POSITIVE);
            // P = T − ω D⁻¹ A T; A T has T's pattern (the diagonal is stored).
            let mut p = a.matmul(&t);
            for i in 0..p.rows() {
                let (cols, vals) = p.row_mut(i);
                let own = cols.binary_search(&agg[i]).ok();
                for v in vals.iter_mut() {
                    *v *= -omega * inv_diag[i];
                }
                if let Some(k) = own {
                    vals[k] += tentative[i].2;
                }
            }
            let r = p.transpose();
            let coarse = r.matmul(&a.matmul(&p));
            entries += a.nnz() + 2 * p.nnz();
            levels.push(Level { a: owned.take(), inv_diag, p, r });
            owned = Some(coarse);
            b = b_coarse;
            theta *= 0.5;
        }
        let a = owned.as_ref().unwrap_or(fine);
        let n = a.rows();
        if n > DENSE_MAX {
            return Err(TensorError::Factorisation {
                what: "multigrid setup".into(),
                detail: format!(
                    "coarsening stalled at {n} rows (a matrix with almost no off-diagonal entries)"
                ),
            });
        }
        let mut dense = Mat::<f64>::zeros(n, n);
        for i in 0..n {
            let (cols, vals) = a.row(i);
            for (&j, &v) in cols.iter().zip(vals) {
                dense[(i, j)] += v;
            }
        }
        if kernel == Kernel::Exact {
            let (comp, count) = components(a);
            let alpha = (0..n).map(|i| dense[(i, i)].abs()).sum::<f64>() / n.max(1) as f64;
            let mut norm2 = vec![0.0; count];
            for i in 0..n {
                norm2[comp[i]] += b[i] * b[i];
            }
            for i in 0..n {
                for j in 0..n {
                    if comp[i] == comp[j] && norm2[comp[i]] > 0.0 {
                        dense[(i, j)] += alpha * b[i] * b[j] / norm2[comp[i]];
                    }
                }
            }
        }
        let coarse = dense.llt(Side::Lower).map_err(|e| TensorError::Factorisation {
            what: "multigrid coarsest level".into(),
            detail: format!("{n} rows: {e:?}"),
        })?;
        let kernel = match kernel {
            Kernel::Exact => {
                let norm = dot(near_null, near_null).sqrt();
                (norm > 0.0).then(|| near_null.iter().map(|v| v / norm).collect())
            }
            Kernel::Near => None,
        };
        Ok(Self { levels, coarse, coarse_n: n, fine_n, entries: entries + n * n, kernel })
    }

    /// Rows per level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.levels.iter().map(|l| l.p.rows()).collect();
        s.push(self.coarse_n);
        s
    }

    /// Stored entries of all level matrices and prolongations (the hierarchy's memory, in
    /// f64s, the dense coarsest factor included).
    pub fn entries(&self) -> usize {
        self.entries
    }

    /// One V-cycle on level `l` from a zero guess: an approximation of `A_l⁻¹ b`.
    fn v_cycle(&self, fine: &CsrMatrix, l: usize, b: &[f64]) -> Vec<f64> {
        let Some(level) = self.levels.get(l) else {
            let rhs = Mat::from_fn(b.len(), 1, |i, _| b[i]);
            let x = self.coarse.solve(&rhs);
            return (0..b.len()).map(|i| x[(i, 0)]).collect();
        };
        let a = level.a.as_ref().unwrap_or(fine);
        let mut x = vec![0.0; b.len()];
        gauss_seidel(a, &level.inv_diag, b, &mut x, false);
        let mut r = a.mul(&x);
        for (ri, bi) in r.iter_mut().zip(b) {
            *ri = bi - *ri;
        }
        let correction = self.v_cycle(fine, l + 1, &level.r.mul(&r));
        let mut px = vec![0.0; b.len()];
        level.p.mul_into(&correction, &mut px);
        for (xi, pi) in x.iter_mut().zip(&px) {
            *xi += pi;
        }
        gauss_seidel(a, &level.inv_diag, b, &mut x, true);
        x
    }

    /// Applies the preconditioner (one V-cycle) to `r`; `fine` is the matrix the hierarchy
    /// was built for.
    pub fn precondition(&self, fine: &CsrMatrix, r: &[f64]) -> Vec<f64> {
        assert_eq!(r.len(), self.fine_n, "one entry per row");
        self.v_cycle(fine, 0, r)
    }

    /// Solves `A x = b` by preconditioned conjugate gradients from the guess in `x`, until
    /// `‖b − A x‖₂ ≤ target` (an absolute residual: the caller knows the scale that matters,
    /// which for a right-hand side that nearly vanishes is not `‖b‖`): the number of steps,
    /// or the residual reached if `max_steps` did not suffice. `a` is the matrix the hierarchy
    /// was built for.
    pub fn solve(
        &self,
        a: &CsrMatrix,
        b: &[f64],
        x: &mut [f64],
        target: f64,
        max_steps: usize,
    ) -> Result<usize, f64> {
        let mut r = a.mul(x);
        for (ri, bi) in r.iter_mut().zip(b) {
            *ri = bi - *ri;
        }
        let deflate = |v: &mut [f64]| {
            if let Some(k) = &self.kernel {
                let c = dot(v, k);
                v.iter_mut().zip(k).for_each(|(x, kx)| *x -= c * kx);
            }
        };
        deflate(&mut r);
        let mut res = dot(&r, &r).sqrt();
        if res <= target {
            return Ok(0);
        }
        let mut z = self.precondition(a, &r);
        deflate(&mut z);
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        let mut q = vec![0.0; b.len()];
        for step in 1..=max_steps {
            a.mul_into(&p, &mut q);
            let pq = dot(&p, &q);
            if pq <= 0.0 || !pq.is_finite() {
                break;
            }
            let alpha = rz / pq;
            for ((xi, ri), (pi, qi)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
                *xi += alpha * pi;
                *ri -= alpha * qi;
            }
            deflate(&mut r);
            res = dot(&r, &r).sqrt();
            if res <= target {
                return Ok(step);
            }
            z = self.precondition(a, &r);
            deflate(&mut z);
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (pi, zi) in p.iter_mut().zip(&z) {
                *pi = zi + beta * *pi;
            }
        }
        Err(res)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The graph Laplacian of an n × n × n grid (singular, kernel: constants), plus `shift` I.
    fn grid_laplacian(n: usize, shift: f64) -> CsrMatrix {
        let id = |i: usize, j: usize, k: usize| (i * n + j) * n + k;
        let mut t = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let a = id(i, j, k);
                    t.push((a, a, shift));
                    for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        let (i2, j2, k2) = (i + di, j + dj, k + dk);
                        if i2 < n && j2 < n && k2 < n {
                            let b = id(i2, j2, k2);
                            t.extend([(a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)]);
                        }
                    }
                }
            }
        }
        CsrMatrix::from_triplets(n * n * n, n * n * n, &t)
    }

    #[test]
    fn preconditioned_cg_solves_a_singular_laplacian_in_few_steps() {
        let n = 24;
        let a = grid_laplacian(n, 0.0);
        let rows = a.rows();
        let ones = vec![1.0; rows];
        let amg = Amg::new(&a, &ones, Kernel::Exact).expect("setup");
        assert!(amg.level_sizes().len() >= 3, "levels {:?}", amg.level_sizes());
        // A consistent right-hand side: zero sum.
        let mut b: Vec<f64> = (0..rows).map(|i| ((i * 7919) % 1000) as f64 / 1000.0).collect();
        let mean = b.iter().sum::<f64>() / rows as f64;
        b.iter_mut().for_each(|v| *v -= mean);
        let mut x = vec![0.0; rows];
        let steps = amg.solve(&a, &b, &mut x, 1e-10 * dot(&b, &b).sqrt(), 100).expect("converges");
        // Plain CG needs about n·(a few) steps here; the multigrid keeps it small.
        assert!(steps < 30, "{steps} steps");
        let ax = a.mul(&x);
        let res = ax.iter().zip(&b).map(|(p, q)| (p - q).powi(2)).sum::<f64>().sqrt();
        assert!(res <= 1e-9 * dot(&b, &b).sqrt(), "true residual {res:e}");
    }

    #[test]
    fn a_matrix_that_cannot_coarsen_is_refused_rather_than_factorised_densely() {
        // Diagonal: no connections to aggregate by. Small enough, the dense level solves it;
        // too large, the setup says so instead of allocating n² entries.
        let diag = |n: usize| {
            CsrMatrix::from_triplets(n, n, &(0..n).map(|i| (i, i, 1.0 + i as f64)).collect::<Vec<_>>())
        };
        let small = diag(1000);
        let amg = Amg::new(&small, &vec![1.0; 1000], Kernel::Near).expect("dense coarsest level");
        let b = vec![1.0; 1000];
        let mut x = vec![0.0; 1000];
        assert_eq!(amg.solve(&small, &b, &mut x, 1e-12, 5), Ok(1));
        assert!((x[9] - 0.1).abs() < 1e-14);
        match Amg::new(&diag(DENSE_MAX + 1), &vec![1.0; DENSE_MAX + 1], Kernel::Near) {
            Err(TensorError::Factorisation { detail, .. }) => assert!(detail.contains("stalled"), "{detail}"),
            other => panic!("expected a stalled-coarsening error, got {:?}", other.map(|a| a.level_sizes())),
        }
    }

    #[test]
    fn a_definite_system_converges_with_a_near_null_vector() {
        let a = grid_laplacian(16, 1e-3);
        let rows = a.rows();
        let amg = Amg::new(&a, &vec![1.0; rows], Kernel::Near).expect("setup");
        let b: Vec<f64> = (0..rows).map(|i| (i as f64).sin()).collect();
        let mut x = vec![0.0; rows];
        let steps = amg.solve(&a, &b, &mut x, 1e-10 * dot(&b, &b).sqrt(), 100).expect("converges");
        assert!(steps < 30, "{steps} steps");
    }
}
