//! One evaluator for both spaces. The full model and the reduced model differ only in where
//! their tensors and inputs come from ([`Operands`]); the sequence of operations is the same,
//! which is the whole point of §4: "computing f̂(x̂) follows exactly the sequence of
//! operations used to compute f(x)".

use rayon::prelude::*;

use super::error::ReduceError;
use super::expr::Expr;
use crate::tensor::{solve, spd_power, spd_power_apply, transpose, SparseTensor, Tensor, TensorError};

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
    /// The named tensor as stored: sparse stays sparse (the full space), else dense.
    fn tensor_value(&self, name: &str) -> Value {
        Value::Dense(self.dense_tensor(name))
    }
    /// `name ⊗_a x_a …` kept sparse, when the stored tensor is sparse and the result keeps two
    /// or more axes (`None`: use [`Operands::contract_tensor`]).
    fn contract_tensor_sparse(
        &self,
        _name: &str,
        _args: &[(usize, &[f64])],
    ) -> Option<Result<SparseTensor, TensorError>> {
        None
    }
    /// The named input's value in input set `b`.
    fn input_value(&self, name: &str, b: usize) -> Result<&[f64], ReduceError>;
}

fn tensor_err(e: &Expr) -> impl FnOnce(TensorError) -> ReduceError + '_ {
    move |cause| ReduceError::Tensor { context: e.to_string(), cause }
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

/// A value during evaluation: dense, or — in the full space, where a sparse tensor contracted
/// on some axes leaves a large sparse result (seed 000 Table 2's `H ⊗₂ r`, an `n² × n²`
/// diagonal) — sparse. Inverses and roots of sparse diagonal matrices stay elementwise;
/// anything else is made dense when an operation needs it (refused above
/// [`MAX_DENSE_VALUES`]).
#[derive(Clone, Debug)]
pub(crate) enum Value {
    Dense(Tensor),
    Sparse(SparseTensor),
}

/// The largest dense value a full-space evaluation builds from a sparse one (2²⁸ values,
/// 2 GiB of f64).
pub const MAX_DENSE_VALUES: usize = 1 << 28;

impl Value {
    fn dense(&self, what: &str) -> Result<Tensor, TensorError> {
        match self {
            Value::Dense(t) => Ok(t.clone()),
            Value::Sparse(s) if s.dense_len() > MAX_DENSE_VALUES => Err(TensorError::NotFinite {
                what: what.into(),
                detail: format!(
                    "a sparse value of shape {:?} would need {} dense values (more than {MAX_DENSE_VALUES}); \
                     only diagonal sparse matrices are inverted or rooted elementwise",
                    s.shape(),
                    s.dense_len()
                ),
            }),
            Value::Sparse(s) => Ok(s.to_dense()),
        }
    }

    fn into_dense(self, what: &str) -> Result<Tensor, TensorError> {
        match self {
            Value::Dense(t) => Ok(t),
            v => v.dense(what),
        }
    }

    fn diagonal(&self) -> Option<Vec<f64>> {
        match self {
            Value::Sparse(s) => s.diagonal(),
            Value::Dense(_) => None,
        }
    }

    /// Contraction of one axis with a vector; a sparse value stays sparse while it keeps two
    /// or more axes.
    fn contract(&self, what: &str, axis: usize, x: &[f64]) -> Result<Value, TensorError> {
        match self {
            Value::Dense(t) => t.contract(axis, x).map(Value::Dense),
            Value::Sparse(s) if s.order() > 2 => {
                s.contract_axes_sparse(what, &[(axis, x)]).map(Value::Sparse)
            }
            Value::Sparse(s) => s.contract_axes(what, &[(axis, x)]).map(Value::Dense),
        }
    }

    fn add_scaled(&self, other: &Value, c: f64, what: &str) -> Result<Value, TensorError> {
        match (self, other) {
            (Value::Sparse(a), Value::Sparse(b)) => a.add_scaled(b, c).map(Value::Sparse),
            (a, b) => a.dense(what)?.add_scaled(&b.dense(what)?, c).map(Value::Dense),
        }
    }

    fn scale(&self, c: f64) -> Value {
        match self {
            Value::Dense(t) => Value::Dense(t.scale(c)),
            Value::Sparse(s) => Value::Sparse(s.scale(c)),
        }
    }
}

/// One result per batch element, computed in parallel when there are several.
fn per_item(
    batch: usize,
    f: impl Fn(usize) -> Result<Value, ReduceError> + Sync + Send,
) -> Result<Vec<Value>, ReduceError> {
    if batch == 1 {
        Ok(vec![f(0)?])
    } else {
        (0..batch).into_par_iter().map(f).collect()
    }
}

/// Evaluates `e` (whose [`signature`] has been checked) for every input set of the batch.
pub(crate) fn evaluate(e: &Expr, ops: &impl Operands) -> Result<Vec<Tensor>, ReduceError> {
    evaluate_values(e, ops)?
        .into_iter()
        .map(|v| v.into_dense(&e.to_string()).map_err(tensor_err(e)))
        .collect()
}

