//! Sparse symmetric systems whose pattern is fixed while their values change (the fluid's
//! projection every frame, the harmonic deformation every frame): the pattern and the
//! fill-reducing symbolic Cholesky factorisation are computed once, each new set of values is
//! factorised numerically (LLᵀ for positive definite, LDLᵀ for quasi-definite saddle-point
//! systems) and solved, on faer.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::error::TensorError;

/// The upper triangle of a symmetric sparse matrix in compressed columns, with a slot for
/// every (row, column) the assembler will add into.
#[derive(Clone, Debug)]
pub struct SymmetricPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
}

impl SymmetricPattern {
    /// The pattern of the given entries (any order, duplicates allowed; the lower-triangle
    /// ones are mirrored), with every diagonal entry present.
    pub fn new(n: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut cols: Vec<Vec<usize>> = (0..n).map(|j| vec![j]).collect();
        for (r, c) in entries {
            let (r, c) = if r <= c { (r, c) } else { (c, r) };
            cols[c].push(r);
        }
        let (col_ptr, row_idx) = super::csr::compress(cols);
        Self { n, col_ptr, row_idx }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored (upper-triangle) entries.
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// The value slot of entry (r, c) (either triangle), if it is in the pattern.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        let (r, c) = if r <= c { (r, c) } else { (c, r) };
        let col = &self.row_idx[self.col_ptr[c]..self.col_ptr[c + 1]];
        col.binary_search(&r).ok().map(|i| self.col_ptr[c] + i)
    }

    /// y = A x for the symmetric matrix with these upper-triangle `values`.
    pub fn mul(&self, values: &[f64], x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.n];
        for c in 0..self.n {
            let span = self.col_ptr[c]..self.col_ptr[c + 1];
            for (&r, &v) in self.row_idx[span.clone()].iter().zip(&values[span]) {
                y[r] += v * x[c];
                if r != c {
                    y[c] += v * x[r];
                }
            }
        }
        y
    }

    fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// faer's parallelism: every core rayon has (supernodal factorisation and solves).
fn parallelism() -> Par {
    Par::rayon(rayon::current_num_threads().max(1))
}

/// Which numerical factorisation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Factorisation {
    /// LLᵀ: symmetric positive definite.
    Llt,
    /// LDLᵀ without pivoting: quasi-definite (positive definite leading block, negative
    /// definite trailing block), e.g. a regularised saddle-point system.
    Ldlt,
}

/// A symbolic factorisation reused for every numerical one.
pub struct SparseSymmetricSolver {
    pattern: SymmetricPattern,
    symbolic: SymbolicCholesky<usize>,
    kind: Factorisation,
    factor: Vec<f64>,
    factored: bool,
}

impl std::fmt::Debug for SparseSymmetricSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseSymmetricSolver")
            .field("n", &self.pattern.n)
            .field("nnz", &self.pattern.nnz())
            .field("factor_len", &self.symbolic.len_val())
            .field("kind", &self.kind)
            .finish()
    }
}

impl SparseSymmetricSolver {
    /// Orders the pattern (approximate minimum degree) and computes its symbolic factor.
    pub fn new(pattern: SymmetricPattern, kind: Factorisation) -> Result<Self, TensorError> {
        let symbolic = factorize_symbolic_cholesky(
            pattern.symbolic(),
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| TensorError::Factorisation {
            what: "sparse symbolic factorisation".into(),
            detail: format!("{e:?}"),
        })?;
        let factor = vec![0.0; symbolic.len_val()];
        Ok(Self { pattern, symbolic, kind, factor, factored: false })
    }

    /// The pattern the values are laid out in.
    pub fn pattern(&self) -> &SymmetricPattern {
        &self.pattern
    }

