//! Premultiplication: `Q̂ = Q ⊗₀ B₀ ⊗₁ B₁ … ⊗_d B_d` (Eq. 2), the precompute that took the
//! paper's authors about half an hour on a 110-node cluster per scene.
//!
//! Never expanded as an outer product of basis rows per nonzero. A sparse tensor is reduced by
//! a chain of sparse mode products, one axis at a time, in an order chosen by cost (the way
//! opt_einsum picks contraction paths): each stage groups the entries by their remaining sparse
//! coordinates, sums entries that share the contracted coordinate, and multiplies each group's
//! stack of dense blocks by the matching rows of the basis — a GEMM, large exactly when it
//! matters (the last stages, where one group holds everything). Dense tensors take one GEMM per
//! axis, the axis that shrinks most first.

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

use crate::tensor::{SparseTensor, Tensor, TensorError};

/// Groups at least this large go through faer's GEMM; smaller ones use a plain loop.
const GEMM_MIN_ROWS: usize = 8;

/// `out (m × p) += Bᵀ_rows · A` where `rows[g]` picks the basis row matching `A`'s row `g`:
/// `out[t][:] += Σ_g B[rows[g]][t] · A[g][:]`.
fn accumulate(out: &mut [f64], basis: &Tensor, rows: &[u32], a: &[f64], p: usize) {
    let m = basis.shape()[1];
    let b = basis.data();
    if rows.len() >= GEMM_MIN_ROWS && p * m >= 64 {
        let gathered: Vec<f64> =
            rows.iter().flat_map(|&r| b[r as usize * m..(r as usize + 1) * m].iter().copied()).collect();
        let bg = MatRef::from_row_major_slice(&gathered, rows.len(), m);
        let am = MatRef::from_row_major_slice(a, rows.len(), p);
        let om = MatMut::from_row_major_slice_mut(out, m, p);
        matmul(om, Accum::Add, bg.transpose(), am, 1.0, Par::rayon(0));
    } else {
        for (g, &r) in rows.iter().enumerate() {
            let arow = &a[g * p..(g + 1) * p];
            for t in 0..m {
                let w = b[r as usize * m + t];
                if w != 0.0 {
                    for (o, &v) in out[t * p..(t + 1) * p].iter_mut().zip(arow) {
                        *o += w * v;
                    }
                }
            }
        }
    }
}

fn check_bases(shape: &[usize], bases: &[&Tensor]) -> Result<(), TensorError> {
    if bases.len() != shape.len() {
        return Err(TensorError::NoSuchAxis {
            what: "premultiply: one basis per axis".into(),
            axis: bases.len(),
            order: shape.len(),
        });
    }
    for (axis, (b, &n)) in bases.iter().zip(shape).enumerate() {
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
        let rows: Vec<u32> = (0..n as u32).collect();
        for o in 0..outer {
            let a = &t.data()[o * n * inner..(o + 1) * n * inner];
            accumulate(&mut out[o * m * inner..(o + 1) * m * inner], b, &rows, a, inner);
        }
        let mut shape = t.shape().to_vec();
        shape[axis] = m;
        t = Tensor::from_vec(&shape, out)?;
    }
    Ok(t)
}

/// The contraction order chosen for a sparse tensor and what each stage leaves.
#[derive(Clone, Debug, PartialEq)]
pub struct PremultiplyPlan {
    /// Axes in the order they are contracted.
    pub order: Vec<usize>,
    /// Entries (distinct remaining sparse coordinates) after each stage.
    pub entries: Vec<usize>,
    /// Multiply–adds of all stages.
    pub flops: f64,
}

/// A sparse intermediate: entries keyed by their remaining sparse coordinates, each holding a
/// dense block over the axes contracted so far (the latest outermost).
struct Partial {
    sparse_axes: Vec<usize>,
    coords: Vec<u32>,
    dense_axes: Vec<usize>,
    block: usize,
    values: Vec<f64>,
}

impl Partial {
    fn entries(&self) -> usize {
        self.values.len() / self.block.max(1)
    }

