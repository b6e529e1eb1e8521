//! The reduced model: the same composition over premultiplied tensors, evaluated on reduced
//! inputs, with the bases needed to project inputs and lift outputs.

use std::collections::BTreeMap;

use super::basis::{Bases, Basis};
use super::error::ReduceError;
use super::eval::{evaluate, Operands};
use super::expr::Expr;
use crate::tensor::{Tensor, TensorError};

/// A premultiplied tensor `Q̂` with the basis name of each axis.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct ReducedTensor {
    pub axes: Vec<String>,
    pub data: Tensor,
}

/// `f̂(x̂)`: reduced tensors `Q̂ᵢ`, the composition of the full model, and the bases of its
/// inputs and output.
#[derive(Clone, Debug, PartialEq)]
pub struct ReducedModel {
    pub(crate) tensors: BTreeMap<String, ReducedTensor>,
    pub(crate) inputs: BTreeMap<String, String>,
    pub(crate) output: Expr,
    pub(crate) output_axes: Vec<String>,
    pub(crate) bases: Bases,
}

impl ReducedModel {
    pub(crate) fn new(
        tensors: BTreeMap<String, ReducedTensor>,
        inputs: BTreeMap<String, String>,
        output: Expr,
        output_axes: Vec<String>,
        bases: Bases,
    ) -> Self {
        Self { tensors, inputs, output, output_axes, bases }
    }

    /// The model with the bases named in `dims` cut to their first `dims[name]` columns and
    /// every tensor axis in those bases cut alike. Premultiplication is linear in each basis
    /// column, so for nested bases (PCA modes, in order) this *is* the model reduced with the
    /// smaller bases — no premultiplication again (§7.1's study of basis sizes).
    pub fn truncated(&self, dims: &BTreeMap<String, usize>) -> Result<ReducedModel, ReduceError> {
        let mut out = self.clone();
        for (name, &m) in dims {
            let b = self.bases.get(name).ok_or_else(|| ReduceError::UnknownBasis {
                basis: name.clone(),
                needed_by: "truncation".into(),
            })?;
            if m == 0 || m > b.reduced_dim() {
                return Err(ReduceError::BadBasis {
                    basis: name.clone(),
                    detail: format!("cannot cut {} columns to {m}", b.reduced_dim()),
                });
            }
            let cut = b
                .matrix()
                .leading(&[b.full_dim(), m])
                .map_err(|cause| ReduceError::Tensor { context: format!("cutting basis `{name}`"), cause })?;
            out.bases.insert(name.clone(), Basis::new(name, cut, 1e-9)?);
        }
        for (name, t) in out.tensors.iter_mut() {
            let lens: Vec<usize> =
                t.axes.iter().zip(t.data.shape()).map(|(b, &n)| dims.get(b).copied().unwrap_or(n)).collect();
            t.data = t.data.leading(&lens).map_err(|cause| ReduceError::Tensor {
                context: format!("cutting tensor `{name}`"),
                cause,
            })?;
        }
        Ok(out)
    }

    /// Inserts (or replaces) a reduced tensor: for a capability whose tensor is not a block of
    /// a larger one after [`ReducedModel::truncated`] (a basis built from other bases).
    pub(crate) fn insert_tensor(&mut self, name: &str, axes: &[&str], data: Tensor) {
        let axes = axes.iter().map(|s| s.to_string()).collect();
        self.tensors.insert(name.to_string(), ReducedTensor { axes, data });
    }

