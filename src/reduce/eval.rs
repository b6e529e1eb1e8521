//! One evaluator for both spaces. The full model and the reduced model differ only in where
//! their tensors and inputs come from ([`Operands`]); the sequence of operations is the same,
//! which is the whole point of §4: "computing f̂(x̂) follows exactly the sequence of
//! operations used to compute f(x)".

use rayon::prelude::*;

use super::error::ReduceError;
use super::expr::Expr;
use crate::tensor::{solve, spd_power, transpose, Tensor, TensorError};

/// Where an evaluation takes its tensors and inputs from, for a batch of input sets.
pub(crate) trait Operands: Sync {
    /// Basis names of a named tensor's axes.
    fn tensor_axes(&self, name: &str) -> Option<&[String]>;
    /// Basis name of a named input.
    fn input_basis(&self, name: &str) -> Option<&str>;
    /// `name ⊗_a x_a …` computed from the stored form (sparse or dense).
    fn contract_tensor(&self, name: &str, args: &[(usize, &[f64])]) -> Result<Tensor, TensorError>;
    /// One contraction per input set; the default loops over them in parallel, the GPU
    /// overrides it with one GEMM for the whole batch.
    fn contract_tensor_batch(
        &self,
        name: &str,
        args: &[Vec<(usize, &[f64])>],
    ) -> Result<Vec<Tensor>, TensorError> {
        if args.len() == 1 {
            return Ok(vec![self.contract_tensor(name, &args[0])?]);
        }
        args.par_iter().map(|a| self.contract_tensor(name, a)).collect()
    }
    /// `x_b = M_b⁻¹ v_b` for every input set (§4's inverse applied to a vector: a solve, never
    /// an explicit inverse), each system's own result; the outer error is the device's. The
    /// default solves on the CPU in f64, in parallel; the GPU overrides it with one batched
    /// solve on the device.
    fn solve_batch(
        &self,
        what: &str,
        matrices: &[Tensor],
        rhs: &[&[f64]],
    ) -> Result<Vec<Result<Vec<f64>, TensorError>>, ReduceError> {
        Ok((0..matrices.len()).into_par_iter().map(|b| solve(what, &matrices[b], rhs[b])).collect())
    }
    /// Number of input sets.
    fn batch(&self) -> usize;
    /// The named tensor, dense.
    fn dense_tensor(&self, name: &str) -> Tensor;
    /// The named input's value in input set `b`.
    fn input_value(&self, name: &str, b: usize) -> Result<&[f64], ReduceError>;
}

fn tensor_err(e: &Expr) -> impl FnOnce(TensorError) -> ReduceError + '_ {
    move |source| ReduceError::Tensor { context: e.to_string(), source }
}