    fn key<'a>(&'a self, e: usize, skip: usize) -> impl Iterator<Item = u32> + 'a {
        let s = self.sparse_axes.len();
        self.coords[e * s..(e + 1) * s].iter().enumerate().filter(move |(i, _)| *i != skip).map(|(_, &c)| c)
    }

    /// Entry indices sorted by their coordinates without position `skip`, then by `skip`'s.
    fn sorted_without(&self, skip: usize) -> Vec<usize> {
        let s = self.sparse_axes.len();
        let mut idx: Vec<usize> = (0..self.entries()).collect();
        idx.sort_unstable_by(|&a, &b| {
            self.key(a, skip)
                .cmp(self.key(b, skip))
                .then(self.coords[a * s + skip].cmp(&self.coords[b * s + skip]))
        });
        idx
    }

    fn distinct_without(&self, skip: usize) -> usize {
        let idx = self.sorted_without(skip);
        1 + idx.windows(2).filter(|w| !self.key(w[0], skip).eq(self.key(w[1], skip))).count()
    }

    /// Contracts sparse position `p` with `basis`.
    fn contract(self, p: usize, basis: &Tensor) -> Partial {
        let s = self.sparse_axes.len();
        let m = basis.shape()[1];
        let (block, nb) = (self.block, m * self.block);
        let idx = self.sorted_without(p);
        let mut coords = Vec::new();
        let mut values = Vec::new();
        let mut i = 0;
        while i < idx.len() {
            // One group: equal coordinates apart from position p.
            let mut j = i + 1;
            while j < idx.len() && self.key(idx[i], p).eq(self.key(idx[j], p)) {
                j += 1;
            }
            // Within it, sum the blocks of entries that share the contracted coordinate.
            let mut rows = Vec::new();
            let mut stacked = Vec::new();
            let mut k = i;
            while k < j {
                let c = self.coords[idx[k] * s + p];
                let start = stacked.len();
                stacked.extend_from_slice(&self.values[idx[k] * block..(idx[k] + 1) * block]);
                k += 1;
                while k < j && self.coords[idx[k] * s + p] == c {
                    for (d, &v) in
                        stacked[start..].iter_mut().zip(&self.values[idx[k] * block..(idx[k] + 1) * block])
                    {
                        *d += v;
                    }
                    k += 1;
                }
                rows.push(c);
            }
            let out_start = values.len();
            values.resize(out_start + nb, 0.0);
            accumulate(&mut values[out_start..], basis, &rows, &stacked, block);
            coords.extend(self.key(idx[i], p));
            i = j;
        }
        let mut sparse_axes = self.sparse_axes.clone();
        let axis = sparse_axes.remove(p);
        let mut dense_axes = vec![axis];
        dense_axes.extend(&self.dense_axes);
        Partial { sparse_axes, coords, dense_axes, block: nb, values }
    }
}

/// `Q̂` of a sparse tensor by a cost-ordered chain of sparse mode products (see the module
/// docs). Returns the dense reduced tensor with axes in `Q`'s order.
pub fn premultiply_sparse(q: &SparseTensor, bases: &[&Tensor]) -> Result<Tensor, TensorError> {
    Ok(premultiply_sparse_planned(q, bases)?.0)
}

/// [`premultiply_sparse`], also returning the plan it followed.
pub fn premultiply_sparse_planned(
    q: &SparseTensor,
    bases: &[&Tensor],
) -> Result<(Tensor, PremultiplyPlan), TensorError> {
    check_bases(q.shape(), bases)?;
    let reduced_shape: Vec<usize> = bases.iter().map(|b| b.shape()[1]).collect();
    let mut plan = PremultiplyPlan { order: Vec::new(), entries: Vec::new(), flops: 0.0 };
    if q.nnz() == 0 {
        return Ok((Tensor::zeros(&reduced_shape), plan));
    }
    let mut part = Partial {
        sparse_axes: (0..q.order()).collect(),
        coords: q.coords().to_vec(),
        dense_axes: Vec::new(),
        block: 1,
        values: q.values().to_vec(),
    };
    while !part.sparse_axes.is_empty() {
        // Greedy: contract next the axis that leaves the smallest intermediate.
        let p = (0..part.sparse_axes.len())
            .min_by_key(|&p| part.distinct_without(p) * bases[part.sparse_axes[p]].shape()[1])
            .expect("a sparse axis remains");
        let axis = part.sparse_axes[p];
        plan.flops += (part.entries() * part.block * bases[axis].shape()[1]) as f64;
        part = part.contract(p, bases[axis]);
        plan.order.push(axis);
        plan.entries.push(part.entries());
    }
    let shape: Vec<usize> = part.dense_axes.iter().map(|&a| reduced_shape[a]).collect();
    let t = Tensor::from_vec(&shape, part.values)?;
    let perm: Vec<usize> = (0..q.order())
        .map(|a| part.dense_axes.iter().position(|&d| d == a).expect("every axis contracted"))
        .collect();
    Ok((t.permute(&perm), plan))
}
