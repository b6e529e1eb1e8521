//! Streamed premultiplication: `Q̂ = Q ⊗₀ B₀ ⊗₁ B₁ …` (Eq. 2) for tensors too large to hold
//! whole and bases too large to hold whole — the pair-space tensors of seed 000 §9 (Table 2 at
//! 5,000 faces: 25 million pairs, up to 117 entries per pair, bases of 25 million rows).
//!
//! `Q̂` is linear in `Q`'s entries, so `Q` is taken a chunk of entries at a time
//! ([`TensorChunks`]); each chunk only meets the basis rows its coordinates name, so only those
//! rows are asked for ([`BasisRows`]: a stored [`Basis`] gathers them, a basis held as snapshot
//! coefficients regenerates them). Each chunk becomes a small sparse tensor over its own
//! distinct coordinates, premultiplied by [`premultiply_sparse_with`] — the same planned chain
//! as a whole tensor — against the gathered rows, and the chunk results are summed.

use std::sync::Arc;

use super::{premultiply_sparse_in, Buffers, PremultiplyOptions};
use crate::reduce::ranks::allreduce_parts;
use crate::reduce::{Basis, ReduceError};
use crate::tensor::{SparseTensor, Tensor};

/// A basis that hands out rows on demand (`B[indices, :]`), for bases whose whole `n × m`
/// matrix need not, or cannot, be held.
pub trait BasisRows: Sync {
    /// Full dimension `n`.
    fn full_dim(&self) -> usize;
    /// Reduced dimension `m`.
    fn reduced_dim(&self) -> usize;
    /// Rows `indices` (each `< n`) as an `indices.len() × m` row-major matrix.
    fn rows(&self, indices: &[usize]) -> Result<Tensor, ReduceError>;
}

impl BasisRows for Basis {
    fn full_dim(&self) -> usize {
        Basis::full_dim(self)
    }
    fn reduced_dim(&self) -> usize {
        Basis::reduced_dim(self)
    }
    fn rows(&self, indices: &[usize]) -> Result<Tensor, ReduceError> {
        let m = Basis::reduced_dim(self);
        let data = self.matrix().data();
        let mut out = Vec::with_capacity(indices.len() * m);
        for &i in indices {
            out.extend_from_slice(&data[i * m..(i + 1) * m]);
        }
        Ok(Tensor::from_vec(&[indices.len(), m], out).expect("shape matches"))
    }
}

/// Rows of an axis's basis on demand: `rows(axis, indices)` is `B_axis[indices, :]`.
pub type AxisRows<'a> = dyn FnMut(usize, &[usize]) -> Result<Arc<Tensor>, ReduceError> + 'a;

/// A sparse tensor produced a chunk of entries at a time (every entry in exactly one chunk;
/// each chunk a [`SparseTensor`] of the full shape, with the tensor's symmetric groups).
pub trait TensorChunks: Send + Sync {
    /// The full shape.
    fn shape(&self) -> Vec<usize>;
    /// Number of chunks.
    fn chunks(&self) -> usize;
    /// The entries of chunk `c`.
    fn chunk(&self, c: usize) -> SparseTensor;

    /// The rows chunk `c` touches on `axis`, ascending (a superset of its coordinates there),
    /// if the tensor names them — so that tensors chunked alike ask their bases for identical
    /// row sets (which bases that regenerate rows can make once); otherwise the chunk's
    /// distinct coordinates are used.
    fn chunk_rows(&self, _c: usize, _axis: usize) -> Option<Vec<usize>> {
        None
    }

    /// Chunk `c` premultiplied — `Σ value · B₀[i₀, :] ⊗ B₁[i₁, :] ⊗ …` over its entries, dense in
    /// the reduced shape — computed from the tensor's own structure instead of its entries, for
    /// tensors that have a faster way (Table 2's `R`: three rank-one terms per pair, where its
    /// 117 entries per pair cost a hundred times more). `rows(axis, indices)` gives the rows
    /// `indices` of that axis's basis (`indices.len() × m_axis`). `None` (the default): the
    /// entries are premultiplied.
    fn premultiply_chunk(&self, _c: usize, _rows: &mut AxisRows<'_>) -> Option<Result<Tensor, ReduceError>> {
        None
    }

    /// Every chunk in one tensor (for the full-space evaluation of small cases).
    fn to_sparse(&self) -> SparseTensor {
        let shape = self.shape();
        let mut coords = Vec::new();
        let mut values = Vec::new();
        let mut groups = Vec::new();
        for c in 0..self.chunks() {
            let t = self.chunk(c);
            coords.extend_from_slice(t.coords());
            values.extend_from_slice(t.values());
            groups = t.symmetric_groups().to_vec();
        }
        let mut out = SparseTensor::from_coords("chunked tensor", &shape, coords, values)
            .expect("chunks hold valid entries");
        for g in groups {
            out = out.with_symmetric_axes(&g).expect("the chunks' own groups");
        }
        out
    }
}