/// The basis of every axis of `e`'s value, checking every rule on the way: known names,
/// matching bases where axes meet, and §4's same-basis rule for inverses and roots.
pub(crate) fn signature(e: &Expr, ops: &impl Operands) -> Result<Vec<String>, ReduceError> {
    match e {
        Expr::Tensor(n) => {
            ops.tensor_axes(n).map(<[String]>::to_vec).ok_or_else(|| ReduceError::UnknownTensor(n.clone()))
        }
        Expr::Input(n) => ops
            .input_basis(n)
            .map(|b| vec![b.to_string()])
            .ok_or_else(|| ReduceError::UnknownInput(n.clone())),
        Expr::Contract(base, args) => {
            let axes = signature(base, ops)?;
            let mut replaced: Vec<Option<Option<String>>> = vec![None; axes.len()];
            for (axis, a) in args {
                let what = e.to_string();
                let slot = replaced.get_mut(*axis).ok_or_else(|| ReduceError::BadContraction {
                    what: what.clone(),
                    detail: format!("axis {axis} does not exist: {base} has {} axes", axes.len()),
                })?;
                if slot.is_some() {
                    return Err(ReduceError::BadContraction {
                        what,
                        detail: format!("axis {axis} is contracted twice"),
                    });
                }
                let a_axes = signature(a, ops)?;
                if a_axes.is_empty() || a_axes.len() > 2 {
                    return Err(ReduceError::BadContraction {
                        what,
                        detail: format!("axis {axis} is multiplied by {a}, which has {} axes (a vector or matrix is needed)", a_axes.len()),
                    });
                }
                if a_axes[0] != axes[*axis] {
                    return Err(ReduceError::BasisMismatch {
                        what,
                        axis: *axis,
                        expected: axes[*axis].clone(),
                        found: a_axes[0].clone(),
                    });
                }
                *slot = Some(a_axes.get(1).cloned());
            }
            Ok(axes
                .into_iter()
                .zip(replaced)
                .filter_map(|(b, r)| match r {
                    None => Some(b),
                    Some(None) => None,
                    Some(Some(new)) => Some(new),
                })
                .collect())
        }
        Expr::Inverse(m) | Expr::Power(m, _) => {
            let op = if matches!(e, Expr::Inverse(_)) { "inverse" } else { "root" };
            let axes = signature(m, ops)?;
            if axes.len() != 2 {
                return Err(ReduceError::NotAMatrix { op, what: m.to_string(), order: axes.len() });
            }
            if axes[0] != axes[1] {
                return Err(ReduceError::SameBasisRequired {
                    op,
                    what: m.to_string(),
                    axis0: axes[0].clone(),
                    axis1: axes[1].clone(),
                });
            }
            Ok(axes)
        }
        Expr::Sum(terms) => {
            let mut first: Option<Vec<String>> = None;
            for t in terms {
                let s = signature(t, ops)?;
                match &first {
                    None => first = Some(s),
                    Some(f) => same_axes(e, f, &s)?,
                }
            }
            first.ok_or_else(|| ReduceError::BadContraction {
                what: "sum".into(),
                detail: "a sum of nothing".into(),
            })
        }
        Expr::Difference(a, b) => {
            let (sa, sb) = (signature(a, ops)?, signature(b, ops)?);
            same_axes(e, &sa, &sb)?;
            Ok(sa)
        }
        Expr::Scale(_, x) => signature(x, ops),
    }
}

fn same_axes(e: &Expr, a: &[String], b: &[String]) -> Result<(), ReduceError> {
    if a.len() != b.len() {
        return Err(ReduceError::BadContraction {
            what: e.to_string(),
            detail: format!("terms have {} and {} axes", a.len(), b.len()),
        });
    }
    match a.iter().zip(b).position(|(x, y)| x != y) {
        Some(axis) => Err(ReduceError::BasisMismatch {
            what: e.to_string(),
            axis,
            expected: a[axis].clone(),
            found: b[axis].clone(),
        }),
        None => Ok(()),
    }
}

/// One result per batch element, computed in parallel when there are several.
fn per_item(
    batch: usize,
    f: impl Fn(usize) -> Result<Tensor, ReduceError> + Sync + Send,
) -> Result<Vec<Tensor>, ReduceError> {
    if batch == 1 {
        Ok(vec![f(0)?])
    } else {
        (0..batch).into_par_iter().map(f).collect()
    }
}

