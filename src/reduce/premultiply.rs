//! Premultiplication: `Q̂ = Q ⊗₀ B₀ ⊗₁ B₁ … ⊗_d B_d` (Eq. 2), the precompute that took the
//! paper's authors about half an hour on a 110-node cluster per scene.
//!
//! Never expanded as an outer product of all basis rows per nonzero. A sparse tensor is reduced
//! by a chain of sparse mode products over *units* — single axes, or whole symmetric groups of
//! axes — planned up front by cost (the way opt_einsum plans contraction paths):
//!
//! - a unit stage groups the entries by their remaining sparse coordinates, sums entries that
//!   share the unit's coordinates, and multiplies each group's stack of dense blocks by the
//!   matching basis rows;
//! - the last stage contracts every remaining unit at once: one GEMM whose left operand is the
//!   Khatri–Rao product of the entries' basis rows (built in bounded chunks) and whose right
//!   operand is the stack of blocks. For the fluid volume tensor that is the issue's
//!   `(m_p·m_u) × n_cells × m_g³` GEMM, after a per-entry stage over the geometry axes.
//!
//! A symmetric group (the volume tensor's three geometry axes, all in one basis) is contracted
//! as one unit and kept packed: only reduced indices `c₁ ≤ c₂ ≤ c₃` are computed and carried,
//! `m(m+1)(m+2)/6` values instead of `m³`, and expanded at the very end. For a stored entry
//! with sorted indices `(i₁, i₂, i₃)` the packed row is `S[c] = Σ_π Π_l B[π(i)_l, c_l]` over the
//! distinct permutations `π` — the entry stands for all of them.
//!
//! Each plan step is chosen from: every single unit, or finishing all units now; the cost of a
//! step counts its multiply–adds plus the finishing GEMM after it, and a step whose
//! intermediate would exceed the memory budget is not taken. Entry counts of every stage are
//! known before any arithmetic (they are distinct projections of the input's coordinates), so
//! progress is reported against the plan's total.

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicUsize, Ordering};

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;

use crate::tensor::{SparseTensor, Tensor, TensorError};

/// Rows gathered for one GEMM are bounded so that a chunk holds about this many values.
const KR_CHUNK_VALUES: usize = 1 << 22;

/// Options of a premultiplication.
#[derive(Clone, Copy)]
pub struct PremultiplyOptions<'a> {
    /// Largest intermediate (bytes) the planner may create.
    pub memory_budget: u64,
    /// Called with (multiply–adds done, multiply–adds planned) as stages progress.
    pub progress: Option<&'a (dyn Fn(f64, f64) + Sync)>,
}

impl Default for PremultiplyOptions<'_> {
    fn default() -> Self {
        Self { memory_budget: 4 << 30, progress: None }
    }
}

/// One contraction unit: an axis, or a symmetric group of axes sharing one basis.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Unit {
    /// A single axis.
    Axis(usize),
    /// A symmetric group (axes ascending).
    Group(Vec<usize>),
}

impl Unit {
    fn axes(&self) -> &[usize] {
        match self {
            Unit::Axis(a) => std::slice::from_ref(a),
            Unit::Group(g) => g,
        }
    }
}

/// The chosen plan.
#[derive(Clone, Debug, PartialEq)]
pub struct PremultiplyPlan {
    /// Stages in order, each the units it contracts.
    pub stages: Vec<Vec<Unit>>,
    /// Entries after each stage.
    pub entries: Vec<usize>,
    /// Multiply–adds of each stage.
    pub flops: Vec<f64>,
}

impl PremultiplyPlan {
    /// Total multiply–adds.
    pub fn total_flops(&self) -> f64 {
        self.flops.iter().sum()
    }
}

/// Sorted reduced index tuples of a symmetric group and their packed positions.
struct Packing {
    g: usize,
    m: usize,
    tuples: Vec<Vec<u32>>,
    /// Packed index of every tuple of `m^g`, sorted or not.
    index: Vec<u32>,
}