/// `Q̂` of a chunked tensor against bases given by rows (one per axis, in axis order), on the
/// CPU. `progress` is called with (chunks done, chunks) after each chunk.
pub fn premultiply_streamed(
    name: &str,
    q: &dyn TensorChunks,
    bases: &[&dyn BasisRows],
    options: PremultiplyOptions<'_>,
) -> Result<Tensor, ReduceError> {
    let mut out = premultiply_streamed_together(&[(name, q, bases)], options)?;
    Ok(out.pop().expect("one tensor"))
}

/// Several chunked tensors premultiplied in lockstep — chunk `c` of every tensor before chunk
/// `c + 1` of any — so that bases regenerating rows for a chunk (and keeping the last few
/// blocks) make them once for all the tensors. `progress`: (chunks done, chunks) of this
/// rank's share.
///
/// Sharded over `options.ranks`: `Q̂` is linear in `Q`'s entries, so each rank premultiplies a
/// contiguous share of the chunks (its faces' pairs, its cells) against the basis rows those
/// chunks name, and one allreduce sums the small reduced tensors, in rank order.
pub fn premultiply_streamed_together(
    tensors: &[(&str, &dyn TensorChunks, &[&dyn BasisRows])],
    options: PremultiplyOptions<'_>,
) -> Result<Vec<Tensor>, ReduceError> {
    let mut totals = Vec::with_capacity(tensors.len());
    for &(name, q, bases) in tensors {
        let shape = q.shape();
        if bases.len() != shape.len() {
            return Err(ReduceError::BadBasis {
                basis: name.to_string(),
                detail: format!("{} bases for a tensor of order {}", bases.len(), shape.len()),
            });
        }
        for (axis, (b, &n)) in bases.iter().zip(&shape).enumerate() {
            if b.full_dim() != n {
                return Err(ReduceError::BadBasis {
                    basis: name.to_string(),
                    detail: format!("axis {axis} has length {n}, its basis {} full dimensions", b.full_dim()),
                });
            }
        }
        totals.push(Tensor::zeros(&bases.iter().map(|b| b.reduced_dim()).collect::<Vec<_>>()));
    }
    let chunks = tensors.iter().map(|t| t.1.chunks()).max().unwrap_or(0);
    let share = options.ranks.share(chunks);
    let inner = PremultiplyOptions { progress: None, ..options };
    // Seconds per tensor: generating chunks, gathering rows, premultiplying.
    let mut seconds = vec![[0.0f64; 3]; tensors.len()];
    let mut buffers = Buffers::default();
    for c in share.clone() {
        let mut memo = RowMemo::default();
        for ((&(name, q, bases), total), time) in tensors.iter().zip(&mut totals).zip(&mut seconds) {
            if c >= q.chunks() {
                continue;
            }
            let clock = std::time::Instant::now();
            let mut rows = |axis: usize, list: &[usize]| memo.rows(bases[axis], list);
            if let Some(y) = q.premultiply_chunk(c, &mut rows) {
                let y = y?;
                if y.shape() != total.shape() {
                    return Err(ReduceError::BadBasis {
                        basis: name.to_string(),
                        detail: format!(
                            "chunk {c} premultiplied to shape {:?}, not {:?}",
                            y.shape(),
                            total.shape()
                        ),
                    });
                }
                for (t, v) in total.data_mut().iter_mut().zip(y.data()) {
                    *t += v;
                }
                time[2] += clock.elapsed().as_secs_f64();
                continue;
            }
            let part = q.chunk(c);
            time[0] += clock.elapsed().as_secs_f64();
            if part.nnz() == 0 {
                continue;
            }
            let declared: Vec<Option<Vec<usize>>> = (0..part.order()).map(|a| q.chunk_rows(c, a)).collect();
            let clock = std::time::Instant::now();
            let (local, rows) = localise(&part, &declared, bases, &mut memo)?;
            time[1] += clock.elapsed().as_secs_f64();
            let clock = std::time::Instant::now();
            let refs: Vec<&Tensor> = rows.iter().map(|r| r.as_ref()).collect();
            let (y, _) = premultiply_sparse_in(&local, &refs, inner, &mut buffers).map_err(|cause| {
                ReduceError::Tensor { context: format!("premultiplying `{name}` in chunks"), cause }
            })?;
            for (t, v) in total.data_mut().iter_mut().zip(y.data()) {
                *t += v;
            }
            time[2] += clock.elapsed().as_secs_f64();
        }
        if let Some(p) = options.progress {
            p((c + 1 - share.start) as f64, share.len() as f64);
        }
    }
    let mut parts: Vec<&mut [f64]> = totals.iter_mut().map(Tensor::data_mut).collect();
    allreduce_parts(options.ranks, &mut parts, "the premultiplied chunks")?;
    for ((name, ..), [generate, rows, multiply]) in tensors.iter().zip(&seconds) {
        tracing::debug!(tensor = name, generate, rows, multiply, "streamed premultiplication (seconds)");
    }
    Ok(totals)
}

