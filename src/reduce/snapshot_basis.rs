//! Bases held as snapshot coefficients, for quantities whose bases are larger than memory (seed
//! 000 §9: pair quantities of 25 million rows at 5,000 faces, up to 120 columns each).
//!
//! A PCA basis is `B = S W` — the snapshots `S` (`n × k`) times a small coefficient matrix
//! `W` (`k × m`) from the eigenvectors of the Gram matrix `G = SᵀS` (the method of snapshots,
//! [`super::pca`]) — so a basis can be kept as `W` alone, its rows regenerated on demand from
//! the snapshot rows (`B[K, :] = S[K, :] W`) by whatever regenerates the snapshots. Everything
//! else a basis needs is `k × k` algebra on Gram matrices: orthonormality (`BᵀB = WᵀGW`), the
//! merge of two bases that must agree (`[B_a B_b]` re-orthonormalised needs only `S_aᵀS_b`), and
//! the reduced coordinates of the snapshots themselves (`BᵀS = WᵀG`). Gram matrices of several
//! sources (and the cross terms a merge needs) are accumulated in one pass over blocks of rows
//! by [`snapshot_grams`].

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

use super::error::ReduceError;
use super::pca::{modes_from_gram, Truncation, BLOCK_ROWS};
use super::premultiply::BasisRows;
use super::Basis;
use crate::tensor::Tensor;

/// Snapshots whose rows can be regenerated at any indices (`k` snapshots of dimension `n`).
pub trait SnapshotRows: Sync {
    /// Full dimension `n`.
    fn dim(&self) -> usize;
    /// Number of snapshots `k`.
    fn count(&self) -> usize;
    /// Rows `indices` of every snapshot, as an `indices.len() × k` row-major matrix.
    fn rows_at(&self, indices: &[usize]) -> Result<Tensor, ReduceError>;
}

/// The Gram matrices `S_aᵀ S_b` (`k_a × k_b`) of `sources[a]` and `sources[b]` for every `(a,
/// b)` in `pairs`, in one pass over blocks of rows (all sources have the same dimension).
/// `progress` is called with (rows done, rows).
pub fn snapshot_grams(
    sources: &[&dyn SnapshotRows],
    pairs: &[(usize, usize)],
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
) -> Result<Vec<Tensor>, ReduceError> {
    let Some(first) = sources.first() else { return Ok(Vec::new()) };
    let n = first.dim();
    if let Some(s) = sources.iter().find(|s| s.dim() != n) {
        return Err(ReduceError::BadBasis {
            basis: "snapshots".into(),
            detail: format!("sources of {n} and {} rows cannot share a Gram pass", s.dim()),
        });
    }
    let mut grams: Vec<Vec<f64>> =
        pairs.iter().map(|&(a, b)| vec![0.0; sources[a].count() * sources[b].count()]).collect();
    let used: Vec<usize> = {
        let mut u: Vec<usize> = pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
        u.sort_unstable();
        u.dedup();
        u
    };
    for start in (0..n).step_by(BLOCK_ROWS) {
        let end = (start + BLOCK_ROWS).min(n);
        let indices: Vec<usize> = (start..end).collect();
        let mut blocks: Vec<Option<Tensor>> = vec![None; sources.len()];
        for &s in &used {
            let block = sources[s].rows_at(&indices)?;
            let k = sources[s].count();
            if let Some(i) = block.data().iter().position(|v| !v.is_finite()) {
                return Err(ReduceError::BadBasis {
                    basis: "snapshots".into(),
                    detail: format!("source {s}: snapshot {} row {} is not finite", i % k, start + i / k),
                });
            }
            blocks[s] = Some(block);
        }
        for (g, &(a, b)) in grams.iter_mut().zip(pairs) {
            let (ka, kb) = (sources[a].count(), sources[b].count());
            let sa = blocks[a].as_ref().expect("generated above");
            let sb = blocks[b].as_ref().expect("generated above");
            let sa = MatRef::from_row_major_slice(sa.data(), end - start, ka);
            let sb = MatRef::from_row_major_slice(sb.data(), end - start, kb);
            matmul(
                MatMut::from_row_major_slice_mut(g, ka, kb),
                Accum::Add,
                sa.transpose(),
                sb,
                1.0,
                Par::rayon(0),
            );
        }
        if let Some(p) = progress {
            p(end as f64, n as f64);
        }
    }
    Ok(pairs
        .iter()
        .zip(grams)
        .map(|(&(a, b), g)| {
            Tensor::from_vec(&[sources[a].count(), sources[b].count()], g).expect("k_a × k_b")
        })
        .collect())
}

