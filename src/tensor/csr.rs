//! Sparse matrices in compressed rows: the fixed-pattern assembly target of the fluid's
//! projection system and the level matrices and prolongations of the algebraic multigrid
//! ([`super::amg`]). Products are written plainly (Gustavson's row-by-row accumulation);
//! the matrix–vector product runs on every core.

use rayon::prelude::*;

/// A sparse matrix in compressed rows, columns sorted within each row.
#[derive(Clone, Debug, Default)]
pub struct CsrMatrix {
    rows: usize,
    cols: usize,
    row_ptr: Vec<usize>,
    col_idx: Vec<usize>,
    values: Vec<f64>,
}

/// Compressed storage of per-line index lists (rows of a CSR matrix, columns of a CSC one):
/// each line sorted and deduplicated, then concatenated; the line starts and the indices.
pub(crate) fn compress(lines: Vec<Vec<usize>>) -> (Vec<usize>, Vec<usize>) {
    let mut start = Vec::with_capacity(lines.len() + 1);
    let mut index = Vec::new();
    start.push(0);
    for mut line in lines {
        line.sort_unstable();
        line.dedup();
        index.extend(line);
        start.push(index.len());
    }
    (start, index)
}

/// Rows per parallel task of [`CsrMatrix::mul_into`].
const ROWS_PER_TASK: usize = 4096;

impl CsrMatrix {
    /// The `rows × cols` matrix with a (zero) slot at every given (row, column), duplicates
    /// merged; [`CsrMatrix::slot`] finds where an entry's value lives.
    pub fn with_pattern(rows: usize, cols: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let mut per_row: Vec<Vec<usize>> = vec![Vec::new(); rows];
        for (r, c) in entries {
            assert!(r < rows && c < cols, "entry ({r}, {c}) outside {rows} × {cols}");
            per_row[r].push(c);
        }
        let (row_ptr, col_idx) = compress(per_row);
        let values = vec![0.0; col_idx.len()];
        Self { rows, cols, row_ptr, col_idx, values }
    }

