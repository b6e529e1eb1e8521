//! Reduced evaluation on the device, a batch of input sets at a time.
//!
//! The composition is walked by the same evaluator as on the CPU (`eval.rs`); only the step
//! that dominates — a reduced tensor contracted with vectors, `Q̂ ⊗_a x ⊗_b y …` — runs on the
//! device, for the whole batch at once, as one GEMM: with the tensor permuted so that its
//! contracted axes lead and reshaped to `K × R`, and the batch's Khatri–Rao rows
//! `x ⊗ y ⊗ …` stacked as `B × K`, the results are `(B × K)·(K × R)`. Inverses applied to
//! vectors run on the device too, as one batched LU solve ([`crate::tensor::gpu::BatchedSolve`],
//! one workgroup per system). Roots (a symmetric eigendecomposition each) and sums of the
//! small results stay on the CPU (faer).
//!
//! Arrays larger than one storage binding are split: tensors by column blocks, batches by
//! rows, bases (for lifting) by rows.

use std::collections::{BTreeMap, HashMap};
use std::sync::Mutex;

use ash::vk;

use super::error::ReduceError;
use super::eval::{evaluate, Operands};
use super::reduced::ReducedModel;

use crate::gpu::{Buffer, Gpu, MemoryKind, Submitter};
use crate::tensor::gpu::{BatchedSolve, Gemm, GemmShape};
use crate::tensor::{Tensor, TensorError};

/// Which processor evaluates or premultiplies.
#[derive(Copy, Clone, Debug, Default, PartialEq, Eq)]
pub enum Backend {
    /// The GPU backend on a real GPU; the CPU backend when the only device is a CPU rasteriser
    /// (lavapipe's best SGEMM is 15–60× below faer on the same cores) or there is no device.
    #[default]
    Auto,
    /// faer on the CPU.
    Cpu,
    /// Compute shaders.
    Gpu,
}

impl Backend {
    /// True if this choice runs on `gpu`.
    pub fn uses_gpu(self, gpu: Option<&Gpu>) -> bool {
        match self {
            Backend::Cpu => false,
            Backend::Gpu => gpu.is_some(),
            Backend::Auto => gpu.is_some_and(|g| !g.caps().is_cpu()),
        }
    }
}

/// A reduced tensor on the device, permuted for one contraction pattern: `K × R` in column
/// blocks of one binding each.
struct DeviceContraction {
    /// Contracted axes, in the order their vectors form the Khatri–Rao rows.
    axes: Vec<usize>,
    k: usize,
    kept_shape: Vec<usize>,
    /// (first column, columns, buffer) per block.
    blocks: Vec<(usize, usize, Buffer<f32>)>,
}

/// Device layouts by (tensor, contracted axes).
type ContractionCache = HashMap<(String, Vec<usize>), std::sync::Arc<DeviceContraction>>;

/// A [`ReducedModel`] resident on the device.
pub struct GpuReducedModel {
    gpu: Gpu,
    model: ReducedModel,
    gemm: Gemm,
    solver: BatchedSolve,
    contractions: Mutex<ContractionCache>,
}

impl GpuReducedModel {
    /// Makes the model resident on `gpu` (tensors are uploaded on first use, in the layout
    /// their contraction needs).
    pub fn new(gpu: &Gpu, model: ReducedModel) -> Result<Self, ReduceError> {
        let gemm = Gemm::new(gpu).map_err(ReduceError::device("building the GEMM pipeline"))?;
        let solver = BatchedSolve::new(gpu).map_err(ReduceError::device("building the solve pipeline"))?;
        Ok(Self { gpu: gpu.clone(), model, gemm, solver, contractions: Mutex::new(HashMap::new()) })
    }

    /// The model.
    pub fn model(&self) -> &ReducedModel {
        &self.model
    }

    /// Evaluates `f̂` for every input set of `batch`: tensor contractions on the device (one
    /// GEMM per contraction for the whole batch) and solves (one batched LU) on the device,
    /// roots and sums on the CPU.
    pub fn evaluate_batch(&self, batch: &[BTreeMap<&str, &[f64]>]) -> Result<Vec<Tensor>, ReduceError> {
        self.evaluate_batch_with(&mut self.gpu.submitter(), batch)
    }