impl Packing {
    fn new(m: usize, g: usize) -> Self {
        let mut tuples = Vec::new();
        let mut t = vec![0u32; g];
        loop {
            tuples.push(t.clone());
            // Next non-decreasing tuple.
            let Some(k) = (0..g).rev().find(|&k| (t[k] as usize) < m - 1) else { break };
            let v = t[k] + 1;
            for x in &mut t[k..] {
                *x = v;
            }
        }
        let total = m.pow(g as u32);
        let mut index = vec![0u32; total];
        for (flat, slot) in index.iter_mut().enumerate() {
            let mut c: Vec<u32> = (0..g).map(|l| ((flat / m.pow((g - 1 - l) as u32)) % m) as u32).collect();
            c.sort_unstable();
            *slot = tuples.binary_search(&c).expect("sorted tuple is listed") as u32;
        }
        Self { g, m, tuples, index }
    }

    fn len(&self) -> usize {
        self.tuples.len()
    }
}

/// The unit vector of an entry: a basis row (axis) or a packed symmetrised row (group).
fn unit_row(
    unit: &Unit,
    coords: &[u32],
    bases: &[&Tensor],
    packings: &HashMap<Vec<usize>, Packing>,
    out: &mut Vec<f64>,
) {
    out.clear();
    match unit {
        Unit::Axis(a) => {
            let b = bases[*a];
            let m = b.shape()[1];
            let r = coords[0] as usize;
            out.extend_from_slice(&b.data()[r * m..(r + 1) * m]);
        }
        Unit::Group(axes) => {
            let p = &packings[axes];
            let b = bases[axes[0]].data();
            let m = p.m;
            out.resize(p.len(), 0.0);
            // Walk the distinct permutations of the (sorted) coordinates in place.
            let g = coords.len();
            let mut perm = [0u32; 8];
            perm[..g].copy_from_slice(coords);
            loop {
                for (t, tuple) in p.tuples.iter().enumerate() {
                    let mut prod = 1.0;
                    for (l, &c) in tuple.iter().enumerate() {
                        prod *= b[perm[l] as usize * m + c as usize];
                    }
                    out[t] += prod;
                }
                let Some(i) = (1..g).rev().find(|&i| perm[i - 1] < perm[i]) else { break };
                let j = (i..g).rev().find(|&j| perm[j] > perm[i - 1]).expect("a larger element exists");
                perm.swap(i - 1, j);
                perm[i..g].reverse();
            }
        }
    }
}

fn unit_size(unit: &Unit, bases: &[&Tensor], packings: &HashMap<Vec<usize>, Packing>) -> usize {
    match unit {
        Unit::Axis(a) => bases[*a].shape()[1],
        Unit::Group(g) => packings[g].len(),
    }
}

fn check_bases(q_shape: &[usize], bases: &[&Tensor]) -> Result<(), TensorError> {
    if bases.len() != q_shape.len() {
        return Err(TensorError::NoSuchAxis {
            what: "premultiply: one basis per axis".into(),
            axis: bases.len(),
            order: q_shape.len(),
        });
    }
    for (axis, (b, &n)) in bases.iter().zip(q_shape).enumerate() {
        if b.order() != 2 {
            return Err(TensorError::NotSquare {
                what: format!("basis of axis {axis}"),
                shape: b.shape().to_vec(),
            });
        }
        b.expect_axis(&format!("basis of axis {axis}"), 0, n)?;
    }
    Ok(())
}

