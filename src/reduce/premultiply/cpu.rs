//! The CPU stages: sparse unit contractions and the streamed final GEMMs, in f64 with faer.

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

use super::plan::{chunks_of_groups, sorted_entries, unit_and_key_positions, unit_positions};
use super::{unit_row, unit_size, Packing, Unit};
use crate::tensor::Tensor;

/// Rows gathered for one GEMM are bounded so that a chunk holds about this many values.
pub(crate) const KR_CHUNK_VALUES: usize = 1 << 22;

/// `out (u × p) += Σ_r kr_r ⊗ a_r` for `rows` unit rows `kr` (r × u) and blocks `a` (r × p),
/// through faer's GEMM when it is large enough to pay (on every core when `parallel`).
pub(crate) fn accumulate(
    out: &mut [f64],
    kr: &[f64],
    a: &[f64],
    rows: usize,
    u: usize,
    p: usize,
    parallel: bool,
) {
    if rows >= 8 && u * p >= 64 {
        let k = MatRef::from_row_major_slice(kr, rows, u);
        let am = MatRef::from_row_major_slice(a, rows, p);
        let om = MatMut::from_row_major_slice_mut(out, u, p);
        let par = if parallel { Par::rayon(0) } else { Par::Seq };
        matmul(om, Accum::Add, k.transpose(), am, 1.0, par);
    } else {
        for r in 0..rows {
            let arow = &a[r * p..(r + 1) * p];
            for t in 0..u {
                let w = kr[r * u + t];
                if w != 0.0 {
                    for (o, &v) in out[t * p..(t + 1) * p].iter_mut().zip(arow) {
                        *o += w * v;
                    }
                }
            }
        }
    }
}

/// Value buffers kept between stages and between the chunks of a streamed premultiplication: a
/// fresh allocation of a hundred MB or more costs a page fault (and, on a VM, a TLB shootdown)
/// per 4 KiB page — 1,133 s of system time in the 4,974-face radiosity training before.
#[derive(Default)]
pub(crate) struct Buffers(Vec<Vec<f64>>);

impl Buffers {
    /// At most this many buffers are kept.
    const KEPT: usize = 4;

    /// An empty buffer, the largest kept one if any.
    pub fn take(&mut self) -> Vec<f64> {
        let largest = (0..self.0.len()).max_by_key(|&i| self.0[i].capacity());
        let mut v = largest.map(|i| self.0.swap_remove(i)).unwrap_or_default();
        v.clear();
        v
    }

    /// Keeps `v` for a later [`Buffers::take`] (dropping the smallest beyond [`Buffers::KEPT`]).
    pub fn give(&mut self, v: Vec<f64>) {
        if v.capacity() == 0 {
            return;
        }
        self.0.push(v);
        if self.0.len() > Self::KEPT {
            let smallest = (0..self.0.len()).min_by_key(|&i| self.0[i].capacity()).expect("not empty");
            self.0.swap_remove(smallest);
        }
    }
}

/// A sparse intermediate: entries keyed by their coordinates on `sparse_axes`, each holding a
/// dense block over the units contracted so far (`dense`, outermost first).
pub(crate) struct Partial {
    pub sparse_axes: Vec<usize>,
    pub coords: Vec<u32>,
    pub dense: Vec<Unit>,
    pub block: usize,
    pub values: Vec<f64>,
}

impl Partial {
    pub fn entries(&self) -> usize {
        self.values.len() / self.block.max(1)
    }

    /// Entry order sorted by the coordinates at `key_pos`, then those at `unit_pos`.
    pub fn sorted(&self, key_pos: &[usize], unit_pos: &[usize]) -> Vec<usize> {
        if self.sparse_axes.is_empty() {
            return (0..self.entries()).collect();
        }
        sorted_entries(&self.coords, self.sparse_axes.len(), key_pos, unit_pos)
    }