    /// The matrix of these (row, column, value) triplets, duplicates summed.
    pub fn from_triplets(rows: usize, cols: usize, triplets: &[(usize, usize, f64)]) -> Self {
        let mut m = Self::with_pattern(rows, cols, triplets.iter().map(|&(r, c, _)| (r, c)));
        for &(r, c, v) in triplets {
            let s = m.slot(r, c).expect("in the pattern");
            m.values[s] += v;
        }
        m
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// The value index of entry (r, c), if it is stored.
    pub fn slot(&self, r: usize, c: usize) -> Option<usize> {
        let span = self.row_ptr[r]..self.row_ptr[r + 1];
        self.col_idx[span.clone()].binary_search(&c).ok().map(|i| span.start + i)
    }

    /// The stored values, in row order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// The stored values, for assembly into the fixed pattern.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Row `r`'s (columns, values).
    pub fn row(&self, r: usize) -> (&[usize], &[f64]) {
        let span = self.row_ptr[r]..self.row_ptr[r + 1];
        (&self.col_idx[span.clone()], &self.values[span])
    }

    /// Row `r`'s columns and mutable values.
    pub fn row_mut(&mut self, r: usize) -> (&[usize], &mut [f64]) {
        let span = self.row_ptr[r]..self.row_ptr[r + 1];
        (&self.col_idx[span.clone()], &mut self.values[span])
    }

    /// The diagonal (zero where no entry is stored).
    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.rows.min(self.cols)).map(|r| self.slot(r, r).map_or(0.0, |s| self.values[s])).collect()
    }

    /// `y = A x`, rows in parallel.
    pub fn mul_into(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.cols, "x has one entry per column");
        assert_eq!(y.len(), self.rows, "y has one entry per row");
        y.par_chunks_mut(ROWS_PER_TASK).enumerate().for_each(|(chunk, ys)| {
            let first = chunk * ROWS_PER_TASK;
            for (i, yi) in ys.iter_mut().enumerate() {
                let (cols, vals) = self.row(first + i);
                *yi = cols.iter().zip(vals).map(|(&c, v)| v * x[c]).sum();
            }
        });
    }

    /// `A x`.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; self.rows];
        self.mul_into(x, &mut y);
        y
    }

    /// `Aᵀ`.
    pub fn transpose(&self) -> Self {
        let mut count = vec![0usize; self.cols + 1];
        for &c in &self.col_idx {
            count[c + 1] += 1;
        }
        for c in 0..self.cols {
            count[c + 1] += count[c];
        }
        let row_ptr = count.clone();
        let mut next = count;
        let mut col_idx = vec![0; self.nnz()];
        let mut values = vec![0.0; self.nnz()];
        for r in 0..self.rows {
            let (cols, vals) = self.row(r);
            for (&c, &v) in cols.iter().zip(vals) {
                col_idx[next[c]] = r;
                values[next[c]] = v;
                next[c] += 1;
            }
        }
        Self { rows: self.cols, cols: self.rows, row_ptr, col_idx, values }
    }

    /// `A B` (Gustavson: each row of the product accumulated in a dense scratch row).
    pub fn matmul(&self, b: &CsrMatrix) -> Self {
        assert_eq!(self.cols, b.rows, "inner dimensions of a product");
        let mut marker = vec![usize::MAX; b.cols];
        let mut acc = vec![0.0; b.cols];
        let mut row_ptr = Vec::with_capacity(self.rows + 1);
        let mut col_idx = Vec::new();
        let mut values = Vec::new();
        row_ptr.push(0);
        let mut touched = Vec::new();
        for r in 0..self.rows {
            touched.clear();
            let (cols, vals) = self.row(r);
            for (&k, &a) in cols.iter().zip(vals) {
                let (bc, bv) = b.row(k);
                for (&c, &v) in bc.iter().zip(bv) {
                    if marker[c] != r {
                        marker[c] = r;
                        acc[c] = 0.0;
                        touched.push(c);
                    }
                    acc[c] += a * v;
                }
            }
            touched.sort_unstable();
            for &c in &touched {
                col_idx.push(c);
                values.push(acc[c]);
            }
            row_ptr.push(col_idx.len());
        }
        Self { rows: self.rows, cols: b.cols, row_ptr, col_idx, values }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(m: &CsrMatrix) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; m.cols()]; m.rows()];
        for (r, row) in d.iter_mut().enumerate() {
            let (cols, vals) = m.row(r);
            for (&c, &v) in cols.iter().zip(vals) {
                row[c] += v;
            }
        }
        d
    }

    #[test]
    fn products_and_transposes_agree_with_dense_arithmetic() {
        let a = CsrMatrix::from_triplets(
            3,
            4,
            &[(0, 0, 1.0), (0, 3, 2.0), (1, 1, -1.0), (2, 0, 4.0), (2, 0, 0.5)],
        );
        let b = CsrMatrix::from_triplets(4, 2, &[(0, 1, 3.0), (1, 0, 2.0), (3, 0, 1.0), (3, 1, -2.0)]);
        let (da, db) = (dense(&a), dense(&b));
        let ab = dense(&a.matmul(&b));
        for i in 0..3 {
            for j in 0..2 {
                let want: f64 = (0..4).map(|k| da[i][k] * db[k][j]).sum();
                assert_eq!(ab[i][j], want);
            }
        }
        let at = dense(&a.transpose());
        for i in 0..3 {
            for j in 0..4 {
                assert_eq!(at[j][i], da[i][j]);
            }
        }
        assert_eq!(a.mul(&[1.0, 2.0, 3.0, 4.0]), vec![9.0, -2.0, 4.5]);
        assert_eq!(a.diagonal(), vec![1.0, -1.0, 0.0]);
    }
}