/// An orthonormal basis `B = Σ_p S_p W_p` over one or two snapshot sources, its rows
/// regenerated on demand.
pub struct SnapshotBasis<'a> {
    name: String,
    dim: usize,
    columns: usize,
    parts: Vec<(&'a dyn SnapshotRows, Tensor)>,
}

/// What a PCA kept: every singular value and the energy fraction of the kept modes.
#[derive(Clone, Debug, PartialEq)]
pub struct Spectrum {
    /// Every singular value σ of the snapshot matrix, descending.
    pub singular_values: Vec<f64>,
    /// Fraction of Σσ² the kept modes hold.
    pub energy: f64,
}

/// Remainders whose squared norm (measured through a Gram matrix, so with an absolute error
/// of about ε times the column's) falls below this fraction of the column's are dependent.
const DEPENDENT: f64 = 1e-12;

/// Gram–Schmidt (twice) of the columns of the identity in the metric `c` (`m × m`, SPD up to
/// rounding): coefficient columns `u` with `uᵢᵀ c uⱼ = δᵢⱼ`, dependent columns dropped — the
/// coefficients that orthonormalise columns whose Gram matrix is `c`.
fn orthonormal_in(name: &str, c: &Tensor) -> Result<Tensor, ReduceError> {
    let m = c.shape()[0];
    let cd = c.data();
    let apply =
        |u: &[f64]| -> Vec<f64> { (0..m).map(|i| (0..m).map(|j| cd[i * m + j] * u[j]).sum()).collect() };
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for j in 0..m {
        let mut u = vec![0.0; m];
        u[j] = 1.0;
        for _ in 0..2 {
            let cu = apply(&u);
            let dots: Vec<f64> = kept.iter().map(|q| q.iter().zip(&cu).map(|(a, b)| a * b).sum()).collect();
            for (q, d) in kept.iter().zip(dots) {
                u.iter_mut().zip(q).for_each(|(x, qi)| *x -= d * qi);
            }
        }
        let norm2: f64 = u.iter().zip(apply(&u)).map(|(a, b)| a * b).sum();
        if !norm2.is_finite() {
            return Err(ReduceError::BadBasis {
                basis: name.into(),
                detail: format!("column {j} is not finite"),
            });
        }
        if norm2 > DEPENDENT * cd[j * m + j] && norm2 > 0.0 {
            let s = norm2.sqrt();
            u.iter_mut().for_each(|x| *x /= s);
            kept.push(u);
        }
    }
    if kept.is_empty() {
        return Err(ReduceError::BadBasis {
            basis: name.into(),
            detail: "every column is zero or dependent".into(),
        });
    }
    let cols = kept.len();
    let mut data = vec![0.0; m * cols];
    for (j, q) in kept.iter().enumerate() {
        for i in 0..m {
            data[i * cols + j] = q[i];
        }
    }
    Ok(Tensor::from_vec(&[m, cols], data).expect("shape matches"))
}

/// `a · b` for row-major matrices.
fn product(a: &Tensor, b: &Tensor) -> Tensor {
    let (r, k, c) = (a.shape()[0], a.shape()[1], b.shape()[1]);
    let mut out = vec![0.0; r * c];
    matmul(
        MatMut::from_row_major_slice_mut(&mut out, r, c),
        Accum::Replace,
        MatRef::from_row_major_slice(a.data(), r, k),
        MatRef::from_row_major_slice(b.data(), k, c),
        1.0,
        Par::Seq,
    );
    Tensor::from_vec(&[r, c], out).expect("shape matches")
}

/// `aᵀ · b`.
fn transposed_product(a: &Tensor, b: &Tensor) -> Tensor {
    product(&a.permute(&[1, 0]), b)
}

