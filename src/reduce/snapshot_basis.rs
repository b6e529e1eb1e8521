//! Bases held as snapshot coefficients, for quantities whose bases are larger than memory (seed
//! 000 §9: pair quantities of 25 million rows at 5,000 faces, up to 120 columns each).
//!
//! A PCA basis is `B = S W` — the snapshots `S` (`n × k`) times a small coefficient matrix
//! `W` (`k × m`) from the eigenvectors of the Gram matrix `G = SᵀS` (the method of snapshots,
//! [`super::pca`]) — so a basis can be kept as `W` alone, its rows regenerated on demand from
//! the snapshot rows (`B[K, :] = S[K, :] W`) by whatever regenerates the snapshots. The modes
//! come from `G`, accumulated in one pass over blocks of rows ([`snapshot_grams`], several
//! sources at once). Orthonormalising them through `G` would amplify its rounding by
//! `σ_max²/σᵢ²`, so the columns `S V` are orthonormalised from *their* Gram matrix, accumulated
//! in a second pass over their rows ([`basis_grams`]), which also gives the cross terms a merge
//! of two bases needs (`[B_a B_b]` re-orthonormalised: [`SnapshotBasis::merge`]). The reduced
//! coordinates of the snapshots themselves need no pass at all: `BᵀS = WᵀG`.

use std::sync::Arc;

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::{Accum, MatMut, MatRef, Par};

use super::error::ReduceError;
use super::pca::{modes_from_gram, Truncation, BLOCK_ROWS};
use super::premultiply::BasisRows;
use super::ranks::{allreduce_parts, Communicator};
use super::Basis;
use crate::tensor::Tensor;

/// Snapshots whose rows can be regenerated at any indices (`k` snapshots of dimension `n`).
pub trait SnapshotRows: Sync {
    /// Full dimension `n`.
    fn dim(&self) -> usize;
    /// Number of snapshots `k`.
    fn count(&self) -> usize;
    /// Rows `indices` of every snapshot, as an `indices.len() × k` row-major matrix (shared:
    /// sources that regenerate several quantities at once may hand out what they cached).
    fn rows_at(&self, indices: &[usize]) -> Result<Arc<Tensor>, ReduceError>;
}

/// The Gram matrices `S_aᵀ S_b` (`k_a × k_b`) of `sources[a]` and `sources[b]` for every `(a,
/// b)` in `pairs`, in one pass over blocks of rows (all sources have the same dimension).
/// `progress` is called with (rows done, rows) of this rank's share.
///
/// Sharded over `ranks`: each rank regenerates and multiplies only its contiguous share of
/// the rows, in blocks (for pair quantities, rows `i n + j` of a range of faces `i`), and one
/// allreduce sums the small Gram matrices — the same on every rank, added in rank order.
pub fn snapshot_grams(
    sources: &[&dyn SnapshotRows],
    pairs: &[(usize, usize)],
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
    ranks: &dyn Communicator,
) -> Result<Vec<Tensor>, ReduceError> {
    let dims: Vec<usize> = sources.iter().map(|s| s.dim()).collect();
    let counts: Vec<usize> = sources.iter().map(|s| s.count()).collect();
    gram_pass(&dims, &counts, |s, rows| sources[s].rows_at(rows), pairs, progress, ranks)
}

/// The Gram matrices `B_aᵀ B_b` (`m_a × m_b`) of bases given by rows, in one pass over blocks
/// of rows — what orthonormalising and merging [`SnapshotBasis`] columns needs. Sharded over
/// `ranks` as [`snapshot_grams`].
pub fn basis_grams(
    bases: &[&dyn BasisRows],
    pairs: &[(usize, usize)],
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
    ranks: &dyn Communicator,
) -> Result<Vec<Tensor>, ReduceError> {
    let dims: Vec<usize> = bases.iter().map(|b| b.full_dim()).collect();
    let counts: Vec<usize> = bases.iter().map(|b| b.reduced_dim()).collect();
    gram_pass(&dims, &counts, |s, rows| bases[s].rows(rows).map(Arc::new), pairs, progress, ranks)
}