/// Basis rows already gathered for the current chunk, by basis and row list: tensors chunked
/// alike ask for the same rows of a basis (the pair bases' whole rows of pairs), which is
/// computed once per chunk.
#[derive(Default)]
struct RowMemo {
    rows: Vec<(usize, Vec<usize>, Arc<Tensor>)>,
}

impl RowMemo {
    fn rows(&mut self, basis: &dyn BasisRows, list: &[usize]) -> Result<Arc<Tensor>, ReduceError> {
        let id = basis as *const dyn BasisRows as *const () as usize;
        if let Some((_, _, t)) = self.rows.iter().find(|(b, l, _)| *b == id && l == list) {
            return Ok(t.clone());
        }
        let t = Arc::new(basis.rows(list)?);
        self.rows.push((id, list.to_vec(), t.clone()));
        Ok(t)
    }
}

/// Position of a coordinate in a chunk's row list: a table over the list's span when that is
/// not much longer than the list (a block of whole rows of pairs, a few faces' vertices), else a
/// binary search (the transposed pairs, spread over all `n²`).
enum LocalIndex {
    Table { first: u32, slots: Vec<u32> },
    Sorted(Vec<(u32, u32)>),
}

impl LocalIndex {
    const EMPTY: u32 = u32::MAX;

    /// The index of `rows` (distinct; ascending as declared, but any order works).
    fn new(rows: &[u32]) -> Self {
        let (first, last) = rows.iter().fold((u32::MAX, 0), |(lo, hi), &i| (lo.min(i), hi.max(i)));
        if !rows.is_empty() && ((last - first) as usize) < 4 * rows.len() + (1 << 16) {
            let mut slots = vec![Self::EMPTY; (last - first) as usize + 1];
            for (l, &i) in rows.iter().enumerate() {
                slots[(i - first) as usize] = l as u32;
            }
            return LocalIndex::Table { first, slots };
        }
        let mut sorted: Vec<(u32, u32)> = rows.iter().enumerate().map(|(l, &i)| (i, l as u32)).collect();
        sorted.sort_unstable();
        LocalIndex::Sorted(sorted)
    }

    /// The position of coordinate `i`, if it is one of the rows.
    fn get(&self, i: u32) -> Option<u32> {
        match self {
            LocalIndex::Table { first, slots } => {
                let l = *slots.get(i.checked_sub(*first)? as usize)?;
                (l != Self::EMPTY).then_some(l)
            }
            LocalIndex::Sorted(rows) => rows.binary_search_by_key(&i, |&(v, _)| v).ok().map(|k| rows[k].1),
        }
    }
}

