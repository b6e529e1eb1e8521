//! `y ← a·x + y` on the device: the first compute pass. Arrays larger than one storage binding
//! (128 MiB on lavapipe) are walked chunk by chunk, one descriptor set per chunk.

use crate::gpu::{
    BindingKind, Buffer, Chunk, ComputePipeline, ComputePipelineDesc, DescriptorSet, Gpu, GpuResult,
    Recorder, Resource,
};

crate::push_constants! {
    struct Push {
        a: f32,
        n: u32,
    }
}

/// The axpy compute pipeline.
pub struct Axpy {
    pipeline: ComputePipeline,
}

/// `x` and `y` bound chunk by chunk.
pub struct AxpyBinding {
    chunks: Vec<(Chunk, DescriptorSet)>,
}

impl AxpyBinding {
    /// Number of chunks (1 when the arrays fit in one binding).
    pub fn chunk_count(&self) -> usize {
        self.chunks.len()
    }
}

impl Axpy {
    /// Builds the pipeline.
    pub fn new(gpu: &Gpu) -> GpuResult<Self> {
        let pipeline = ComputePipeline::new(
            gpu,
            &ComputePipelineDesc {
                name: "axpy",
                spirv: crate::demo::shaders::AXPY,
                bindings: &[BindingKind::StorageBuffer, BindingKind::StorageBuffer],
                push: crate::gpu::PushLayout::of::<Push>(),
                specialization: &[],
            },
        )?;
        Ok(Self { pipeline })
    }

    /// Binds `x` and `y` (same length) in chunks of at most one storage binding each.
    pub fn bind(&self, gpu: &Gpu, x: &Buffer<f32>, y: &Buffer<f32>) -> GpuResult<AxpyBinding> {
        assert_eq!(x.len(), y.len(), "axpy: x and y differ in length");
        let chunks = y
            .binding_chunks()
            .into_iter()
            .map(|c| {
                let set = self.pipeline.bind(
                    gpu,
                    &[Resource::Storage(x.binding_range(c)), Resource::Storage(y.binding_range(c))],
                )?;
                Ok((c, set))
            })
            .collect::<GpuResult<_>>()?;
        Ok(AxpyBinding { chunks })
    }

    /// Records `y ← a·x + y` over every chunk.
    pub fn record(&self, gpu: &Gpu, rec: &mut Recorder<'_>, binding: &AxpyBinding, a: f32) {
        for (chunk, set) in &binding.chunks {
            let n = u32::try_from(chunk.len).expect("a binding chunk holds fewer than 2^32 floats");
            let push = Push { a, n };
            let groups = gpu.caps().groups_1d(chunk.len, self.pipeline.local_size()[0]);
            self.pipeline.record_dispatch(rec, set, &push, [groups, 1, 1]);
        }
    }
}

/// CPU f64 reference: `a·x + y` per element.
pub fn axpy_reference(a: f64, x: &[f32], y: &[f32]) -> Vec<f64> {
    x.iter().zip(y).map(|(&x, &y)| a * f64::from(x) + f64::from(y)).collect()
}

/// The largest error relative to the f32 error bound, and where (≤ 1 passes).
/// The device computes `fma(a, x, y)` in f32: one rounding if the FMA is fused, two (product,
/// then sum) if the driver splits it — lavapipe does, and its worst case sits just under the
/// bound. Each rounding is at most half an ulp, ≤ 2⁻²⁴ of the value rounded, so
/// |gpu − exact| ≤ 2⁻²⁴(|a·x| + |a·x + y|) + 2⁻⁴⁸|a·x| ≤ 2⁻²³(|a·x| + |y|)(1 + 2⁻²²), plus the
/// rounding of `a` itself to f32 (|a − a_f32|·|x|).
pub fn axpy_error_ratio(a: f64, x: &[f32], y: &[f32], gpu: &[f32]) -> (f64, usize) {
    let a32 = f64::from(a as f32);
    let mut worst = (0.0, 0);
    for (i, ((&x, &y), &g)) in x.iter().zip(y).zip(gpu).enumerate() {
        let (x, y) = (f64::from(x), f64::from(y));
        let reference = a * x + y;
        let bound = 2f64.powi(-23) * (a.abs() * x.abs() + y.abs()) * (1.0 + 2f64.powi(-22))
            + (a - a32).abs() * x.abs()
            + f64::MIN_POSITIVE;
        let ratio = (f64::from(g) - reference).abs() / bound;
        let ratio = if ratio.is_nan() { f64::INFINITY } else { ratio };
        if ratio > worst.0 {
            worst = (ratio, i);
        }
    }
    worst
}
