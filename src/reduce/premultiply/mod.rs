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
//! Each plan step is chosen from: every single unit, or finishing all units now (streamed, in
//! the units' cheapest order); the cost of a step counts its multiply–adds plus those of the
//! units after it in their cheapest order (exhaustive: a unit's stage leaves one entry per
//! distinct coordinate on the units still to come), and a step whose intermediate would exceed
//! the memory budget is not taken. Entry counts of every stage are
//! known before any arithmetic (they are distinct projections of the input's coordinates), so
//! progress is reported against the plan's total.

use std::collections::HashMap;

use super::ranks::{Communicator, SINGLE_RANK};
use crate::tensor::{SparseTensor, Tensor, TensorError};

mod cpu;
mod gpu;
mod plan;
mod stream;

pub(crate) use cpu::Buffers;
use cpu::{accumulate, Partial};
pub use gpu::{premultiply_sparse_gpu, premultiply_sparse_on};
use plan::plan;
pub(crate) use plan::{unit_row, unit_size, Packing};
pub use stream::{premultiply_streamed, premultiply_streamed_together, AxisRows, BasisRows, TensorChunks};

/// Options of a premultiplication.
#[derive(Clone, Copy)]
pub struct PremultiplyOptions<'a> {
    /// Largest intermediate (bytes) the planner may create.
    pub memory_budget: u64,
    /// Called with (multiply–adds done, multiply–adds planned) as stages progress.
    pub progress: Option<&'a (dyn Fn(f64, f64) + Sync)>,
    /// The ranks a streamed tensor's chunks are shared over ([`premultiply_streamed_together`]):
    /// one rank by default.
    pub ranks: &'a dyn Communicator,
}

impl Default for PremultiplyOptions<'_> {
    fn default() -> Self {
        Self { memory_budget: 4 << 30, progress: None, ranks: &SINGLE_RANK }
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

pub(crate) fn check_bases(q_shape: &[usize], bases: &[&Tensor]) -> Result<(), TensorError> {
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

/// Units, packings and sizes of a premultiplication, and its plan.
pub(crate) struct Setup {
    pub packings: HashMap<Vec<usize>, Packing>,
    pub reduced_shape: Vec<usize>,
    pub plan: PremultiplyPlan,
}

impl Setup {
    /// Checks the bases, forms the units (symmetric groups need one basis) and plans.
    pub fn new(q: &SparseTensor, bases: &[&Tensor], budget: u64) -> Result<Self, TensorError> {
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
        let plan = if q.nnz() == 0 {
            PremultiplyPlan { stages: Vec::new(), entries: Vec::new(), flops: Vec::new() }
        } else {
            let sizes: Vec<usize> = units.iter().map(|u| unit_size(u, bases, &packings)).collect();
            plan(q, &units, &sizes, budget)
        };
        Ok(Self { packings, reduced_shape, plan })
    }

    /// The full reduced tensor (axes in Q's order) from the final packed block laid out as
    /// `dense` (outermost first).
    pub fn expand(&self, dense: &[Unit], bases: &[&Tensor], values: &[f64]) -> Tensor {
        let dense_sizes: Vec<usize> = dense.iter().map(|u| unit_size(u, bases, &self.packings)).collect();
        let mut strides = vec![1usize; dense_sizes.len()];
        for k in (0..dense_sizes.len().saturating_sub(1)).rev() {
            strides[k] = strides[k + 1] * dense_sizes[k + 1];
        }
        let shape = &self.reduced_shape;
        let mut out = Tensor::zeros(shape);
        let mut index = vec![0usize; shape.len()];
        for v in out.data_mut() {
            let mut offset = 0;
            for (u, st) in dense.iter().zip(&strides) {
                let i = match u {
                    Unit::Axis(a) => index[*a],
                    Unit::Group(g) => {
                        let p = &self.packings[g];
                        p.index[g.iter().fold(0, |f, &a| f * p.m + index[a])] as usize
                    }
                };
                offset += i * st;
            }
            *v = values[offset];
            for a in (0..index.len()).rev() {
                index[a] += 1;
                if index[a] < shape[a] {
                    break;
                }
                index[a] = 0;
            }
        }
        out
    }
}

/// `Q̂` of a sparse tensor (symmetric groups included) by the planned chain, on the CPU.
/// Returns the dense reduced tensor with axes in `Q`'s order.
pub fn premultiply_sparse(q: &SparseTensor, bases: &[&Tensor]) -> Result<Tensor, TensorError> {
    Ok(premultiply_sparse_with(q, bases, PremultiplyOptions::default())?.0)
}

/// [`premultiply_sparse`] with options, also returning the plan it followed.
pub fn premultiply_sparse_with(
    q: &SparseTensor,
    bases: &[&Tensor],
    options: PremultiplyOptions<'_>,
) -> Result<(Tensor, PremultiplyPlan), TensorError> {
    premultiply_sparse_in(q, bases, options, &mut Buffers::default())
}

/// [`premultiply_sparse_with`] with its intermediates in `buffers` (kept by a caller that
/// premultiplies many chunks).
pub(crate) fn premultiply_sparse_in(
    q: &SparseTensor,
    bases: &[&Tensor],
    options: PremultiplyOptions<'_>,
    buffers: &mut Buffers,
) -> Result<(Tensor, PremultiplyPlan), TensorError> {
    let setup = Setup::new(q, bases, options.memory_budget)?;
    if q.nnz() == 0 {
        return Ok((Tensor::zeros(&setup.reduced_shape), setup.plan));
    }
    let total = setup.plan.total_flops();
    let mut done = 0.0;
    let mut part = Partial {
        sparse_axes: (0..q.order()).collect(),
        coords: q.coords().to_vec(),
        dense: Vec::new(),
        block: 1,
        values: {
            let mut v = buffers.take();
            v.extend_from_slice(q.values());
            v
        },
    };
    for (stage, flops) in setup.plan.stages.iter().zip(&setup.plan.flops) {
        let report = |f: f64| {
            if let Some(p) = options.progress {
                p(done + f * flops, total);
            }
        };
        let t = std::time::Instant::now();
        part = part.finish(stage, bases, &setup.packings, &report, buffers);
        tracing::debug!(
            ?stage,
            entries = part.entries(),
            seconds = t.elapsed().as_secs_f64(),
            "premultiply stage"
        );
        done += flops;
    }
    let out = setup.expand(&part.dense, bases, &part.values);
    buffers.give(part.values);
    Ok((out, setup.plan))
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
