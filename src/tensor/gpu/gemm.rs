//! The shared-memory tiled SGEMM (`shaders-glsl/tensor/gemm.comp`, tiling in
//! `shaders-glsl/include/gemm_tile.glsl`).

use crate::gpu::{
    BindingKind, BufferBinding, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuResult,
    Recorder, Resource,
};

/// Tile edge of `include/gemm_tile.glsl` (rows and columns of C per workgroup). Its shared
/// tiles hold `2 · GEMM_TILE · GEMM_KT` floats, which `tests/shader_layout.rs` checks against
/// the workgroup memory the SPIR-V declares.
pub const GEMM_TILE: u32 = 64;

/// The k-step of `include/gemm_tile.glsl` (the depth of its shared tiles).
pub const GEMM_KT: u32 = 32;

crate::push_constants! {
    struct GemmPush {
        m: u32,
        n: u32,
        k: u32,
        accumulate: u32,
    }
}

/// `C = A·B` or `C += A·B` in f32, row-major, any sizes.
pub struct Gemm {
    pipeline: ComputePipeline,
}

/// Sizes of `C (m×n) = A (m×k) · B (k×n)`.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub struct GemmShape {
    /// Rows of A and C.
    pub m: u32,
    /// Columns of B and C.
    pub n: u32,
    /// Columns of A, rows of B.
    pub k: u32,
}

/// A, B and C bound with their sizes.
pub struct GemmBinding {
    set: DescriptorSet,
    m: u32,
    n: u32,
    k: u32,
}

impl GemmBinding {
    /// Multiply–adds of one product.
    pub fn flops(&self) -> f64 {
        f64::from(self.m) * f64::from(self.n) * f64::from(self.k)
    }
}

impl Gemm {
    /// Builds the pipeline (16 KiB of shared memory, 64 invocations per workgroup).
    pub fn new(gpu: &Gpu) -> GpuResult<Self> {
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "gemm",
                spirv: crate::tensor::shaders::GEMM,
                bindings: &[BindingKind::StorageBuffer; 3],
                push: crate::gpu::PushLayout::of::<GemmPush>(),
                specialization: &[],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// Binds A (m×k), B (k×n) and C (m×n), each within one storage binding. The ranges must
    /// hold at least that many f32 values (checked).
    pub fn bind(
        &self,
        gpu: &Gpu,
        a: BufferBinding,
        b: BufferBinding,
        c: BufferBinding,
        shape: GemmShape,
    ) -> GpuResult<GemmBinding> {
        let GemmShape { m, n, k } = shape;
        let need = |r: BufferBinding, rows: u32, cols: u32, what: &str| {
            assert!(
                r.range >= 4 * u64::from(rows) * u64::from(cols),
                "gemm: {what} binding holds {} bytes, needs {rows}×{cols} f32",
                r.range
            );
        };
        need(a, m, k, "A");
        need(b, k, n, "B");
        need(c, m, n, "C");
        let set =
            self.pipeline.bind(gpu, &[Resource::Storage(a), Resource::Storage(b), Resource::Storage(c)])?;
        Ok(GemmBinding { set, m, n, k })
    }

    /// Records `C = A·B`, or `C += A·B` with `accumulate`.
    pub fn record(&self, rec: &mut Recorder<'_>, binding: &GemmBinding, accumulate: bool) {
        let push = GemmPush { m: binding.m, n: binding.n, k: binding.k, accumulate: u32::from(accumulate) };
        let groups = [binding.n.div_ceil(GEMM_TILE), binding.m.div_ceil(GEMM_TILE), 1];
        self.pipeline.record_dispatch(rec, &binding.set, &push, groups);
    }
}
