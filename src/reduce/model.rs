//! A function as a [`Model`]: named full-space tensors whose axes carry basis names, named
//! inputs, and the composition [`Expr`] that computes the output.

use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

use super::basis::{Bases, Basis};
use super::error::ReduceError;
use super::eval::{evaluate, signature, Operands, Value};
use super::expr::Expr;
use super::gpu_eval::Backend;
use super::premultiply::{
    premultiply_dense, premultiply_sparse_gpu, premultiply_sparse_with, premultiply_streamed_together,
    BasisRows, PremultiplyOptions, TensorChunks,
};
use super::ranks::allreduce_parts;
use super::ranks::{Communicator, SINGLE_RANK};
use super::reduced::{ReducedModel, ReducedTensor};
use crate::gpu::Gpu;
use crate::tensor::{SparseTensor, Tensor, TensorError};

/// How [`Model::reduce_with`] premultiplies.
#[derive(Clone, Copy)]
pub struct ReduceOptions<'a> {
    /// CPU, GPU, or `Auto` (the GPU on a real GPU, the CPU on a CPU rasteriser).
    pub backend: Backend,
    /// The device for the GPU backend.
    pub gpu: Option<&'a Gpu>,
    /// Called with (multiply–adds done, planned) during each sparse tensor's premultiplication.
    pub progress: Option<&'a (dyn Fn(f64, f64) + Sync)>,
    /// The ranks the premultiplication is shared over: each premultiplies its share of every
    /// sparse tensor's entries (of a streamed tensor's chunks) and one allreduce sums the
    /// reduced tensors; dense tensors (small) are premultiplied whole on every rank. One rank
    /// by default.
    pub ranks: &'a dyn Communicator,
}

impl Default for ReduceOptions<'_> {
    fn default() -> Self {
        Self { backend: Backend::default(), gpu: None, progress: None, ranks: &SINGLE_RANK }
    }
}

/// A full-space tensor: dense (small) or sparse (what real models have), or streamed (too
/// large to hold: produced a chunk of entries at a time and premultiplied chunk by chunk).
#[derive(Clone, Debug, PartialEq)]
pub enum FullTensor {
    /// Dense.
    Dense(Tensor),
    /// Coordinate list.
    Sparse(SparseTensor),
    /// Chunks of a coordinate list, generated on demand.
    Streamed(StreamedTensor),
}

impl FullTensor {
    /// Axis lengths.
    pub fn shape(&self) -> &[usize] {
        match self {
            Self::Dense(t) => t.shape(),
            Self::Sparse(s) => s.shape(),
            Self::Streamed(s) => &s.shape,
        }
    }
}

/// A sparse tensor given by its chunks ([`TensorChunks`]). The reduction premultiplies it a
/// chunk at a time ([`premultiply_streamed_together`]); a full-space evaluation (for models
/// small enough to check in the full space) gathers the chunks once into one coordinate list.
#[derive(Clone)]
pub struct StreamedTensor {
    shape: Vec<usize>,
    chunks: Arc<dyn TensorChunks>,
    whole: Arc<OnceLock<SparseTensor>>,
}

impl StreamedTensor {
    /// Wraps `chunks`.
    pub fn new(chunks: Arc<dyn TensorChunks>) -> Self {
        Self { shape: chunks.shape(), chunks, whole: Arc::new(OnceLock::new()) }
    }

    /// The chunks.
    pub fn chunks(&self) -> &dyn TensorChunks {
        self.chunks.as_ref()
    }

    /// Every chunk in one coordinate list, gathered on first use.
    pub fn whole(&self) -> &SparseTensor {
        self.whole.get_or_init(|| self.chunks.to_sparse())
    }
}

impl std::fmt::Debug for StreamedTensor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "StreamedTensor {{ shape: {:?}, chunks: {} }}", self.shape, self.chunks.chunks())
    }
}

/// Streamed tensors are equal when they are the same generator.
impl PartialEq for StreamedTensor {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.chunks, &other.chunks)
    }
}

impl From<StreamedTensor> for FullTensor {
    fn from(s: StreamedTensor) -> Self {
        Self::Streamed(s)
    }
}

impl From<Tensor> for FullTensor {
    fn from(t: Tensor) -> Self {
        Self::Dense(t)
    }
}