    /// Replaces the composition by `output`, which may use `tensor` — a reduced tensor with no
    /// full-space tensor behind it (computed in the reduced space, e.g. a correction fitted at
    /// training points) — and `input`, an input always given reduced (its basis is not kept).
    /// Checked like a premultiplied model: on an error the model is left unchanged.
    pub(crate) fn extend(
        &mut self,
        output: Expr,
        tensor: (&str, &[&str], Tensor),
        input: (&str, &str),
    ) -> Result<(), ReduceError> {
        let mut next = self.clone();
        next.insert_tensor(tensor.0, tensor.1, tensor.2);
        next.inputs.insert(input.0.to_string(), input.1.to_string());
        next.output = output;
        let axes = next.check()?;
        if axes != self.output_axes {
            return Err(ReduceError::BadContraction {
                what: next.output.to_string(),
                detail: format!("its axes {axes:?} are not the model's {:?}", self.output_axes),
            });
        }
        *self = next;
        Ok(())
    }

    /// Removes a reduced tensor and its basis, if present.
    pub(crate) fn remove(&mut self, tensor: &str, basis: Option<&str>) {
        self.tensors.remove(tensor);
        if let Some(b) = basis {
            self.bases.remove(b);
        }
    }

    /// The reduced tensor `Q̂` called `name`.
    pub fn tensor(&self, name: &str) -> Option<&Tensor> {
        self.tensors.get(name).map(|t| &t.data)
    }

    /// The composition (the full model's, unchanged).
    pub fn output(&self) -> &Expr {
        &self.output
    }

    /// Basis names of the output's axes.
    pub fn output_axes(&self) -> &[String] {
        &self.output_axes
    }

    /// Every reduced tensor's name, axis bases and data.
    pub fn tensors(&self) -> impl Iterator<Item = (&str, &[String], &Tensor)> {
        self.tensors.iter().map(|(n, t)| (n.as_str(), t.axes.as_slice(), &t.data))
    }

    /// The basis called `name` (those of the inputs and the output are kept).
    pub fn basis(&self, name: &str) -> Option<&Basis> {
        self.bases.get(name)
    }

    /// Drops the basis of input `name`, which callers will always give already reduced (seed
    /// 000 §8.3: the reduced visibility comes from the learned model, never from projecting a
    /// full visibility), so that the run-time model does not carry it — for radiosity the
    /// visibility basis has `n²` rows. Refused for a basis the output is lifted with.
    pub fn forget_input_basis(&mut self, name: &str) -> Result<(), ReduceError> {
        let b = self.inputs.get(name).ok_or_else(|| ReduceError::UnknownInput(name.to_string()))?.clone();
        if self.output_axes.contains(&b) {
            return Err(ReduceError::BadBasis {
                basis: b,
                detail: format!("input `{name}` shares its basis with the output, which is lifted with it"),
            });
        }
        self.bases.remove(&b);
        Ok(())
    }

    /// The reduced dimension of basis `name`: the basis's, or read off the tensors' axes for a
    /// forgotten input basis.
    pub fn reduced_dim(&self, name: &str) -> Option<usize> {
        self.bases.get(name).map(Basis::reduced_dim).or_else(|| {
            self.tensors
                .values()
                .find_map(|t| t.axes.iter().position(|a| a == name).map(|axis| t.data.shape()[axis]))
        })
    }

    /// `x̂ = B_xᵀ x` for input `name`.
    pub fn project_input(&self, name: &str, x: &[f64]) -> Result<Vec<f64>, ReduceError> {
        let b = self.inputs.get(name).ok_or_else(|| ReduceError::UnknownInput(name.to_string()))?;
        let basis = self.bases.get(b).ok_or_else(|| ReduceError::UnknownBasis {
            basis: b.clone(),
            needed_by: format!("projecting input `{name}` (its basis was dropped: give it reduced)"),
        })?;
        if x.len() != basis.full_dim() {
            return Err(ReduceError::InputLength {
                input: name.into(),
                basis: b.clone(),
                expected: basis.full_dim(),
                found: x.len(),
            });
        }
        Ok(basis.project(x))
    }

    /// Checks the composition against the reduced tensors (names, bases, §4's rules) and
    /// returns the output's axis bases.
    pub fn check(&self) -> Result<Vec<String>, ReduceError> {
        super::eval::signature(&self.output, &ReducedOperands { model: self, inputs: &[] })
    }