/// `out (u × p) += Σ_r kr_r ⊗ a_r` for `rows` unit rows `kr` (r × u) and blocks `a` (r × p),
/// through faer's GEMM when it is large enough to pay (on every core when `parallel`).
fn accumulate(out: &mut [f64], kr: &[f64], a: &[f64], rows: usize, u: usize, p: usize, parallel: bool) {
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

/// A sparse intermediate: entries keyed by their coordinates on `sparse_axes`, each holding a
/// dense block over the units contracted so far (`dense`, outermost first).
struct Partial {
    sparse_axes: Vec<usize>,
    coords: Vec<u32>,
    dense: Vec<Unit>,
    block: usize,
    values: Vec<f64>,
}

impl Partial {
    fn entries(&self) -> usize {
        self.values.len() / self.block.max(1)
    }

    /// Entry order sorted by the coordinates at `key_pos`, then those at `unit_pos`.
    fn sorted(&self, key_pos: &[usize], unit_pos: &[usize]) -> Vec<usize> {
        let s = self.sparse_axes.len();
        let c = &self.coords;
        let mut idx: Vec<usize> = (0..self.entries()).collect();
        idx.par_sort_unstable_by(|&a, &b| {
            let ka = key_pos.iter().map(|&i| c[a * s + i]);
            let kb = key_pos.iter().map(|&i| c[b * s + i]);
            ka.cmp(kb).then_with(|| {
                unit_pos.iter().map(|&i| c[a * s + i]).cmp(unit_pos.iter().map(|&i| c[b * s + i]))
            })
        });
        idx
    }

    /// Contracts one unit: entries that agree on every other sparse axis form a group, and
    /// each group's blocks, summed where they share the unit's coordinates, are multiplied by
    /// the unit's rows (a small GEMM per group; one large parallel GEMM when a single group
    /// holds everything).
    fn contract_unit(
        self,
        unit: &Unit,
        bases: &[&Tensor],
        packings: &HashMap<Vec<usize>, Packing>,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Partial {
        self.contract_unit_into(unit, bases, packings, progress, Vec::new())
    }

    /// [`Partial::contract_unit`] writing into `recycled` (its pages already touched: large
    /// fresh allocations cost a page fault and, on a VM, a TLB shootdown per 4 KiB page).
    fn contract_unit_into(
        self,
        unit: &Unit,
        bases: &[&Tensor],
        packings: &HashMap<Vec<usize>, Packing>,
        progress: &(dyn Fn(f64) + Sync),
        recycled: Vec<f64>,
    ) -> Partial {
        let s = self.sparse_axes.len();
        let unit_pos: Vec<usize> = unit
            .axes()
            .iter()
            .map(|a| self.sparse_axes.iter().position(|x| x == a).expect("sparse"))
            .collect();
        let key_pos: Vec<usize> = (0..s).filter(|i| !unit_pos.contains(i)).collect();
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
        let mut values = recycled;
        values.clear();
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
    /// intermediates stay within a chunk.
    fn finish(
        self,
        units: &[Unit],
        bases: &[&Tensor],
        packings: &HashMap<Vec<usize>, Packing>,
        progress: &(dyn Fn(f64) + Sync),
    ) -> Partial {
        if units.len() == 1 {
            return self.contract_unit(&units[0], bases, packings, progress);
        }
        let (first, rest) = (&units[0], &units[1..]);
        let s = self.sparse_axes.len();
        let first_pos: Vec<usize> = first
            .axes()
            .iter()
            .map(|a| self.sparse_axes.iter().position(|x| x == a).expect("sparse"))
            .collect();
        let size = unit_size(first, bases, packings);
        let rest_size: usize = rest.iter().map(|u| unit_size(u, bases, packings)).product();
        let w_block = rest_size * self.block;
        let idx = self.sorted(&first_pos, &[]);
        let first_of = |e: usize| first_pos.iter().map(|&i| self.coords[e * s + i]).collect::<Vec<u32>>();
        // Chunks of whole first-unit groups, each chunk's W within KR_CHUNK_VALUES · 4.
        let per_chunk = (4 * KR_CHUNK_VALUES / w_block.max(1)).max(1);
        let mut out = vec![0.0; size * w_block];
        let mut i = 0;
        let total = idx.len().max(1);
        let mut row = Vec::new();
        let mut recycled: Vec<f64> = Vec::new();
        let mut rows_m: Vec<f64> = Vec::new();
        while i < idx.len() {
            let mut j = i;
            let mut distinct = 0;
            while j < idx.len() && (distinct < per_chunk || first_of(idx[j]) == first_of(idx[j - 1])) {
                if j == i || first_of(idx[j]) != first_of(idx[j - 1]) {
                    distinct += 1;
                }
                j += 1;
            }
            let chunk = Partial {
                sparse_axes: self.sparse_axes.clone(),
                coords: idx[i..j]
                    .iter()
                    .flat_map(|&e| self.coords[e * s..(e + 1) * s].iter().copied())
                    .collect(),
                dense: Vec::new(),
                block: self.block,
                values: idx[i..j]
                    .iter()
                    .flat_map(|&e| self.values[e * self.block..(e + 1) * self.block].iter().copied())
                    .collect(),
            };
            let t0 = std::time::Instant::now();
            let (base, span) = (i, j - i);
            let sub_progress = |f: f64| progress((base as f64 + f * span as f64) / total as f64);
            // Innermost first, so W's block is laid out as [rest…, previous dense].
            let mut w = chunk;
            for u in rest.iter().rev() {
                w = w.contract_unit_into(u, bases, packings, &sub_progress, std::mem::take(&mut recycled));
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
            recycled = w.values;
            i = j;
        }
        let mut dense = units.to_vec();
        dense.extend(self.dense);
        Partial { sparse_axes: Vec::new(), coords: Vec::new(), dense, block: size * w_block, values: out }
    }
}

/// Number of distinct projections of `q`'s coordinates onto `axes`.
fn distinct_on(q: &SparseTensor, axes: &[usize]) -> usize {
    if axes.is_empty() {
        return 1;
    }
    let order = q.order();
    if axes.len() <= 4 {
        let mut keys: Vec<u128> = q
            .coords()
            .par_chunks(order)
            .map(|c| axes.iter().fold(0u128, |k, &a| (k << 32) | u128::from(c[a])))
            .collect();
        keys.par_sort_unstable();
        keys.dedup();
        return keys.len();
    }
    let set: HashSet<Vec<u32>> =
        q.coords().par_chunks(order).map(|c| axes.iter().map(|&a| c[a]).collect::<Vec<u32>>()).collect();
    set.len()
}

/// Plans the stages (see the module docs).
fn plan(q: &SparseTensor, units: &[Unit], sizes: &[usize], budget: u64) -> PremultiplyPlan {
    let mut remaining: Vec<usize> = (0..units.len()).collect();
    let mut cache: HashMap<Vec<usize>, usize> = HashMap::new();
    let mut distinct = |rem: &[usize]| -> usize {
        let mut axes: Vec<usize> = rem.iter().flat_map(|&u| units[u].axes().iter().copied()).collect();
        axes.sort_unstable();
        *cache.entry(axes.clone()).or_insert_with(|| distinct_on(q, &axes))
    };
    let mut plan = PremultiplyPlan { stages: Vec::new(), entries: Vec::new(), flops: Vec::new() };
    let mut entries = q.nnz();
    let mut block = 1usize;
    let budget_values = (budget / 8) as f64;
    while !remaining.is_empty() {
        let all: f64 = remaining.iter().map(|&u| sizes[u] as f64).product();
        let finish_cost = entries as f64 * block as f64 * all;
        let mut best: (bool, f64, Vec<usize>, usize) =
            (block as f64 * all <= budget_values, finish_cost, remaining.clone(), 1);
        if remaining.len() > 1 {
            for (k, &u) in remaining.iter().enumerate() {
                let mut rest = remaining.clone();
                rest.remove(k);
                let d = distinct(&rest);
                let s = sizes[u] as f64;
                let rest_all: f64 = rest.iter().map(|&v| sizes[v] as f64).product();
                let cost = entries as f64 * block as f64 * s + d as f64 * block as f64 * s * rest_all;
                let fits = d as f64 * block as f64 * s <= budget_values;
                if (fits, -cost) > (best.0, -best.1) {
                    best = (fits, cost, vec![u], d);
                }
            }
        }
        let (_, _, chosen, d) = best;
        let s: f64 = chosen.iter().map(|&u| sizes[u] as f64).product();
        plan.flops.push(entries as f64 * block as f64 * s);
        plan.stages.push(chosen.iter().map(|&u| units[u].clone()).collect());
        remaining.retain(|u| !chosen.contains(u));
        entries = if remaining.is_empty() { 1 } else { d };
        block *= s as usize;
        plan.entries.push(entries);
    }
    plan
}

/// `Q̂` of a sparse tensor (symmetric groups included) by the planned chain. Returns the dense
/// reduced tensor with axes in `Q`'s order.
pub fn premultiply_sparse(q: &SparseTensor, bases: &[&Tensor]) -> Result<Tensor, TensorError> {
    Ok(premultiply_sparse_with(q, bases, PremultiplyOptions::default())?.0)
}

/// [`premultiply_sparse`] with options, also returning the plan it followed.
pub fn premultiply_sparse_with(
    q: &SparseTensor,
    bases: &[&Tensor],
    options: PremultiplyOptions<'_>,
) -> Result<(Tensor, PremultiplyPlan), TensorError> {
    check_bases(q.shape(), bases)?;
    let reduced_shape: Vec<usize> = bases.iter().map(|b| b.shape()[1]).collect();
    let mut units: Vec<Unit> = Vec::new();
    let mut packings = HashMap::new();
    for g in q.symmetric_groups() {
        for &a in &g[1..] {
            if bases[a] != bases[g[0]] {
                return Err(TensorError::NotFinite {
                    what: "premultiply".into(),
                    detail: format!("symmetric axes {g:?} need one basis, axis {a} has another"),
                });
            }
        }
        let m = bases[g[0]].shape()[1];
        if m.checked_pow(g.len() as u32).is_none_or(|v| v > 1 << 24) {
            return Err(TensorError::NotFinite {
                what: "premultiply".into(),
                detail: format!("symmetric group {g:?} with {m} reduced dimensions is too large to pack"),
            });
        }
        packings.insert(g.clone(), Packing::new(m, g.len()));
        units.push(Unit::Group(g.clone()));
    }
    for a in 0..q.order() {
        if !q.symmetric_groups().iter().any(|g| g.contains(&a)) {
            units.push(Unit::Axis(a));
        }
    }
    units.sort_by_key(|u| u.axes()[0]);
    if q.nnz() == 0 {
        return Ok((
            Tensor::zeros(&reduced_shape),
            PremultiplyPlan { stages: Vec::new(), entries: Vec::new(), flops: Vec::new() },
        ));
    }
    let sizes: Vec<usize> = units.iter().map(|u| unit_size(u, bases, &packings)).collect();
    let plan = plan(q, &units, &sizes, options.memory_budget);
    let total = plan.total_flops();
    let mut done = 0.0;
    let mut part = Partial {
        sparse_axes: (0..q.order()).collect(),
        coords: q.coords().to_vec(),
        dense: Vec::new(),
        block: 1,
        values: q.values().to_vec(),
    };
    for (stage, flops) in plan.stages.iter().zip(&plan.flops) {
        let report = |f: f64| {
            if let Some(p) = options.progress {
                p(done + f * flops, total);
            }
        };
        let t = std::time::Instant::now();
        part = part.finish(stage, bases, &packings, &report);
        tracing::debug!(
            ?stage,
            entries = part.entries(),
            seconds = t.elapsed().as_secs_f64(),
            "premultiply stage"
        );
        done += flops;
    }
    // Expand the packed result into the full reduced tensor, axes in Q's order.
    let dense_sizes: Vec<usize> = part.dense.iter().map(|u| unit_size(u, bases, &packings)).collect();
    let mut strides = vec![1usize; dense_sizes.len()];
    for k in (0..dense_sizes.len().saturating_sub(1)).rev() {
        strides[k] = strides[k + 1] * dense_sizes[k + 1];
    }
    let mut out = Tensor::zeros(&reduced_shape);
    let mut index = vec![0usize; reduced_shape.len()];
    for v in out.data_mut() {
        let mut offset = 0;
        for (u, st) in part.dense.iter().zip(&strides) {
            let i = match u {
                Unit::Axis(a) => index[*a],
                Unit::Group(g) => {
                    let p = &packings[g];
                    let flat = g.iter().fold(0, |f, &a| f * p.m + index[a]);
                    debug_assert_eq!(p.g, g.len());
                    p.index[flat] as usize
                }
            };
            offset += i * st;
        }
        *v = part.values[offset];
        for a in (0..index.len()).rev() {
            index[a] += 1;
            if index[a] < reduced_shape[a] {
                break;
            }
            index[a] = 0;
        }
    }
    Ok((out, plan))
}

/// `Q̂` of a dense tensor: one GEMM per axis, the axis with the largest `n/m` first.
pub fn premultiply_dense(q: &Tensor, bases: &[&Tensor]) -> Result<Tensor, TensorError> {
    check_bases(q.shape(), bases)?;
    let mut order: Vec<usize> = (0..q.order()).collect();
    order.sort_by(|&a, &b| {
        let r = |k: usize| bases[k].shape()[1] as f64 / bases[k].shape()[0] as f64;
        r(a).total_cmp(&r(b))
    });
    let mut t = q.clone();
    for axis in order {
        let b = bases[axis];
        let (n, m) = (b.shape()[0], b.shape()[1]);
        let outer: usize = t.shape()[..axis].iter().product();
        let inner: usize = t.shape()[axis + 1..].iter().product();
        let mut out = vec![0.0; outer * m * inner];
        for o in 0..outer {
            let a = &t.data()[o * n * inner..(o + 1) * n * inner];
            accumulate(&mut out[o * m * inner..(o + 1) * m * inner], b.data(), a, n, m, inner, outer == 1);
        }
        let mut shape = t.shape().to_vec();
        shape[axis] = m;
        t = Tensor::from_vec(&shape, out)?;
    }
    Ok(t)
}