impl From<SparseTensor> for FullTensor {
    fn from(s: SparseTensor) -> Self {
        Self::Sparse(s)
    }
}

/// A named tensor: its data and the basis name of each axis (axis 0 first).
#[derive(Clone, Debug, PartialEq)]
pub struct TensorDecl {
    /// Basis name per axis.
    pub axes: Vec<String>,
    /// The full-space data.
    pub data: FullTensor,
}

/// `y = f(x)` as tensors, inputs and a composition.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    tensors: BTreeMap<String, TensorDecl>,
    inputs: BTreeMap<String, String>,
    output: Expr,
}

impl Model {
    /// A model computing `output`; declare its tensors and inputs next.
    pub fn new(output: Expr) -> Self {
        Self { tensors: BTreeMap::new(), inputs: BTreeMap::new(), output }
    }

    /// Declares tensor `name` with the basis name of each axis.
    pub fn with_tensor(mut self, name: &str, axes: &[&str], data: impl Into<FullTensor>) -> Self {
        let decl = TensorDecl { axes: axes.iter().map(|s| s.to_string()).collect(), data: data.into() };
        self.tensors.insert(name.to_string(), decl);
        self
    }

    /// Declares input `name`, a vector in basis `basis`.
    pub fn with_input(mut self, name: &str, basis: &str) -> Self {
        self.inputs.insert(name.to_string(), basis.to_string());
        self
    }

    /// The composition.
    pub fn output(&self) -> &Expr {
        &self.output
    }

    /// The declared tensors.
    pub fn tensors(&self) -> &BTreeMap<String, TensorDecl> {
        &self.tensors
    }

    /// The declared inputs and their bases.
    pub fn inputs(&self) -> &BTreeMap<String, String> {
        &self.inputs
    }

    /// The full dimension of every basis name, checked to agree across all axes that use it.
    pub fn dimensions(&self) -> Result<BTreeMap<String, usize>, ReduceError> {
        let mut dims: BTreeMap<String, usize> = BTreeMap::new();
        for (name, t) in &self.tensors {
            let shape = t.data.shape();
            if shape.len() != t.axes.len() {
                return Err(ReduceError::AxisLength {
                    tensor: name.clone(),
                    axis: shape.len().min(t.axes.len()),
                    basis: t.axes.get(shape.len()).cloned().unwrap_or_default(),
                    detail: format!("{} basis names for a tensor of order {}", t.axes.len(), shape.len()),
                });
            }
            for (axis, (b, &n)) in t.axes.iter().zip(shape).enumerate() {
                match dims.get(b) {
                    Some(&m) if m != n => {
                        return Err(ReduceError::AxisLength {
                            tensor: name.clone(),
                            axis,
                            basis: b.clone(),
                            detail: format!("length {n}, but other axes in this basis have length {m}"),
                        })
                    }
                    _ => {
                        dims.insert(b.clone(), n);
                    }
                }
            }
        }
        Ok(dims)
    }

    /// Checks the whole model (names, bases where axes meet, §4's same-basis rule, axis
    /// lengths) and returns the basis of each output axis.
    pub fn check(&self) -> Result<Vec<String>, ReduceError> {
        self.dimensions()?;
        signature(&self.output, &FullOperands { model: self, inputs: &BTreeMap::new() })
    }

    /// Evaluates `f(x)` in the full space, in f64.
    pub fn evaluate(&self, inputs: &BTreeMap<&str, &[f64]>) -> Result<Tensor, ReduceError> {
        let dims = self.dimensions()?;
        for (name, basis) in &self.inputs {
            if let (Some(x), Some(&n)) = (inputs.get(name.as_str()), dims.get(basis)) {
                if x.len() != n {
                    return Err(ReduceError::InputLength {
                        input: name.clone(),
                        basis: basis.clone(),
                        expected: n,
                        found: x.len(),
                    });
                }
            }
        }
        let ops = FullOperands { model: self, inputs };
        signature(&self.output, &ops)?;
        Ok(evaluate(&self.output, &ops)?.swap_remove(0))
    }

    /// Premultiplies every tensor by the bases of its axes (Eq. 2 and §4's table:
    /// `Q̂ = Q ⊗₀ B₀ ⊗₁ B₁ …`) on the CPU, and returns the reduced model. Every axis name needs
    /// a basis whose full dimension matches the axis.
    pub fn reduce(&self, bases: &Bases) -> Result<ReducedModel, ReduceError> {
        self.reduce_with(bases, &ReduceOptions::default())
    }