/// `X_aᵀ X_b` over blocks of rows of matrices given by rows (`rows(source, indices)`, of
/// `counts[source]` columns each): this rank's share of the rows, then one allreduce.
fn gram_pass(
    dims: &[usize],
    counts: &[usize],
    rows: impl Fn(usize, &[usize]) -> Result<Arc<Tensor>, ReduceError>,
    pairs: &[(usize, usize)],
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
    ranks: &dyn Communicator,
) -> Result<Vec<Tensor>, ReduceError> {
    let Some(&n) = dims.first() else { return Ok(Vec::new()) };
    if let Some(d) = dims.iter().find(|&&d| d != n) {
        return Err(ReduceError::BadBasis {
            basis: "snapshots".into(),
            detail: format!("sources of {n} and {d} rows cannot share a Gram pass"),
        });
    }
    let mut grams: Vec<Vec<f64>> = pairs.iter().map(|&(a, b)| vec![0.0; counts[a] * counts[b]]).collect();
    let used: Vec<usize> = {
        let mut u: Vec<usize> = pairs.iter().flat_map(|&(a, b)| [a, b]).collect();
        u.sort_unstable();
        u.dedup();
        u
    };
    let share = ranks.share(n);
    let (first, last) = (share.start, share.end);
    for start in (first..last).step_by(BLOCK_ROWS) {
        let end = (start + BLOCK_ROWS).min(last);
        let indices: Vec<usize> = (start..end).collect();
        let mut blocks: Vec<Option<Arc<Tensor>>> = vec![None; counts.len()];
        for &s in &used {
            let block = rows(s, &indices)?;
            let k = counts[s];
            if let Some(i) = block.data().iter().position(|v| !v.is_finite()) {
                return Err(ReduceError::BadBasis {
                    basis: "snapshots".into(),
                    detail: format!("source {s}: column {} row {} is not finite", i % k, start + i / k),
                });
            }
            blocks[s] = Some(block);
        }
        for (g, &(a, b)) in grams.iter_mut().zip(pairs) {
            let (ka, kb) = (counts[a], counts[b]);
            let sa = blocks[a].as_ref().expect("generated above");
            let sb = blocks[b].as_ref().expect("generated above");
            let sa = MatRef::from_row_major_slice(sa.data(), end - start, ka);
            let sb = MatRef::from_row_major_slice(sb.data(), end - start, kb);
            let dst = MatMut::from_row_major_slice_mut(g, ka, kb);
            if a == b {
                // Symmetric: the lower triangle only (half the work), mirrored at the end.
                triangular::matmul(
                    dst,
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    sa.transpose(),
                    BlockStructure::Rectangular,
                    sb,
                    BlockStructure::Rectangular,
                    1.0,
                    Par::rayon(0),
                );
            } else {
                matmul(dst, Accum::Add, sa.transpose(), sb, 1.0, Par::rayon(0));
            }
        }
        if let Some(p) = progress {
            p((end - first) as f64, (last - first) as f64);
        }
    }
    let mut parts: Vec<&mut [f64]> = grams.iter_mut().map(Vec::as_mut_slice).collect();
    allreduce_parts(ranks, &mut parts, "the Gram matrices of the snapshots")?;
    for (g, &(a, b)) in grams.iter_mut().zip(pairs) {
        if a == b {
            let k = counts[a];
            for i in 0..k {
                for j in i + 1..k {
                    g[i * k + j] = g[j * k + i];
                }
            }
        }
    }
    Ok(pairs
        .iter()
        .zip(grams)
        .map(|(&(a, b), g)| Tensor::from_vec(&[counts[a], counts[b]], g).expect("k_a × k_b"))
        .collect())
}

/// A basis `B = Σ_p S_p W_p` over one or two snapshot sources, its rows regenerated on demand
/// (orthonormal once [`SnapshotBasis::orthonormalized`] or [`SnapshotBasis::merge`] made it).
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