    /// Evaluates `ŷ = f̂(x̂)` on reduced inputs.
    pub fn evaluate(&self, inputs: &BTreeMap<&str, &[f64]>) -> Result<Tensor, ReduceError> {
        Ok(self.evaluate_batch(std::slice::from_ref(inputs))?.swap_remove(0))
    }

    /// Evaluates `f̂` for every input set of `batch` (in parallel on the CPU).
    pub fn evaluate_batch(&self, batch: &[BTreeMap<&str, &[f64]>]) -> Result<Vec<Tensor>, ReduceError> {
        self.check_inputs(batch)?;
        if batch.is_empty() {
            return Ok(Vec::new());
        }
        evaluate(&self.output, &ReducedOperands { model: self, inputs: batch })
    }

    /// Evaluates another composition `expr` over this model's reduced tensors on reduced
    /// inputs — a part of the output's (§4: every sub-expression of a reduced composition is
    /// the reduction of the same sub-expression), e.g. the reduced operator inside an inverse.
    /// Its tensors must be this model's; its axes come out in their reduced bases.
    pub fn evaluate_expression(
        &self,
        expr: &Expr,
        inputs: &BTreeMap<&str, &[f64]>,
    ) -> Result<Tensor, ReduceError> {
        self.check_inputs(std::slice::from_ref(inputs))?;
        let ops = ReducedOperands { model: self, inputs: std::slice::from_ref(inputs) };
        super::eval::signature(expr, &ReducedOperands { model: self, inputs: &[] })?;
        Ok(evaluate(expr, &ops)?.swap_remove(0))
    }

    /// Every given input has its basis's reduced length.
    pub(crate) fn check_inputs(&self, batch: &[BTreeMap<&str, &[f64]>]) -> Result<(), ReduceError> {
        for inputs in batch {
            for (name, b) in &self.inputs {
                if let Some(x) = inputs.get(name.as_str()) {
                    let Some(m) = self.reduced_dim(b) else { continue };
                    if x.len() != m {
                        return Err(ReduceError::InputLength {
                            input: name.clone(),
                            basis: b.clone(),
                            expected: m,
                            found: x.len(),
                        });
                    }
                }
            }
        }
        Ok(())
    }

    /// `y = B_y ŷ` for a vector output.
    pub fn lift(&self, yhat: &[f64]) -> Result<Vec<f64>, ReduceError> {
        match self.output_axes.as_slice() {
            [b] => Ok(self.bases[b].lift(yhat)),
            axes => Err(ReduceError::BadContraction {
                what: self.output.to_string(),
                detail: format!("only vector outputs lift; this one has {} axes", axes.len()),
            }),
        }
    }
}

struct ReducedOperands<'a> {
    model: &'a ReducedModel,
    inputs: &'a [BTreeMap<&'a str, &'a [f64]>],
}

impl ReducedOperands<'_> {
    fn dense(&self, name: &str) -> &Tensor {
        &self.model.tensors[name].data
    }
}

impl Operands for ReducedOperands<'_> {
    fn tensor_axes(&self, name: &str) -> Option<&[String]> {
        self.model.tensors.get(name).map(|t| t.axes.as_slice())
    }

    fn input_basis(&self, name: &str) -> Option<&str> {
        self.model.inputs.get(name).map(String::as_str)
    }

    fn contract_tensor(&self, name: &str, args: &[(usize, &[f64])]) -> Result<Tensor, TensorError> {
        self.dense(name).contract_axes(args)
    }

    fn dense_tensor(&self, name: &str) -> Tensor {
        self.dense(name).clone()
    }

    fn batch(&self) -> usize {
        self.inputs.len()
    }

    fn input_value(&self, name: &str, b: usize) -> Result<&[f64], ReduceError> {
        self.inputs[b].get(name).copied().ok_or_else(|| ReduceError::MissingInput(name.to_string()))
    }
}