/// A chunk as a tensor over its own rows per axis — the declared ones, else its distinct
/// coordinates (ascending; one shared list per symmetric group, so sorted group indices stay
/// sorted) — with the matching basis rows.
fn localise(
    part: &SparseTensor,
    declared: &[Option<Vec<usize>>],
    bases: &[&dyn BasisRows],
    memo: &mut RowMemo,
) -> Result<(SparseTensor, Vec<Arc<Tensor>>), ReduceError> {
    let order = part.order();
    let groups = part.symmetric_groups().to_vec();
    // Axes sharing one list: each symmetric group, then every other axis alone.
    let mut sets: Vec<Vec<usize>> = groups.clone();
    for a in 0..order {
        if !groups.iter().any(|g| g.contains(&a)) {
            sets.push(vec![a]);
        }
    }
    let mut maps: Vec<Option<std::rc::Rc<LocalIndex>>> = vec![None; order];
    let mut lists: Vec<Vec<usize>> = vec![Vec::new(); order];
    for set in &sets {
        let distinct: Vec<u32> = match (set.as_slice(), declared[set[0]].as_ref()) {
            ([_], Some(rows)) => rows.iter().map(|&i| i as u32).collect(),
            _ => {
                let mut d: Vec<u32> =
                    part.coords().chunks_exact(order).flat_map(|c| set.iter().map(move |&a| c[a])).collect();
                d.sort_unstable();
                d.dedup();
                d
            }
        };
        let map = std::rc::Rc::new(LocalIndex::new(&distinct));
        for &a in set {
            maps[a] = Some(map.clone());
            lists[a] = distinct.iter().map(|&i| i as usize).collect();
        }
    }
    let maps: Vec<std::rc::Rc<LocalIndex>> =
        maps.into_iter().map(|m| m.expect("every axis in a set")).collect();
    let mut coords = Vec::with_capacity(part.coords().len());
    for c in part.coords().chunks_exact(order) {
        for a in 0..order {
            let Some(l) = maps[a].get(c[a]) else {
                return Err(ReduceError::BadBasis {
                    basis: "chunk".into(),
                    detail: format!(
                        "coordinate {} on axis {a} is not among the rows the chunk declared",
                        c[a]
                    ),
                });
            };
            coords.push(l);
        }
    }
    let shape: Vec<usize> = lists.iter().map(Vec::len).collect();
    let context = || "localising a chunk".to_string();
    let mut local = SparseTensor::from_coords("chunk", &shape, coords, part.values().to_vec())
        .map_err(|cause| ReduceError::Tensor { context: context(), cause })?;
    for g in &groups {
        local = local
            .with_symmetric_axes(g)
            .map_err(|cause| ReduceError::Tensor { context: context(), cause })?;
    }
    let rows = lists.iter().zip(bases).map(|(l, b)| memo.rows(*b, l)).collect::<Result<Vec<_>, _>>()?;
    Ok((local, rows))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reduce::premultiply_sparse;

    struct Split(SparseTensor, usize);

    impl TensorChunks for Split {
        fn shape(&self) -> Vec<usize> {
            self.0.shape().to_vec()
        }
        fn chunks(&self) -> usize {
            self.1
        }
        fn chunk(&self, c: usize) -> SparseTensor {
            let n = self.0.nnz();
            let (lo, hi) = (c * n / self.1, (c + 1) * n / self.1);
            let o = self.0.order();
            let mut t = SparseTensor::from_coords(
                "part",
                self.0.shape(),
                self.0.coords()[lo * o..hi * o].to_vec(),
                self.0.values()[lo..hi].to_vec(),
            )
            .unwrap();
            for g in self.0.symmetric_groups() {
                t = t.with_symmetric_axes(g).unwrap();
            }
            t
        }
    }

    /// Both kinds of chunk index find every row's position, in any order, and nothing else.
    #[test]
    fn local_indices_find_the_rows_and_only_them() {
        let near: Vec<u32> = vec![70, 12, 13, 40, 11];
        let spread: Vec<u32> = vec![5_000_000, 3, 900_000, 1 << 30, 77];
        for rows in [near, spread] {
            let index = LocalIndex::new(&rows);
            let table = matches!(index, LocalIndex::Table { .. });
            assert_eq!(table, rows[0] == 70, "a table only for a short span");
            for (l, &i) in rows.iter().enumerate() {
                assert_eq!(index.get(i), Some(l as u32));
            }
            for missing in [0, 2, 14, 69, 71, 4_999_999, u32::MAX] {
                assert_eq!(index.get(missing), None, "{missing}");
            }
        }
        assert_eq!(LocalIndex::new(&[]).get(0), None);
    }

    fn basis(n: usize, m: usize, seed: u64) -> Basis {
        let mut s = seed;
        let data: Vec<f64> = (0..n * m)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect();
        Basis::orthonormalize("random", &Tensor::from_vec(&[n, m], data).unwrap()).unwrap()
    }

    /// Chunked against whole, with a symmetric group, repeated coordinates across chunks and
    /// an axis whose coordinates reach outside each chunk's range.
    #[test]
    fn chunks_sum_to_the_whole_premultiplication() {
        let (n, g) = (40, 9);
        let mut q = SparseTensor::new(&[n, g, g, n]).with_symmetric_axes(&[1, 2]).unwrap();
        let mut s = 7u64;
        for k in 0..400 {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1);
            let r = (s >> 33) as usize;
            q.push(&[k % n, r % g, (r / g) % g, (r / 97) % n], ((r % 1000) as f64 - 500.0) / 250.0);
        }
        let (b0, b1, b3) = (basis(n, 5, 1), basis(g, 4, 2), basis(n, 3, 3));
        let whole = premultiply_sparse(&q, &[b0.matrix(), b1.matrix(), b1.matrix(), b3.matrix()]).unwrap();
        for chunks in [1, 3, 17] {
            let streamed = premultiply_streamed(
                "q",
                &Split(q.clone(), chunks),
                &[&b0, &b1, &b1, &b3],
                PremultiplyOptions::default(),
            )
            .unwrap();
            assert!(streamed.max_abs_diff(&whole) < 1e-12 * whole.max_abs(), "{chunks} chunks");
        }
        assert!(Split(q.clone(), 5).to_sparse().to_dense().max_abs_diff(&q.to_dense()) == 0.0);
    }
}