    /// [`Self::evaluate_batch`] with the device steps submitted through `submitter` (the
    /// engine's queue or a host's): per contraction, the Khatri–Rao rows uploaded, the GEMMs
    /// and the readback of their results; per set of inverses, the batched solve. The host
    /// steps between them (roots, sums, the walk of the composition) run on this thread.
    pub fn evaluate_batch_with(
        &self,
        submitter: &mut dyn Submitter,
        batch: &[BTreeMap<&str, &[f64]>],
    ) -> Result<Vec<Tensor>, ReduceError> {
        self.model.check_inputs(batch)?;
        if batch.is_empty() {
            return Ok(Vec::new());
        }
        let operands = GpuOperands { owner: self, inputs: batch, submitter: Mutex::new(submitter) };
        evaluate(&self.model.output, &operands)
    }

    fn floats_per_binding(&self) -> usize {
        (self.gpu.max_binding_bytes() / 4) as usize
    }

    fn contraction(
        &self,
        submitter: &mut dyn Submitter,
        name: &str,
        axes: &[usize],
    ) -> Result<std::sync::Arc<DeviceContraction>, ReduceError> {
        let key = (name.to_string(), axes.to_vec());
        if let Some(c) = self.contractions.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
            return Ok(c.clone());
        }
        let t = &self.model.tensors[name].data;
        let kept: Vec<usize> = (0..t.order()).filter(|a| !axes.contains(a)).collect();
        let perm: Vec<usize> = axes.iter().chain(&kept).copied().collect();
        let p = t.permute(&perm);
        let k: usize = axes.iter().map(|&a| t.shape()[a]).product();
        let r: usize = kept.iter().map(|&a| t.shape()[a]).product::<usize>().max(1);
        let cols_per_block = (self.floats_per_binding() / k.max(1)).max(1);
        let mut blocks = Vec::new();
        for start in (0..r).step_by(cols_per_block) {
            let cols = cols_per_block.min(r - start);
            let data: Vec<f32> = (0..k)
                .flat_map(|i| p.data()[i * r + start..i * r + start + cols].iter().map(|&v| v as f32))
                .collect();
            let buf = submitter
                .buffer_from_slice(
                    &format!("{name} for contraction {axes:?}"),
                    &data,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )
                .map_err(ReduceError::device("uploading a reduced tensor"))?;
            blocks.push((start, cols, buf));
        }
        let c = std::sync::Arc::new(DeviceContraction {
            axes: axes.to_vec(),
            k,
            kept_shape: kept.iter().map(|&a| t.shape()[a]).collect(),
            blocks,
        });
        self.contractions.lock().unwrap_or_else(|p| p.into_inner()).insert(key, c.clone());
        Ok(c)
    }

    /// `Q̂ ⊗ …` for every input set: one GEMM per (column block, batch chunk), one submission
    /// per batch chunk.
    fn contract_batch(
        &self,
        submitter: &mut dyn Submitter,
        name: &str,
        args: &[Vec<(usize, &[f64])>],
    ) -> Result<Vec<Tensor>, ReduceError> {
        let mut axes: Vec<usize> = args[0].iter().map(|a| a.0).collect();
        axes.sort_unstable();
        let dc = self.contraction(submitter, name, &axes)?;
        let batch = args.len();
        // Khatri–Rao rows, x_{a0} ⊗ x_{a1} ⊗ … in the permuted axis order.
        let mut kr = Vec::with_capacity(batch * dc.k);
        for set in args {
            let mut row = vec![1.0f64];
            for &a in &dc.axes {
                let x = set
                    .iter()
                    .find(|(b, _)| *b == a)
                    .map(|(_, x)| *x)
                    .expect("every contracted axis has a vector");
                row = row.iter().flat_map(|&p| x.iter().map(move |&v| p * v)).collect();
            }
            kr.extend(row.into_iter().map(|v| v as f32));
        }
        let per = self.floats_per_binding();
        let widest = dc.blocks.iter().map(|b| b.1).max().unwrap_or(1);
        let rows_per_chunk = (per / dc.k.max(1)).min(per / widest.max(1)).max(1);
        let r_total: usize = dc.kept_shape.iter().product::<usize>().max(1);
        let mut out = vec![0.0f64; batch * r_total];
        for b0 in (0..batch).step_by(rows_per_chunk) {
            let rows = rows_per_chunk.min(batch - b0);
            let krb = submitter
                .buffer_from_slice(
                    "Khatri–Rao rows",
                    &kr[b0 * dc.k..(b0 + rows) * dc.k],
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                )
                .map_err(ReduceError::device("uploading inputs"))?;
            let mut results = Vec::new();
            let mut bindings = Vec::new();
            for (start, cols, t) in &dc.blocks {
                let c = Buffer::<f32>::new(
                    &self.gpu,
                    "contraction result",
                    (rows * cols) as u64,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryKind::GpuOnly,
                )
                .map_err(ReduceError::device("allocating results"))?;
                let whole = |b| Buffer::<f32>::whole(b);
                let binding = self
                    .gemm
                    .bind(
                        &self.gpu,
                        whole(&krb),
                        whole(t),
                        whole(&c),
                        GemmShape { m: rows as u32, n: *cols as u32, k: dc.k as u32 },
                    )
                    .map_err(ReduceError::device("binding"))?;
                bindings.push(binding);
                results.push((*start, *cols, c));
            }
            submitter
                .submit(&mut |rec| bindings.iter().for_each(|b| self.gemm.record(rec, b, false)))
                .map_err(ReduceError::device("contracting on the device"))?;
            let readbacks = results
                .iter()
                .map(|(_, _, c)| submitter.record_readback(c, 0, c.len()))
                .collect::<Result<Vec<_>, _>>()
                .map_err(ReduceError::device("reading results"))?;
            submitter.complete().map_err(ReduceError::device("contracting on the device"))?;
            for ((start, cols, _), readback) in results.iter().zip(&readbacks) {
                let vals = readback.read().map_err(ReduceError::device("reading results"))?;
                for i in 0..rows {
                    for j in 0..*cols {
                        out[(b0 + i) * r_total + start + j] = f64::from(vals[i * cols + j]);
                    }
                }
            }
        }
        out.chunks(r_total)
            .map(|c| {
                Tensor::from_vec(&dc.kept_shape, c.to_vec())
                    .map_err(|cause| ReduceError::Tensor { context: name.into(), cause })
            })
            .collect()
    }

    /// `y = B_y ŷ` on the device for a batch of vector outputs: `Yᵀ = B_y · Ŷᵀ`, the basis in
    /// row blocks of one binding each.
    pub fn lift_batch(&self, yhat: &[Vec<f64>]) -> Result<Vec<Vec<f64>>, ReduceError> {
        self.lift_batch_with(&mut self.gpu.submitter(), yhat)
    }

    /// [`Self::lift_batch`] through `submitter` (the engine's queue or a host's): per row
    /// block of the basis, its upload, one GEMM and the readback of its rows.
    pub fn lift_batch_with(
        &self,
        submitter: &mut dyn Submitter,
        yhat: &[Vec<f64>],
    ) -> Result<Vec<Vec<f64>>, ReduceError> {
        let [basis] = self.model.output_axes.as_slice() else {
            return Err(ReduceError::BadContraction {
                what: self.model.output.to_string(),
                detail: format!(
                    "only vector outputs lift; this one has {} axes",
                    self.model.output_axes.len()
                ),
            });
        };
        let b = &self.model.bases[basis];
        let (n, m, batch) = (b.full_dim(), b.reduced_dim(), yhat.len());
        if let Some(bad) = yhat.iter().find(|y| y.len() != m) {
            return Err(ReduceError::InputLength {
                input: "ŷ".into(),
                basis: basis.clone(),
                expected: m,
                found: bad.len(),
            });
        }
        let per = self.floats_per_binding();
        let rows_per_block = (per / m.max(1)).min(per / batch.max(1)).max(1);
        let yt: Vec<f32> = (0..m).flat_map(|j| yhat.iter().map(move |y| y[j] as f32)).collect();
        let ytb = submitter
            .buffer_from_slice("Ŷᵀ", &yt, vk::BufferUsageFlags::STORAGE_BUFFER)
            .map_err(ReduceError::device("uploading ŷ"))?;
        let mut out = vec![vec![0.0f64; n]; batch];
        for r0 in (0..n).step_by(rows_per_block) {
            let rows = rows_per_block.min(n - r0);
            let block: Vec<f32> =
                b.matrix().data()[r0 * m..(r0 + rows) * m].iter().map(|&v| v as f32).collect();
            let bb = submitter
                .buffer_from_slice("basis rows", &block, vk::BufferUsageFlags::STORAGE_BUFFER)
                .map_err(ReduceError::device("uploading the basis"))?;
            let c = Buffer::<f32>::new(
                &self.gpu,
                "lifted rows",
                (rows * batch) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryKind::GpuOnly,
            )
            .map_err(ReduceError::device("allocating results"))?;
            let whole = |x| Buffer::<f32>::whole(x);
            let binding = self
                .gemm
                .bind(
                    &self.gpu,
                    whole(&bb),
                    whole(&ytb),
                    whole(&c),
                    GemmShape { m: rows as u32, n: batch as u32, k: m as u32 },
                )
                .map_err(ReduceError::device("binding"))?;
            submitter
                .submit(&mut |rec| self.gemm.record(rec, &binding, false))
                .map_err(ReduceError::device("lifting"))?;
            let vals = submitter.download(&c).map_err(ReduceError::device("reading results"))?;
            for i in 0..rows {
                for (k, y) in out.iter_mut().enumerate() {
                    y[r0 + i] = f64::from(vals[i * batch + k]);
                }
            }
        }
        Ok(out)
    }
}