    /// [`Model::reduce`] with a choice of backend for the sparse tensors (dense ones are small
    /// and always premultiplied on the CPU) and a progress callback.
    pub fn reduce_with(
        &self,
        bases: &Bases,
        options: &ReduceOptions<'_>,
    ) -> Result<ReducedModel, ReduceError> {
        self.reduce_with_rows(bases, &BTreeMap::new(), options)
    }

    /// [`Model::reduce_with`] where some bases are given only by rows on demand (`row_bases`,
    /// e.g. [`super::SnapshotBasis`] for bases larger than memory): they may only carry axes
    /// of streamed tensors, which are premultiplied chunk by chunk on the CPU; and they are not
    /// kept in the reduced model, so an input in such a basis must be given reduced.
    pub fn reduce_with_rows(
        &self,
        bases: &Bases,
        row_bases: &BTreeMap<String, &dyn BasisRows>,
        options: &ReduceOptions<'_>,
    ) -> Result<ReducedModel, ReduceError> {
        let output_axes = self.check()?;
        let mut reduced = BTreeMap::new();
        let mut streamed: Vec<(&str, &dyn TensorChunks, Vec<&dyn BasisRows>)> = Vec::new();
        for (name, t) in &self.tensors {
            let lookup = |axis: usize, b: &String, n: usize| -> Result<&dyn BasisRows, ReduceError> {
                let found: Option<&dyn BasisRows> = match (bases.get(b), row_bases.get(b)) {
                    (Some(stored), _) => Some(stored),
                    (None, Some(rows)) => Some(*rows),
                    (None, None) => None,
                };
                let basis = found.ok_or_else(|| ReduceError::UnknownBasis {
                    basis: b.clone(),
                    needed_by: format!("tensor `{name}` axis {axis}"),
                })?;
                if basis.full_dim() != n {
                    return Err(ReduceError::AxisLength {
                        tensor: name.clone(),
                        axis,
                        basis: b.clone(),
                        detail: format!("length {n}, but the basis has {} full dimensions", basis.full_dim()),
                    });
                }
                Ok(basis)
            };
            let context = || format!("premultiplying `{name}`");
            let pm = PremultiplyOptions { progress: options.progress, ..PremultiplyOptions::default() };
            let ranks = options.ranks;
            // This rank's share of a sparse tensor's entries (the whole tensor on one rank).
            let local = |s: &SparseTensor| (ranks.size() > 1).then(|| s.entries(ranks.share(s.nnz())));
            let axes = t.axes.iter().zip(t.data.shape()).enumerate();
            let data = if let FullTensor::Streamed(st) = &t.data {
                // Premultiplied below, all streamed tensors together.
                let rows = axes.map(|(axis, (b, &n))| lookup(axis, b, n)).collect::<Result<Vec<_>, _>>()?;
                streamed.push((name.as_str(), st.chunks(), rows));
                continue;
            } else {
                let mats = axes
                    .map(|(axis, (b, &n))| {
                        lookup(axis, b, n)?;
                        bases.get(b).map(Basis::matrix).ok_or_else(|| ReduceError::BadBasis {
                            basis: b.clone(),
                            detail: format!(
                                "given by rows only, but tensor `{name}` (axis {axis}) is not streamed"
                            ),
                        })
                    })
                    .collect::<Result<Vec<&Tensor>, ReduceError>>()?;
                match (&t.data, options.backend.uses_gpu(options.gpu), options.gpu) {
                    (FullTensor::Dense(d), _, _) => premultiply_dense(d, &mats)
                        .map_err(|cause| ReduceError::Tensor { context: context(), cause })?,
                    (FullTensor::Sparse(s), gpu_wanted, gpu) => {
                        let part = local(s);
                        let s = part.as_ref().unwrap_or(s);
                        let mut y = match (gpu_wanted, gpu) {
                            (true, Some(gpu)) => premultiply_sparse_gpu(gpu, s, &mats, pm)?.0,
                            _ => {
                                premultiply_sparse_with(s, &mats, pm)
                                    .map_err(|cause| ReduceError::Tensor { context: context(), cause })?
                                    .0
                            }
                        };
                        allreduce_parts(ranks, &mut [y.data_mut()], &format!("the premultiplied `{name}`"))?;
                        y
                    }
                    (FullTensor::Streamed(_), _, _) => unreachable!("handled above"),
                }
            };
            reduced.insert(name.clone(), ReducedTensor { axes: t.axes.clone(), data });
        }
        // In lockstep, so that bases regenerating rows make each block once for all of them.
        let pm = PremultiplyOptions {
            progress: options.progress,
            ranks: options.ranks,
            ..PremultiplyOptions::default()
        };
        let together: Vec<(&str, &dyn TensorChunks, &[&dyn BasisRows])> =
            streamed.iter().map(|(n, q, rows)| (*n, *q, rows.as_slice())).collect();
        for ((name, _, _), data) in streamed.iter().zip(premultiply_streamed_together(&together, pm)?) {
            let axes = self.tensors[*name].axes.clone();
            reduced.insert(name.to_string(), ReducedTensor { axes, data });
        }
        for (input, b) in &self.inputs {
            if !bases.contains_key(b) && !row_bases.contains_key(b) {
                return Err(ReduceError::UnknownBasis {
                    basis: b.clone(),
                    needed_by: format!("input `{input}`"),
                });
            }
        }
        if let Some(b) = output_axes.iter().find(|b| !bases.contains_key(*b)) {
            return Err(ReduceError::BadBasis {
                basis: b.clone(),
                detail: "carries the output, which is lifted with it: it must be a stored basis".into(),
            });
        }
        let used: Vec<&String> = output_axes.iter().chain(self.inputs.values()).collect();
        let kept =
            bases.iter().filter(|(k, _)| used.contains(k)).map(|(k, v)| (k.clone(), v.clone())).collect();
        Ok(ReducedModel::new(reduced, self.inputs.clone(), self.output.clone(), output_axes, kept))
    }
}