/// Modes whose σ² is below this fraction of the largest are not kept in snapshot-coefficient
/// form: `S v / σ` regenerated from the rows carries the rounding of `v` (an eigenvector of a
/// Gram matrix, accurate to about ε σ_max² / σ²) magnified by `1/σ`. At 1e-10 (σ ≥ 1e-5 σ_max)
/// the columns are accurate to about 1e-6; a PCA truncated at 99.9 % of the energy never gets
/// near it.
const RESOLVED: f64 = 1e-10;

/// Remainders whose squared norm falls below this fraction of their column's are dependent and
/// dropped, and so are columns whose squared norm falls below this fraction of the longest's. Measured through a Gram matrix, a squared norm carries an absolute error of about ε
/// of the column's, so a kept remainder is normalised to within ε / DEPENDENT ≈ 1e-8; what is
/// dropped is less than 1e-4 of its column.
const DEPENDENT: f64 = 1e-8;

/// Gram–Schmidt (twice) of the columns of the identity in the metric `c` (`m × m`, SPD up to
/// rounding): coefficient columns `u` with `uᵢᵀ c uⱼ = δᵢⱼ`, dependent and negligible columns
/// dropped — the coefficients that orthonormalise columns whose Gram matrix is `c`.
pub(crate) fn orthonormal_in(name: &str, c: &Tensor) -> Result<Tensor, ReduceError> {
    let m = c.shape()[0];
    let cd = c.data();
    let apply =
        |u: &[f64]| -> Vec<f64> { (0..m).map(|i| (0..m).map(|j| cd[i * m + j] * u[j]).sum()).collect() };
    // Columns far shorter than the longest are rounding (modes whose σ the Gram matrix of the
    // snapshots could not resolve): their Gram entries are mostly its rounding, too.
    let largest = (0..m).map(|j| cd[j * m + j]).fold(0.0, f64::max);
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
        if norm2 > DEPENDENT * cd[j * m + j] && cd[j * m + j] > DEPENDENT * largest && norm2 > 0.0 {
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
pub(crate) fn product(a: &Tensor, b: &Tensor) -> Tensor {
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
pub(crate) fn transposed_product(a: &Tensor, b: &Tensor) -> Tensor {
    product(&a.permute(&[1, 0]), b)
}

impl<'a> SnapshotBasis<'a> {
    /// The PCA modes of `source` (the method of snapshots, truncated as for [`super::pca`])
    /// from its Gram matrix `gram = SᵀS`: the columns `S vᵢ / σᵢ` (centred: the mean first,
    /// scaled to unit length), orthonormal only up to rounding — finish with [`Self::orthonormalized`] or
    /// [`Self::merge`] and the Gram matrices of [`basis_grams`].
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
        let modes = modes_from_gram(name, gram.data().to_vec(), k, truncation, RESOLVED)?;
        let w = Tensor::from_vec(&[k, modes.columns], modes.coefficients).expect("k × columns");
        let spectrum = Spectrum {
            singular_values: modes.sigma2.iter().map(|s| s.sqrt()).collect(),
            energy: if modes.total > 0.0 { modes.kept / modes.total } else { 1.0 },
        };
        let columns = w.shape()[1];
        Ok((Self { name: name.into(), dim: source.dim(), columns, parts: vec![(source, w)] }, spectrum))
    }

    /// This basis's columns orthonormalised (Gram–Schmidt twice in the metric of `gram =
    /// BᵀB`, dependent columns dropped), in their order.
    pub fn orthonormalized(self, gram: &Tensor) -> Result<Self, ReduceError> {
        self.check_gram(gram, self.columns)?;
        let u = orthonormal_in(&self.name, gram)?;
        let columns = u.shape()[1];
        let parts = self.parts.into_iter().map(|(s, w)| (s, product(&w, &u))).collect();
        Ok(Self { name: self.name, dim: self.dim, columns, parts })
    }

    /// One orthonormal basis spanning both `a` and `b` (each of one source), as
    /// [`Basis::merge`]: the columns of `a` then of `b` orthonormalised from their Gram
    /// matrices `gram_a = B_aᵀB_a`, `gram_b` and `cross = B_aᵀB_b`.
    pub fn merge(
        name: &str,
        (a, gram_a): (&Self, &Tensor),
        (b, gram_b): (&Self, &Tensor),
        cross: &Tensor,
    ) -> Result<Self, ReduceError> {
        let bad = |detail: String| ReduceError::BadBasis { basis: name.into(), detail };
        let ([(sa, wa)], [(sb, wb)]) = (a.parts.as_slice(), b.parts.as_slice()) else {
            return Err(bad("merging needs two bases of one source each".into()));
        };
        let (ma, mb) = (a.columns, b.columns);
        a.check_gram(gram_a, ma)?;
        b.check_gram(gram_b, mb)?;
        if a.dim != b.dim || cross.shape() != [ma, mb] {
            return Err(bad(format!(
                "cannot merge bases of {} and {} rows with a cross Gram matrix of shape {:?}",
                a.dim,
                b.dim,
                cross.shape()
            )));
        }
        let m = ma + mb;
        let mut c = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                c[i * m + j] = match (i < ma, j < ma) {
                    (true, true) => gram_a.data()[i * ma + j],
                    (false, false) => gram_b.data()[(i - ma) * mb + j - ma],
                    (true, false) => cross.data()[i * mb + j - ma],
                    (false, true) => cross.data()[j * mb + i - ma],
                };
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

    fn check_gram(&self, gram: &Tensor, m: usize) -> Result<(), ReduceError> {
        if gram.shape() != [m, m] {
            return Err(ReduceError::BadBasis {
                basis: self.name.clone(),
                detail: format!("a Gram matrix of shape {:?} for {m} columns", gram.shape()),
            });
        }
        Ok(())
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
    use crate::reduce::{pca, SingleRank, SnapshotFn};

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
        fn rows_at(&self, indices: &[usize]) -> Result<Arc<Tensor>, ReduceError> {
            let data = indices.iter().flat_map(|&i| (0..self.k).map(move |c| self.value(i, c))).collect();
            Ok(Arc::new(Tensor::from_vec(&[indices.len(), self.k], data).unwrap()))
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
        let grams = snapshot_grams(&[&a, &b], &[(0, 0), (1, 1)], None, &SingleRank).unwrap();
        let (sa, spectrum) = SnapshotBasis::pca("a", &a, &grams[0], t).unwrap();
        let (sb, _) = SnapshotBasis::pca("b", &b, &grams[1], t).unwrap();
        let own = basis_grams(&[&sa, &sb], &[(0, 0), (1, 1), (0, 1)], None, &SingleRank).unwrap();
        fn stored(s: &Random, t: Truncation) -> crate::reduce::Pca {
            let rows = |r: std::ops::Range<usize>| (*s.rows_at(&r.collect::<Vec<_>>()).unwrap()).clone();
            pca(s.name(), &mut SnapshotFn { dim: s.n, count: s.k, rows }, t).unwrap()
        }
        let (pa, pb) = (stored(&a, t), stored(&b, t));
        let merged =
            SnapshotBasis::merge("ab", (&sa, &own[0]), (&sb, &own[1]), &own[2]).unwrap().to_basis().unwrap();
        let sa = sa.orthonormalized(&own[0]).unwrap();
        assert_eq!(sa.reduced_dim(), pa.basis.reduced_dim());
        assert!((spectrum.energy - pa.energy).abs() < 1e-12);
        let ea = sa.to_basis().unwrap();
        assert!(ea.orthonormality_error() < 1e-12, "{}", ea.orthonormality_error());
        assert!(projector(&ea).max_abs_diff(&projector(&pa.basis)) < 1e-9);
        let stored = Basis::merge("ab", &pa.basis, &pb.basis).unwrap();
        assert_eq!(merged.reduced_dim(), stored.reduced_dim());
        assert!(merged.orthonormality_error() < 1e-12, "{}", merged.orthonormality_error());
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