/// Evaluates `e` (whose [`signature`] has been checked) for every input set of the batch.
pub(crate) fn evaluate(e: &Expr, ops: &impl Operands) -> Result<Vec<Tensor>, ReduceError> {
    let batch = ops.batch();
    match e {
        Expr::Tensor(n) => Ok(vec![ops.dense_tensor(n); batch]),
        Expr::Input(n) => per_item(batch, |b| Ok(Tensor::vector(ops.input_value(n, b)?.to_vec()))),
        Expr::Contract(base, args) => {
            let values: Vec<(usize, Vec<Tensor>)> = args
                .iter()
                .map(|(axis, a)| Ok((*axis, evaluate(a, ops)?)))
                .collect::<Result<_, ReduceError>>()?;
            let all_vectors = values.iter().all(|(_, v)| v[0].order() == 1);
            // A named tensor contracted with vectors: straight from its stored form (sparse in
            // the full space; one GEMM for the whole batch on the GPU).
            if let (Expr::Tensor(name), true) = (base.as_ref(), all_vectors) {
                let refs: Vec<Vec<(usize, &[f64])>> =
                    (0..batch).map(|b| values.iter().map(|(a, v)| (*a, v[b].data())).collect()).collect();
                return ops.contract_tensor_batch(name, &refs).map_err(tensor_err(e));
            }
            // M⁻¹ ⊗₁ v is a solve, M⁻¹ ⊗₀ v a solve with Mᵀ: never an explicit inverse.
            if let (Expr::Inverse(m), [(axis, v)]) = (base.as_ref(), values.as_slice()) {
                if v[0].order() == 1 {
                    let mut mv = evaluate(m, ops)?;
                    if *axis == 0 {
                        mv = mv.iter().map(transpose).collect();
                    }
                    let rhs: Vec<&[f64]> = v.iter().map(Tensor::data).collect();
                    let what = m.to_string();
                    return ops
                        .solve_batch(&what, &mv, &rhs)?
                        .into_iter()
                        .enumerate()
                        .map(|(b, x)| {
                            x.map(Tensor::vector).map_err(|source| ReduceError::Tensor {
                                context: format!("{what}, input set {b}"),
                                source,
                            })
                        })
                        .collect();
                }
            }
            let t = evaluate(base, ops)?;
            per_item(batch, |b| {
                let mut t = t[b].clone();
                for (axis, v) in values.iter().filter(|(_, v)| v[b].order() == 2) {
                    t = t.mode_product(*axis, &v[b]).map_err(tensor_err(e))?;
                }
                let mut vectors: Vec<&(usize, Vec<Tensor>)> =
                    values.iter().filter(|(_, v)| v[b].order() == 1).collect();
                vectors.sort_by_key(|v| std::cmp::Reverse(v.0));
                for (axis, v) in vectors {
                    t = t.contract(*axis, v[b].data()).map_err(tensor_err(e))?;
                }
                Ok(t)
            })
        }
        Expr::Inverse(m) => {
            // Only reached when the inverse is not applied to a single vector: the matrix itself
            // is wanted, so solve for every column of the identity.
            let mv = evaluate(m, ops)?;
            per_item(batch, |b| {
                let n = mv[b].shape()[0];
                let mut inv = Tensor::zeros(&[n, n]);
                for j in 0..n {
                    let mut unit = vec![0.0; n];
                    unit[j] = 1.0;
                    let col = solve(&m.to_string(), &mv[b], &unit).map_err(tensor_err(e))?;
                    for (i, c) in col.into_iter().enumerate() {
                        inv.set(&[i, j], c);
                    }
                }
                Ok(inv)
            })
        }
        Expr::Power(m, p) => {
            let mv = evaluate(m, ops)?;
            per_item(batch, |b| spd_power(&m.to_string(), &mv[b], *p).map_err(tensor_err(e)))
        }
        Expr::Sum(terms) => {
            let values: Vec<Vec<Tensor>> =
                terms.iter().map(|t| evaluate(t, ops)).collect::<Result<_, _>>()?;
            let first = values.first().ok_or_else(|| ReduceError::BadContraction {
                what: "sum".into(),
                detail: "a sum of nothing".into(),
            })?;
            per_item(batch, |b| {
                let mut acc = first[b].clone();
                for v in &values[1..] {
                    acc = acc.add_scaled(&v[b], 1.0).map_err(tensor_err(e))?;
                }
                Ok(acc)
            })
        }
        Expr::Difference(x, y) => {
            let (x, y) = (evaluate(x, ops)?, evaluate(y, ops)?);
            per_item(batch, |b| x[b].add_scaled(&y[b], -1.0).map_err(tensor_err(e)))
        }
        Expr::Scale(c, x) => Ok(evaluate(x, ops)?.into_iter().map(|t| t.scale(*c)).collect()),
    }
}