/// Full-space operands: the model's tensors as declared, the given full inputs.
pub(crate) struct FullOperands<'a> {
    pub model: &'a Model,
    pub inputs: &'a BTreeMap<&'a str, &'a [f64]>,
}

impl Operands for FullOperands<'_> {
    fn tensor_axes(&self, name: &str) -> Option<&[String]> {
        self.model.tensors.get(name).map(|t| t.axes.as_slice())
    }

    fn input_basis(&self, name: &str) -> Option<&str> {
        self.model.inputs.get(name).map(String::as_str)
    }

    fn contract_tensor(&self, name: &str, args: &[(usize, &[f64])]) -> Result<Tensor, TensorError> {
        match &self.model.tensors[name].data {
            FullTensor::Dense(t) => t.contract_axes(args),
            FullTensor::Sparse(s) => s.contract_axes(name, args),
            FullTensor::Streamed(s) => s.whole().contract_axes(name, args),
        }
    }

    fn dense_tensor(&self, name: &str) -> Tensor {
        match &self.model.tensors[name].data {
            FullTensor::Dense(t) => t.clone(),
            FullTensor::Sparse(s) => s.to_dense(),
            FullTensor::Streamed(s) => s.whole().to_dense(),
        }
    }

    fn tensor_value(&self, name: &str) -> Value {
        match &self.model.tensors[name].data {
            FullTensor::Dense(t) => Value::Dense(t.clone()),
            FullTensor::Sparse(s) => Value::Sparse(s.clone()),
            FullTensor::Streamed(s) => Value::Sparse(s.whole().clone()),
        }
    }

    fn contract_tensor_sparse(
        &self,
        name: &str,
        args: &[(usize, &[f64])],
    ) -> Option<Result<SparseTensor, TensorError>> {
        match &self.model.tensors[name].data {
            FullTensor::Sparse(s) if s.order() >= args.len() + 2 => Some(s.contract_axes_sparse(name, args)),
            FullTensor::Streamed(s) if s.shape.len() >= args.len() + 2 => {
                Some(s.whole().contract_axes_sparse(name, args))
            }
            _ => None,
        }
    }

    fn batch(&self) -> usize {
        1
    }

    fn input_value(&self, name: &str, _b: usize) -> Result<&[f64], ReduceError> {
        self.inputs.get(name).copied().ok_or_else(|| ReduceError::MissingInput(name.to_string()))
    }
}