impl<'a> SnapshotBasis<'a> {
    /// The PCA basis of `source` (the method of snapshots, truncated as for
    /// [`super::pca`]) from its Gram matrix `gram = SᵀS`, orthonormalised through the Gram
    /// matrix instead of row by row.
    pub fn pca(
        name: &str,
        source: &'a dyn SnapshotRows,
        gram: &Tensor,
        truncation: Truncation,
    ) -> Result<(Self, Spectrum), ReduceError> {
        let k = source.count();
        if gram.shape() != [k, k] {
            return Err(ReduceError::BadBasis {
                basis: name.into(),
                detail: format!("a Gram matrix of shape {:?} for {k} snapshots", gram.shape()),
            });
        }
        let modes = modes_from_gram(name, gram.data().to_vec(), k, truncation)?;
        let v = Tensor::from_vec(&[k, modes.columns], modes.coefficients).expect("k × columns");
        // BᵀB = Vᵀ G V; its Gram–Schmidt coefficients make S V U orthonormal.
        let u = orthonormal_in(name, &transposed_product(&v, &product(gram, &v)))?;
        let w = product(&v, &u);
        let spectrum = Spectrum {
            singular_values: modes.sigma2.iter().map(|s| s.sqrt()).collect(),
            energy: if modes.total > 0.0 { modes.kept / modes.total } else { 1.0 },
        };
        let columns = w.shape()[1];
        Ok((Self { name: name.into(), dim: source.dim(), columns, parts: vec![(source, w)] }, spectrum))
    }

    /// One basis spanning both `a` and `b` (each a PCA basis of one source), re-orthonormalised
    /// — as [`Basis::merge`] — from `cross = S_aᵀ S_b`.
    pub fn merge(name: &str, a: &Self, b: &Self, cross: &Tensor) -> Result<Self, ReduceError> {
        let bad = |detail: String| ReduceError::BadBasis { basis: name.into(), detail };
        let ([(sa, wa)], [(sb, wb)]) = (a.parts.as_slice(), b.parts.as_slice()) else {
            return Err(bad("merging needs two bases of one source each".into()));
        };
        if a.dim != b.dim || cross.shape() != [sa.count(), sb.count()] {
            return Err(bad(format!(
                "cannot merge bases of {} and {} rows with a cross Gram matrix of shape {:?}",
                a.dim,
                b.dim,
                cross.shape()
            )));
        }
        let (ma, mb) = (a.columns, b.columns);
        // The Gram matrix of [B_a B_b]: identities on the diagonal, W_aᵀ (S_aᵀS_b) W_b off it.
        let x = transposed_product(wa, &product(cross, wb));
        let m = ma + mb;
        let mut c = vec![0.0; m * m];
        for i in 0..m {
            c[i * m + i] = 1.0;
        }
        for i in 0..ma {
            for j in 0..mb {
                c[i * m + ma + j] = x.data()[i * mb + j];
                c[(ma + j) * m + i] = x.data()[i * mb + j];
            }
        }
        let u = orthonormal_in(name, &Tensor::from_vec(&[m, m], c).expect("m × m"))?;
        let cols = u.shape()[1];
        let top = Tensor::from_vec(&[ma, cols], u.data()[..ma * cols].to_vec()).expect("shape matches");
        let bottom = Tensor::from_vec(&[mb, cols], u.data()[ma * cols..].to_vec()).expect("shape matches");
        Ok(Self {
            name: name.into(),
            dim: a.dim,
            columns: cols,
            parts: vec![(*sa, product(wa, &top)), (*sb, product(wb, &bottom))],
        })
    }

    /// The basis's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The reduced coordinates `BᵀS` (`m × k`) of the snapshots of a one-source basis, from
    /// their Gram matrix: `Wᵀ G`.
    pub fn project_snapshots(&self, gram: &Tensor) -> Result<Tensor, ReduceError> {
        match self.parts.as_slice() {
            [(s, w)] if gram.shape() == [s.count(), s.count()] => Ok(transposed_product(w, gram)),
            _ => Err(ReduceError::BadBasis {
                basis: self.name.clone(),
                detail: "projecting snapshots needs a one-source basis and its Gram matrix".into(),
            }),
        }
    }

    /// The whole `n × m` matrix as a stored [`Basis`] (for dimensions that fit in memory).
    pub fn to_basis(&self) -> Result<Basis, ReduceError> {
        let all: Vec<usize> = (0..self.dim).collect();
        Basis::new(&self.name, BasisRows::rows(self, &all)?, 1e-8)
    }
}