fn evaluate_values(e: &Expr, ops: &impl Operands) -> Result<Vec<Value>, ReduceError> {
    let batch = ops.batch();
    match e {
        Expr::Tensor(n) => Ok(vec![ops.tensor_value(n); batch]),
        Expr::Input(n) => {
            per_item(batch, |b| Ok(Value::Dense(Tensor::vector(ops.input_value(n, b)?.to_vec()))))
        }
        Expr::Contract(base, args) => {
            let values: Vec<(usize, Vec<Tensor>)> = args
                .iter()
                .map(|(axis, a)| Ok((*axis, evaluate(a, ops)?)))
                .collect::<Result<_, ReduceError>>()?;
            let all_vectors = values.iter().all(|(_, v)| v[0].order() == 1);
            // A named tensor contracted with vectors: straight from its stored form (sparse in
            // the full space, and kept sparse when the result is a large sparse matrix; one
            // GEMM for the whole batch on the GPU).
            if let (Expr::Tensor(name), true) = (base.as_ref(), all_vectors) {
                let refs: Vec<Vec<(usize, &[f64])>> =
                    (0..batch).map(|b| values.iter().map(|(a, v)| (*a, v[b].data())).collect()).collect();
                if let Some(first) = ops.contract_tensor_sparse(name, &refs[0]) {
                    let mut out = vec![Value::Sparse(first.map_err(tensor_err(e))?)];
                    for r in &refs[1..] {
                        let s = ops.contract_tensor_sparse(name, r).expect("same tensor, same kind");
                        out.push(Value::Sparse(s.map_err(tensor_err(e))?));
                    }
                    return Ok(out);
                }
                return Ok(ops
                    .contract_tensor_batch(name, &refs)
                    .map_err(tensor_err(e))?
                    .into_iter()
                    .map(Value::Dense)
                    .collect());
            }
            // M⁻¹ ⊗₁ v is a solve, M⁻¹ ⊗₀ v a solve with Mᵀ: never an explicit inverse. A
            // sparse diagonal M divides elementwise.
            if let (Expr::Inverse(m), [(axis, v)]) = (base.as_ref(), values.as_slice()) {
                if v[0].order() == 1 {
                    let what = m.to_string();
                    let mv = evaluate_values(m, ops)?;
                    if let Some(diagonals) = mv.iter().map(Value::diagonal).collect::<Option<Vec<_>>>() {
                        return diagonals
                            .iter()
                            .zip(v)
                            .map(|(d, x)| {
                                divide_by_diagonal(&what, d, x.data())
                                    .map(|y| Value::Dense(Tensor::vector(y)))
                            })
                            .collect::<Result<_, _>>()
                            .map_err(tensor_err(e));
                    }
                    let mut mv: Vec<Tensor> = mv
                        .into_iter()
                        .map(|m| m.into_dense(&what))
                        .collect::<Result<_, _>>()
                        .map_err(tensor_err(e))?;
                    if *axis == 0 {
                        mv = mv.iter().map(transpose).collect();
                    }
                    let rhs: Vec<&[f64]> = v.iter().map(Tensor::data).collect();
                    return ops
                        .solve_batch(&what, &mv, &rhs)?
                        .into_iter()
                        .enumerate()
                        .map(|(b, x)| {
                            x.map(|y| Value::Dense(Tensor::vector(y))).map_err(|cause| ReduceError::Tensor {
                                context: format!("{what}, input set {b}"),
                                cause,
                            })
                        })
                        .collect();
                }
            }
            // M^p ⊗₁ v (M symmetric) is applied through M's eigendecomposition, never formed;
            // a sparse diagonal M elementwise.
            if let (Expr::Power(m, p), [(axis, v)]) = (base.as_ref(), values.as_slice()) {
                if v[0].order() == 1 && *axis <= 1 {
                    let what = m.to_string();
                    let mv = evaluate_values(m, ops)?;
                    return per_item(batch, |b| {
                        let x = v[b].data();
                        let y = match mv[b].diagonal() {
                            Some(d) => diagonal_power(&what, &d, *p)
                                .map(|dp| dp.iter().zip(x).map(|(a, b)| a * b).collect()),
                            None => mv[b].dense(&what).and_then(|mb| spd_power_apply(&what, &mb, *p, x)),
                        };
                        y.map(|y| Value::Dense(Tensor::vector(y))).map_err(tensor_err(e))
                    });
                }
            }
            let t = evaluate_values(base, ops)?;
            let what = e.to_string();
            per_item(batch, |b| {
                let mut t = t[b].clone();
                for (axis, v) in values.iter().filter(|(_, v)| v[b].order() == 2) {
                    t = Value::Dense(
                        t.dense(&what).and_then(|d| d.mode_product(*axis, &v[b])).map_err(tensor_err(e))?,
                    );
                }
                let mut vectors: Vec<&(usize, Vec<Tensor>)> =
                    values.iter().filter(|(_, v)| v[b].order() == 1).collect();
                vectors.sort_by_key(|v| std::cmp::Reverse(v.0));
                for (axis, v) in vectors {
                    t = t.contract(&what, *axis, v[b].data()).map_err(tensor_err(e))?;
                }
                Ok(t)
            })
        }
        Expr::Inverse(m) => {
            // Only reached when the inverse is not applied to a single vector: the matrix itself
            // is wanted, so solve for every column of the identity (elementwise when diagonal).
            let mv = evaluate_values(m, ops)?;
            per_item(batch, |b| {
                if let Some(d) = mv[b].diagonal() {
                    let ones = vec![1.0; d.len()];
                    let inv = divide_by_diagonal(&m.to_string(), &d, &ones).map_err(tensor_err(e))?;
                    return Ok(Value::Sparse(SparseTensor::from_diagonal(&inv)));
                }
                let mb = mv[b].dense(&m.to_string()).map_err(tensor_err(e))?;
                let n = mb.shape()[0];
                let mut inv = Tensor::zeros(&[n, n]);
                for j in 0..n {
                    let mut unit = vec![0.0; n];
                    unit[j] = 1.0;
                    let col = solve(&m.to_string(), &mb, &unit).map_err(tensor_err(e))?;
                    for (i, c) in col.into_iter().enumerate() {
                        inv.set(&[i, j], c);
                    }
                }
                Ok(Value::Dense(inv))
            })
        }
        Expr::Power(m, p) => {
            let mv = evaluate_values(m, ops)?;
            per_item(batch, |b| {
                if let Some(d) = mv[b].diagonal() {
                    let powered = diagonal_power(&m.to_string(), &d, *p).map_err(tensor_err(e))?;
                    return Ok(Value::Sparse(SparseTensor::from_diagonal(&powered)));
                }
                let mb = mv[b].dense(&m.to_string()).map_err(tensor_err(e))?;
                spd_power(&m.to_string(), &mb, *p).map(Value::Dense).map_err(tensor_err(e))
            })
        }
        Expr::Sum(terms) => {
            let values: Vec<Vec<Value>> =
                terms.iter().map(|t| evaluate_values(t, ops)).collect::<Result<_, _>>()?;
            let first = values.first().ok_or_else(|| ReduceError::BadContraction {
                what: "sum".into(),
                detail: "a sum of nothing".into(),
            })?;
            let what = e.to_string();
            per_item(batch, |b| {
                let mut acc = first[b].clone();
                for v in &values[1..] {
                    acc = acc.add_scaled(&v[b], 1.0, &what).map_err(tensor_err(e))?;
                }
                Ok(acc)
            })
        }
        Expr::Difference(x, y) => {
            let (x, y) = (evaluate_values(x, ops)?, evaluate_values(y, ops)?);
            let what = e.to_string();
            per_item(batch, |b| x[b].add_scaled(&y[b], -1.0, &what).map_err(tensor_err(e)))
        }
        Expr::Scale(c, x) => Ok(evaluate_values(x, ops)?.into_iter().map(|t| t.scale(*c)).collect()),
    }
}

