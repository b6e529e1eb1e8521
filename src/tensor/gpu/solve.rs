//! Batched dense solves on the device (`shaders-glsl/tensor/lu_solve.comp`): Gaussian
//! elimination with partial pivoting, one workgroup per system, in f32. The reduced inverse of
//! seed 000 §4, `(B_qᵀ Q B_q)⁻¹`, is only ever applied to a vector, so it is a solve (never an
//! explicit inverse), one per input set of a batch.

use ash::vk;
use bytemuck::{Pod, Zeroable};

use crate::gpu::{
    BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, Gpu, GpuError, GpuResult, MemoryKind,
    Resource, Submitter,
};
use crate::tensor::{check_system, pivot_tolerance, Tensor, TensorError};

crate::push_constants! {
    struct SolvePush {
        n: u32,
        batch: u32,
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable, Default)]
struct Status {
    row_plus_one: u32,
    pivot: f32,
}

/// Solves `A_s x_s = b_s` for a batch of square systems of one size on the device.
pub struct BatchedSolve {
    pipeline: ComputePipeline,
}

impl BatchedSolve {
    /// Builds the pipeline (64 invocations per system).
    pub fn new(gpu: &Gpu) -> GpuResult<Self> {
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "batched LU solve",
                spirv: crate::tensor::shaders::LU_SOLVE,
                bindings: &[BindingKind::StorageBuffer; 4],
                push: crate::gpu::PushLayout::of::<SolvePush>(),
                specialization: &[],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// `x_s = A_s⁻¹ b_s` for every system (matrices `n × n`, all of one `n`). The outer error is
    /// the device's; each system's own result is an error if its matrix is not `n × n`, holds
    /// a non-finite value, or is singular to f32 working precision (a pivot of magnitude
    /// ≤ n·ε₃₂·max|A_s|, the CPU [`crate::tensor::solve`]'s test with f32's ε). Batches larger
    /// than one storage binding run in chunks; a single system larger than one binding is
    /// [`GpuError::OverLimit`].
    pub fn solve(
        &self,
        gpu: &Gpu,
        what: &str,
        matrices: &[&Tensor],
        rhs: &[&[f64]],
    ) -> GpuResult<Vec<Result<Vec<f64>, TensorError>>> {
        self.solve_with(&mut gpu.submitter(), what, matrices, rhs)
    }

    /// [`Self::solve`] through `submitter` (the engine's queue or a host's): per chunk of
    /// systems, an upload of the matrices, right-hand sides and pivot thresholds, one
    /// workgroup per system, and a recorded readback of solutions and statuses; the results
    /// are read once after every chunk was submitted.
    pub fn solve_with(
        &self,
        submitter: &mut dyn Submitter,
        what: &str,
        matrices: &[&Tensor],
        rhs: &[&[f64]],
    ) -> GpuResult<Vec<Result<Vec<f64>, TensorError>>> {
        let gpu = &submitter.gpu().clone();
        assert_eq!(matrices.len(), rhs.len(), "one right-hand side per matrix");
        let Some(first) = matrices.first() else { return Ok(Vec::new()) };
        let n = first.shape().first().copied().unwrap_or(0);
        let mut results: Vec<Option<Result<Vec<f64>, TensorError>>> = vec![None; matrices.len()];
        // Systems that cannot be sent: not n × n (the batch's size) or non-finite values.
        let mut sent = Vec::new();
        for (s, (a, b)) in matrices.iter().zip(rhs).enumerate() {
            let check = check_system(what, a, b).and_then(|m| {
                if m == n {
                    Ok(())
                } else {
                    Err(TensorError::Shape { what: what.into(), axis: 0, expected: n, found: m })
                }
            });
            match check {
                Ok(()) => sent.push(s),
                Err(e) => results[s] = Some(Err(e)),
            }
        }
        if n > 0 && !sent.is_empty() {
            let floats = (gpu.max_binding_bytes() / 4) as usize;
            let per_chunk = (floats / (n * n)).max(1).min(sent.len());
            if n * n > floats {
                return Err(GpuError::OverLimit {
                    name: format!("{what} ({n}×{n} system)"),
                    requested: (n * n * 4) as u64,
                    limit: gpu.max_binding_bytes(),
                    limit_name: "maxStorageBufferRange (one system must fit one binding)",
                    unit: "bytes",
                });
            }
            let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
            let new = |name: &str, len: usize| {
                Buffer::<f32>::new(gpu, name, len as u64, storage, MemoryKind::GpuOnly)
            };
            if !sent.is_empty() {
                let mats = new("lu solve matrices", per_chunk * n * n)?;
                let xs = new("lu solve right-hand sides", per_chunk * n)?;
                let tol = new("lu solve pivot thresholds", per_chunk)?;
                let status = Buffer::<Status>::new(
                    gpu,
                    "lu solve status",
                    per_chunk as u64,
                    storage,
                    MemoryKind::GpuOnly,
                )?;
                let set = self.pipeline.bind(
                    gpu,
                    &[mats.binding()?, xs.binding()?, tol.binding()?, status.binding()?]
                        .map(Resource::Storage),
                )?;
                let mut readbacks = Vec::new();
                for chunk in sent.chunks(per_chunk) {
                    let a: Vec<f32> =
                        chunk.iter().flat_map(|&s| matrices[s].data().iter().map(|&v| v as f32)).collect();
                    let b: Vec<f32> = chunk.iter().flat_map(|&s| rhs[s].iter().map(|&v| v as f32)).collect();
                    let t: Vec<f32> = chunk
                        .iter()
                        .map(|&s| pivot_tolerance(matrices[s], f64::from(f32::EPSILON)) as f32)
                        .collect();
                    // Each step's leading barrier orders these copies after the previous
                    // chunk's solve and readback.
                    submitter.upload(&mats, 0, &a)?;
                    submitter.upload(&xs, 0, &b)?;
                    submitter.upload(&tol, 0, &t)?;
                    let push = SolvePush { n: n as u32, batch: chunk.len() as u32 };
                    submitter.submit(&mut |rec| {
                        self.pipeline.record_dispatch(rec, &set, &push, [chunk.len() as u32, 1, 1])
                    })?;
                    let x = submitter.record_readback(&xs, 0, (chunk.len() * n) as u64)?;
                    let st = submitter.record_readback(&status, 0, chunk.len() as u64)?;
                    readbacks.push((chunk, x, st));
                }
                submitter.complete()?;
                for (chunk, x, st) in readbacks {
                    let (x, st) = (x.read()?, st.read()?);
                    for (c, &s) in chunk.iter().enumerate() {
                        results[s] = Some(match st[c] {
                            Status { row_plus_one: 0, .. } => {
                                Ok(x[c * n..(c + 1) * n].iter().map(|&v| f64::from(v)).collect())
                            }
                            Status { row_plus_one, pivot } => Err(TensorError::Singular {
                                what: what.into(),
                                row: row_plus_one as usize - 1,
                                pivot: f64::from(pivot),
                            }),
                        });
                    }
                }
            }
        }
        Ok(results.into_iter().map(|r| r.unwrap_or_else(|| Ok(Vec::new()))).collect())
    }
}