impl BasisRows for SnapshotBasis<'_> {
    fn full_dim(&self) -> usize {
        self.dim
    }
    fn reduced_dim(&self) -> usize {
        self.columns
    }
    fn rows(&self, indices: &[usize]) -> Result<Tensor, ReduceError> {
        let mut out = vec![0.0; indices.len() * self.columns];
        for (source, w) in &self.parts {
            let s = source.rows_at(indices)?;
            let k = source.count();
            matmul(
                MatMut::from_row_major_slice_mut(&mut out, indices.len(), self.columns),
                Accum::Add,
                MatRef::from_row_major_slice(s.data(), indices.len(), k),
                MatRef::from_row_major_slice(w.data(), k, self.columns),
                1.0,
                Par::rayon(0),
            );
        }
        Ok(Tensor::from_vec(&[indices.len(), self.columns], out).expect("shape matches"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduce::{pca, SnapshotFn};

    /// Snapshots made of a few random directions with decaying weights plus a common part.
    struct Random {
        n: usize,
        k: usize,
        seed: u64,
    }

    impl Random {
        fn value(&self, i: usize, c: usize) -> f64 {
            let h = |x: u64| {
                let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            let mut v = 3.0 * h(self.seed ^ (i as u64 * 7919));
            for d in 0..6u64 {
                let w = 0.5f64.powi(d as i32 * 2) * h(self.seed ^ (1000 + d * 31 + c as u64 * 131));
                v += w * h(self.seed ^ (d << 40) ^ (i as u64 * 104729));
            }
            v
        }
    }

    impl Random {
        fn name(&self) -> &'static str {
            if self.seed == 1 {
                "a"
            } else {
                "b"
            }
        }
    }

    impl SnapshotRows for Random {
        fn dim(&self) -> usize {
            self.n
        }
        fn count(&self) -> usize {
            self.k
        }
        fn rows_at(&self, indices: &[usize]) -> Result<Tensor, ReduceError> {
            let data = indices.iter().flat_map(|&i| (0..self.k).map(move |c| self.value(i, c))).collect();
            Ok(Tensor::from_vec(&[indices.len(), self.k], data).unwrap())
        }
    }

    fn projector(b: &Basis) -> Tensor {
        product(b.matrix(), &b.matrix().permute(&[1, 0]))
    }

    /// The snapshot-coefficient basis spans what the row-by-row PCA spans, is orthonormal, and
    /// its merge spans what the stored merge spans; reduced snapshot coordinates match.
    #[test]
    fn snapshot_bases_match_the_stored_pca_and_merge() {
        let (a, b) = (Random { n: 5000, k: 30, seed: 1 }, Random { n: 5000, k: 25, seed: 2 });
        let t = Truncation { energy: 0.999, max_modes: 8, centred: true };
        let grams = snapshot_grams(&[&a, &b], &[(0, 0), (1, 1), (0, 1)], None).unwrap();
        let (sa, spectrum) = SnapshotBasis::pca("a", &a, &grams[0], t).unwrap();
        let (sb, _) = SnapshotBasis::pca("b", &b, &grams[1], t).unwrap();
        fn stored(s: &Random, t: Truncation) -> crate::reduce::Pca {
            let rows = |r: std::ops::Range<usize>| s.rows_at(&r.collect::<Vec<_>>()).unwrap();
            pca(s.name(), &mut SnapshotFn { dim: s.n, count: s.k, rows }, t).unwrap()
        }
        let (pa, pb) = (stored(&a, t), stored(&b, t));
        assert_eq!(sa.reduced_dim(), pa.basis.reduced_dim());
        assert!((spectrum.energy - pa.energy).abs() < 1e-12);
        let ea = sa.to_basis().unwrap();
        assert!(ea.orthonormality_error() < 1e-10, "{}", ea.orthonormality_error());
        assert!(projector(&ea).max_abs_diff(&projector(&pa.basis)) < 1e-9);
        let merged = SnapshotBasis::merge("ab", &sa, &sb, &grams[2]).unwrap().to_basis().unwrap();
        let stored = Basis::merge("ab", &pa.basis, &pb.basis).unwrap();
        assert_eq!(merged.reduced_dim(), stored.reduced_dim());
        assert!(merged.orthonormality_error() < 1e-10);
        assert!(projector(&merged).max_abs_diff(&projector(&stored)) < 1e-9);
        // BᵀS from the Gram matrix equals projecting every snapshot.
        let coords = sa.project_snapshots(&grams[0]).unwrap();
        for c in [0, 7, 29] {
            let snapshot: Vec<f64> = (0..a.n).map(|i| a.value(i, c)).collect();
            let p = ea.project(&snapshot);
            for (r, x) in p.iter().enumerate() {
                assert!((coords.data()[r * a.k + c] - x).abs() < 1e-9 * (1.0 + x.abs()));
            }
        }
    }
}