    /// Contracts one unit: entries that agree on every other sparse axis form a group, and
    /// each group's blocks, summed where they share the unit's coordinates, are multiplied by
    /// the unit's rows (a small GEMM per group; one large parallel GEMM when a single group
    /// holds everything). Its output is written into a buffer from `buffers`, and its input's
    /// values go back there.
    fn contract_unit(
        self,
        unit: &Unit,
        bases: &[&Tensor],
        packings: &HashMap<Vec<usize>, Packing>,
        progress: &(dyn Fn(f64) + Sync),
        buffers: &mut Buffers,
    ) -> Partial {
        let s = self.sparse_axes.len();
        let (unit_pos, key_pos) = unit_and_key_positions(&self.sparse_axes, unit);
        let size = unit_size(unit, bases, packings);
        let block = self.block;
        let coords = &self.coords;
        let key = |e: usize| key_pos.iter().map(move |&i| coords[e * s + i]);
        let ucoords = |e: usize| unit_pos.iter().map(move |&i| coords[e * s + i]);
        let idx = self.sorted(&key_pos, &unit_pos);
        let mut starts = vec![0];
        for i in 1..idx.len() {
            if !key(idx[i - 1]).eq(key(idx[i])) {
                starts.push(i);
            }
        }
        starts.push(idx.len());
        let single_group = starts.len() == 2;
        let chunk_rows = (KR_CHUNK_VALUES / (size + block).max(1)).max(1);
        let done = AtomicUsize::new(0);
        let total = idx.len().max(1);
        let groups = starts.len() - 1;
        let mut values = buffers.take();
        values.resize(groups * size * block, 0.0);
        values.par_chunks_mut(size * block).zip(starts.par_windows(2)).for_each(|(out, w)| {
            let (i, j) = (w[0], w[1]);
            let (mut rows_m, mut stacked, mut row) = (Vec::new(), Vec::new(), Vec::new());
            let mut rows = 0;
            let mut k = i;
            let mut flushed = i;
            while k < j {
                let e = idx[k];
                let start = stacked.len();
                stacked.extend_from_slice(&self.values[e * block..(e + 1) * block]);
                k += 1;
                while k < j && ucoords(idx[k]).eq(ucoords(e)) {
                    let f = idx[k];
                    for (d, &v) in stacked[start..].iter_mut().zip(&self.values[f * block..(f + 1) * block]) {
                        *d += v;
                    }
                    k += 1;
                }
                let c: Vec<u32> = ucoords(e).collect();
                unit_row(unit, &c, bases, packings, &mut row);
                rows_m.extend_from_slice(&row);
                rows += 1;
                if rows == chunk_rows || k == j {
                    accumulate(out, &rows_m, &stacked, rows, size, block, single_group);
                    rows_m.clear();
                    stacked.clear();
                    rows = 0;
                    let n = done.fetch_add(k - flushed, Ordering::Relaxed) + (k - flushed);
                    flushed = k;
                    progress(n.min(total) as f64 / total as f64);
                }
            }
        });
        let coords: Vec<u32> = starts[..groups].iter().flat_map(|&i| key(idx[i])).collect();
        let mut dense = vec![unit.clone()];
        dense.extend(self.dense);
        buffers.give(self.values);
        Partial {
            sparse_axes: key_pos.iter().map(|&i| self.sparse_axes[i]).collect(),
            coords,
            dense,
            block: size * block,
            values,
        }
    }

    /// Contracts all of `units` (every sparse unit left) into one dense block, streaming over
    /// the first unit's coordinates: for a chunk of them, the other units are contracted
    /// (recursively) into `W` (chunk × rest), then `out += B_firstᵀ[chunk] · W` — a GEMM with
    /// the first unit's size by the rest's, so no Khatri–Rao product is ever materialised and
    /// intermediates stay within a chunk (in buffers from `buffers`, which get this partial's
    /// values back).
    pub fn finish(
        self,
        units: &[Unit],
        bases: &[&Tensor],
        packings: &HashMap<Vec<usize>, Packing>,
        progress: &(dyn Fn(f64) + Sync),
        buffers: &mut Buffers,
    ) -> Partial {
        if units.len() == 1 {
            return self.contract_unit(&units[0], bases, packings, progress, buffers);
        }
        let (first, rest) = (&units[0], &units[1..]);
        let s = self.sparse_axes.len();
        let first_pos = unit_positions(&self.sparse_axes, first);
        let size = unit_size(first, bases, packings);
        let rest_size: usize = rest.iter().map(|u| unit_size(u, bases, packings)).product();
        let w_block = rest_size * self.block;
        let idx = self.sorted(&first_pos, &[]);
        let first_of = |e: usize| first_pos.iter().map(|&i| self.coords[e * s + i]).collect::<Vec<u32>>();
        // Chunks of whole first-unit groups, each chunk's W within KR_CHUNK_VALUES · 4.
        let per_chunk = (4 * KR_CHUNK_VALUES / w_block.max(1)).max(1);
        let mut out = vec![0.0; size * w_block];
        let total = idx.len().max(1);
        let mut row = Vec::new();
        let mut rows_m: Vec<f64> = Vec::new();
        for range in chunks_of_groups(&idx, first_of, per_chunk) {
            let (i, j) = (range.start, range.end);
            let chunk = Partial {
                sparse_axes: self.sparse_axes.clone(),
                coords: idx[i..j]
                    .iter()
                    .flat_map(|&e| self.coords[e * s..(e + 1) * s].iter().copied())
                    .collect(),
                dense: Vec::new(),
                block: self.block,
                values: {
                    let mut v = buffers.take();
                    for &e in &idx[i..j] {
                        v.extend_from_slice(&self.values[e * self.block..(e + 1) * self.block]);
                    }
                    v
                },
            };
            let t0 = std::time::Instant::now();
            let (base, span) = (i, j - i);
            let sub_progress = |f: f64| progress((base as f64 + f * span as f64) / total as f64);
            // Innermost first, so W's block is laid out as [rest…, previous dense].
            let mut w = chunk;
            for u in rest.iter().rev() {
                w = w.contract_unit(u, bases, packings, &sub_progress, buffers);
            }
            let t1 = t0.elapsed();
            // W's entries are keyed by the first unit's coordinates only.
            let d = w.entries();
            rows_m.clear();
            for e in 0..d {
                unit_row(
                    first,
                    &w.coords[e * first_pos.len()..(e + 1) * first_pos.len()],
                    bases,
                    packings,
                    &mut row,
                );
                rows_m.extend_from_slice(&row);
            }
            accumulate(&mut out, &rows_m, &w.values, d, size, w_block, true);
            tracing::trace!(
                chunk = j - i,
                contract = t1.as_secs_f64(),
                total = t0.elapsed().as_secs_f64(),
                "finish chunk"
            );
            buffers.give(w.values);
        }
        buffers.give(self.values);
        let mut dense = units.to_vec();
        dense.extend(self.dense);
        Partial { sparse_axes: Vec::new(), coords: Vec::new(), dense, block: size * w_block, values: out }
    }
}
