//! The ceiling kernels on the device: an empty dispatch, an FMA chain, the STREAM triad and a
//! shared-memory tiled SGEMM. Each is a small pass (pipeline + bind + record) so that tests can
//! check its result against the CPU before the benchmark trusts its timing.

use ash::vk;

use crate::gpu::{
    BindingKind, Buffer, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuResult, Recorder,
    Resource,
};
use crate::tensor::gpu::{Gemm, GemmBinding, GemmShape};

fn storage(b: &Buffer<f32>) -> GpuResult<Resource<'_>> {
    Ok(Resource::Storage(b.binding()?))
}

/// Does nothing: measures the cost of one dispatch, submit and wait.
pub struct EmptyKernel {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _sink: Buffer<f32>,
}

impl EmptyKernel {
    /// Builds it.
    pub fn new(gpu: &Gpu) -> GpuResult<Self> {
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "empty",
                spirv: crate::bench::shaders::EMPTY,
                bindings: &[BindingKind::StorageBuffer],
                push: crate::gpu::PushLayout::none(),
                specialization: &[],
            },
        )?;
        let sink = Buffer::new(
            gpu,
            "empty sink",
            1,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            crate::gpu::MemoryKind::GpuOnly,
        )?;
        let set = pipeline.bind(gpu, &[storage(&sink)?])?;
        Ok(Self { pipeline, set, _sink: sink })
    }

    /// Records one 1×1×1 dispatch.
    pub fn record(&self, rec: &mut Recorder<'_>) {
        self.pipeline.record_dispatch(rec, &self.set, &(), [1, 1, 1]);
    }
}

crate::push_constants! {
    struct FmaPush {
        iterations: u32,
        a: f32,
        b: f32,
    }
}

/// Eight independent FMA chains per invocation (`fma.comp`).
pub struct FmaKernel {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    /// One float per invocation: the sum of its chains.
    pub sink: Buffer<f32>,
    invocations: u32,
}

/// Invocations per FMA workgroup.
pub const FMA_LOCAL_SIZE: u32 = 256;

impl FmaKernel {
    /// Builds it for `groups` workgroups of 256 invocations.
    pub fn new(gpu: &Gpu, groups: u32) -> GpuResult<Self> {
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "fma peak",
                spirv: crate::bench::shaders::FMA,
                bindings: &[BindingKind::StorageBuffer],
                push: crate::gpu::PushLayout::of::<FmaPush>(),
                specialization: &[],
            },
        )?;
        let invocations = groups * FMA_LOCAL_SIZE;
        let sink = Buffer::new(
            gpu,
            "fma sink",
            u64::from(invocations),
            vk::BufferUsageFlags::STORAGE_BUFFER,
            crate::gpu::MemoryKind::GpuOnly,
        )?;
        let set = pipeline.bind(gpu, &[storage(&sink)?])?;
        Ok(Self { pipeline, set, sink, invocations })
    }

    /// Records the kernel: `iterations` rounds of `v ← v·a + b` on each of 8 chains.
    pub fn record(&self, rec: &mut Recorder<'_>, iterations: u32, a: f32, b: f32) {
        let push = FmaPush { iterations, a, b };
        self.pipeline.record_dispatch(rec, &self.set, &push, [self.invocations / FMA_LOCAL_SIZE, 1, 1]);
    }

    /// Floating-point operations of one run.
    pub fn flops(&self, iterations: u32) -> f64 {
        2.0 * 8.0 * f64::from(iterations) * f64::from(self.invocations)
    }

    /// CPU f64 reference of invocation `i`'s output (same start values as the shader).
    pub fn reference(i: u32, iterations: u32, a: f32, b: f32) -> f64 {
        let x = f64::from(i as f32 * 1e-7);
        let mut total = 0.0;
        for c in 0..8 {
            let mut v = f64::from((x + f64::from(c) * 0.1) as f32);
            for _ in 0..iterations {
                v = v * f64::from(a) + f64::from(b);
            }
            total += v;
        }
        total
    }
}

crate::push_constants! {
    struct TriadPush {
        s: f32,
        n4: u32,
    }
}

/// STREAM triad `a ← b + s·c` (`triad.comp`).
pub struct TriadKernel {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    n4: u32,
}

impl TriadKernel {
    /// Binds `a`, `b`, `c` (equal lengths, a multiple of 4, each within one binding).
    pub fn new(gpu: &Gpu, a: &Buffer<f32>, b: &Buffer<f32>, c: &Buffer<f32>) -> GpuResult<Self> {
        assert!(
            a.len() == b.len() && b.len() == c.len() && a.len().is_multiple_of(4),
            "triad arrays: equal lengths, multiple of 4"
        );
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "triad",
                spirv: crate::bench::shaders::TRIAD,
                bindings: &[BindingKind::StorageBuffer; 3],
                push: crate::gpu::PushLayout::of::<TriadPush>(),
                specialization: &[],
            },
        )?;
        let set = pipeline.bind(gpu, &[storage(a)?, storage(b)?, storage(c)?])?;
        Ok(Self { pipeline, set, n4: (a.len() / 4) as u32 })
    }

    /// Records one sweep.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, s: f32) {
        let push = TriadPush { s, n4: self.n4 };
        let groups = gpu.caps().groups_1d(u64::from(self.n4), 256);
        self.pipeline.record_dispatch(rec, &self.set, &push, [groups, 1, 1]);
    }

    /// Bytes read and written by one sweep.
    pub fn bytes(&self) -> f64 {
        3.0 * 16.0 * f64::from(self.n4)
    }
}

/// The tiled SGEMM `C ← A·B` of [`crate::tensor::gpu::Gemm`], bound for the benchmark.
pub struct SgemmKernel {
    gemm: Gemm,
    binding: GemmBinding,
}

impl SgemmKernel {
    /// Binds A (m×k), B (k×n) and C (m×n).
    pub fn new(
        gpu: &Gpu,
        a: &Buffer<f32>,
        b: &Buffer<f32>,
        c: &Buffer<f32>,
        m: u32,
        n: u32,
        k: u32,
    ) -> GpuResult<Self> {
        let gemm = Gemm::new(gpu)?;
        let binding = gemm.bind(gpu, a.binding()?, b.binding()?, c.binding()?, GemmShape { m, n, k })?;
        Ok(Self { gemm, binding })
    }

    /// Records the product.
    pub fn record(&self, rec: &mut Recorder<'_>) {
        self.gemm.record(rec, &self.binding, false);
    }

    /// Floating-point operations of one product.
    pub fn flops(&self) -> f64 {
        2.0 * self.binding.flops()
    }
}