    /// Entries of the factor (fill included).
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Factorises the matrix with these upper-triangle values (laid out as the pattern).
    pub fn factorise(&mut self, what: &str, values: &[f64]) -> Result<(), TensorError> {
        assert_eq!(values.len(), self.pattern.nnz(), "values laid out as the pattern");
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(TensorError::NotFinite { what: what.into(), detail: format!("matrix entry {i}") });
        }
        let a = SparseColMatRef::new(self.pattern.symbolic(), values);
        let par = parallelism();
        self.factored = false;
        match self.kind {
            Factorisation::Llt => {
                let req = self.symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default());
                let mut mem = MemBuffer::new(req);
                self.symbolic
                    .factorize_numeric_llt(
                        &mut self.factor,
                        a,
                        Side::Upper,
                        LltRegularization::default(),
                        par,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .map_err(|e| TensorError::Factorisation {
                        what: what.into(),
                        detail: format!("LLᵀ: {e:?}"),
                    })?;
            }
            Factorisation::Ldlt => {
                let req = self.symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
                let mut mem = MemBuffer::new(req);
                self.symbolic
                    .factorize_numeric_ldlt(
                        &mut self.factor,
                        a,
                        Side::Upper,
                        LdltRegularization::default(),
                        par,
                        MemStack::new(&mut mem),
                        Default::default(),
                    )
                    .map_err(|e| TensorError::Factorisation {
                        what: what.into(),
                        detail: format!("LDLᵀ: {e:?}"),
                    })?;
            }
        }
        if let Some(i) = self.factor.iter().position(|v| !v.is_finite()) {
            return Err(TensorError::Factorisation {
                what: what.into(),
                detail: format!("factor entry {i} is not finite"),
            });
        }
        self.factored = true;
        Ok(())
    }

    /// Solves with the last factorisation, in place.
    pub fn solve_in_place(&self, rhs: &mut [f64]) {
        self.solve_columns_in_place(rhs, 1);
    }

    /// Solves for `columns` right-hand sides at once, stored column after column in `rhs`
    /// (one pass over the factor for all of them).
    pub fn solve_columns_in_place(&self, rhs: &mut [f64], columns: usize) {
        assert!(self.factored, "factorise before solving");
        let n = self.pattern.n;
        assert_eq!(rhs.len(), n * columns, "right-hand sides of the wrong length");
        // Sequential: the triangular solves are memory-bound, and rayon's hand-offs between
        // supernodes cost more than the second core gains (measured on the harmonic
        // deformation of a 54,000-vertex mesh).
        let par = Par::Seq;
        let req = self.symbolic.solve_in_place_scratch::<f64>(columns, par);
        let mut mem = MemBuffer::new(req);
        let stack = MemStack::new(&mut mem);
        let x = MatMut::from_column_major_slice_mut(rhs, n, columns);
        match self.kind {
            Factorisation::Llt => faer::sparse::linalg::cholesky::LltRef::new(&self.symbolic, &self.factor)
                .solve_in_place_with_conj(Conj::No, x, par, stack),
            Factorisation::Ldlt => faer::sparse::linalg::cholesky::LdltRef::new(&self.symbolic, &self.factor)
                .solve_in_place_with_conj(Conj::No, x, par, stack),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quasi_definite_ldlt_and_spd_llt_solve_small_systems() {
        // [[4, 1, 1], [1, 3, 0], [1, 0, -1e-3]]: a regularised saddle point.
        let pattern = SymmetricPattern::new(3, [(0, 1), (0, 2), (1, 0)]);
        let mut v = vec![0.0; pattern.nnz()];
        for (r, c, x) in [(0, 0, 4.0), (1, 1, 3.0), (2, 2, -1e-3), (0, 1, 1.0), (0, 2, 1.0)] {
            v[pattern.slot(r, c).expect("in pattern")] += x;
        }
        let b = [1.0, 2.0, 3.0];
        let mut solver = SparseSymmetricSolver::new(pattern.clone(), Factorisation::Ldlt).expect("symbolic");
        solver.factorise("test", &v).expect("factor");
        let mut x = b.to_vec();
        solver.solve_in_place(&mut x);
        let r = pattern.mul(&v, &x);
        assert!(r.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-12), "{r:?}");
        // SPD: drop the saddle.
        let mut v2 = v.clone();
        v2[pattern.slot(2, 2).expect("diag")] = 2.0;
        let mut llt = SparseSymmetricSolver::new(pattern.clone(), Factorisation::Llt).expect("symbolic");
        llt.factorise("test", &v2).expect("factor");
        let mut x = b.to_vec();
        llt.solve_in_place(&mut x);
        let r = pattern.mul(&v2, &x);
        assert!(r.iter().zip(&b).all(|(a, b)| (a - b).abs() < 1e-12));
        // Not positive definite: refused, not panicking.
        v2[pattern.slot(2, 2).expect("diag")] = -2.0;
        assert!(llt.factorise("test", &v2).is_err());
    }
}