/// `x / d` elementwise: the inverse of a diagonal matrix applied to a vector. A zero on the
/// diagonal where `x` is not zero is singular; `0/0` gives 0 (an unused coordinate).
fn divide_by_diagonal(what: &str, d: &[f64], x: &[f64]) -> Result<Vec<f64>, TensorError> {
    if d.len() != x.len() {
        return Err(TensorError::Shape { what: what.into(), axis: 1, expected: d.len(), found: x.len() });
    }
    d.iter()
        .zip(x)
        .enumerate()
        .map(|(i, (&di, &xi))| match (di == 0.0, xi == 0.0) {
            (true, true) => Ok(0.0),
            (true, false) => Err(TensorError::Singular { what: what.into(), row: i, pivot: di }),
            _ => Ok(xi / di),
        })
        .collect()
}

/// `d^p` elementwise for a diagonal matrix that must be positive semidefinite (definite when
/// `p < 0`), as [`spd_power`] requires of a dense one. Zero entries of a definite power stay
/// zero when `p < 0` only if the caller's vector is zero there, so they are refused.
fn diagonal_power(what: &str, d: &[f64], p: f64) -> Result<Vec<f64>, TensorError> {
    d.iter()
        .map(|&l| {
            if l < 0.0 || (p < 0.0 && l == 0.0) || l.is_nan() {
                let kind = if p < 0.0 { "definite" } else { "semidefinite" };
                Err(TensorError::NotSpd { what: what.into(), kind, eigenvalue: l })
            } else {
                Ok(if l == 0.0 { 0.0 } else { l.powf(p) })
            }
        })
        .collect()
}