struct GpuOperands<'a, 's> {
    owner: &'a GpuReducedModel,
    inputs: &'a [BTreeMap<&'a str, &'a [f64]>],
    submitter: Mutex<&'s mut dyn Submitter>,
}

impl Operands for GpuOperands<'_, '_> {
    fn tensor_axes(&self, name: &str) -> Option<&[String]> {
        self.owner.model.tensors.get(name).map(|t| t.axes.as_slice())
    }

    fn input_basis(&self, name: &str) -> Option<&str> {
        self.owner.model.inputs.get(name).map(String::as_str)
    }

    fn contract_tensor(&self, name: &str, args: &[(usize, &[f64])]) -> Result<Tensor, TensorError> {
        self.contract_tensor_batch(name, &[args.to_vec()]).map(|mut v| v.swap_remove(0))
    }

    fn contract_tensor_batch(
        &self,
        name: &str,
        args: &[Vec<(usize, &[f64])>],
    ) -> Result<Vec<Tensor>, TensorError> {
        let mut submitter = self.submitter.lock().unwrap_or_else(|p| p.into_inner());
        self.owner
            .contract_batch(&mut **submitter, name, args)
            .map_err(|e| TensorError::NotFinite { what: name.into(), detail: e.to_string() })
    }

    fn solve_batch(
        &self,
        what: &str,
        matrices: &[Tensor],
        rhs: &[&[f64]],
    ) -> Result<Vec<Result<Vec<f64>, TensorError>>, ReduceError> {
        let refs: Vec<&Tensor> = matrices.iter().collect();
        let mut submitter = self.submitter.lock().unwrap_or_else(|p| p.into_inner());
        self.owner.solver.solve_with(&mut **submitter, what, &refs, rhs).map_err(ReduceError::device(what))
    }

    fn batch(&self) -> usize {
        self.inputs.len()
    }

    fn dense_tensor(&self, name: &str) -> Tensor {
        self.owner.model.tensors[name].data.clone()
    }

    fn input_value(&self, name: &str, b: usize) -> Result<&[f64], ReduceError> {
        self.inputs[b].get(name).copied().ok_or_else(|| ReduceError::MissingInput(name.to_string()))
    }
}
