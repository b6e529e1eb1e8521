//! Test harness: every GPU test gets a `Gpu` with the Khronos validation layer (and
//! synchronization validation) on, and fails if any validation error was recorded — including
//! leaked-object reports made when the device and instance are destroyed at the end.
#![allow(dead_code)]

pub mod evaluations;
pub mod host;
pub mod models;
pub mod obj_box;
pub mod surfaces;
pub mod tunnel;
pub mod volumes;
pub mod wavy;

use std::ops::Deref;
use std::sync::Arc;

use galerkin::gpu::{Gpu, GpuDesc, ValidationLog};

/// A validated `Gpu` that checks its validation log when dropped.
pub struct TestGpu {
    gpu: Option<Gpu>,
    log: Arc<ValidationLog>,
}

impl Deref for TestGpu {
    type Target = Gpu;
    fn deref(&self) -> &Gpu {
        self.gpu.as_ref().expect("gpu is present until drop")
    }
}

impl Drop for TestGpu {
    fn drop(&mut self) {
        drop(self.gpu.take());
        if !std::thread::panicking() {
            self.log.assert_clean();
        }
    }
}

/// A `Gpu` with validation on; `configure` may adjust the description.
pub fn gpu_with(configure: impl FnOnce(&mut GpuDesc)) -> TestGpu {
    let mut desc = GpuDesc { validation: true, ..GpuDesc::from_env() };
    configure(&mut desc);
    let gpu = match Gpu::new(&desc) {
        Ok(g) => g,
        Err(e) => panic!("cannot create the test Gpu: {e}"),
    };
    let log = gpu.validation_log().expect("validation is on in tests");
    TestGpu { gpu: Some(gpu), log }
}

/// A `Gpu` with validation on.
pub fn gpu() -> TestGpu {
    gpu_with(|_| {})
}

/// Deterministic pseudo-random floats in [-1, 1) (SplitMix64), so tests need no RNG crate.
pub fn random_f32(n: usize, seed: u64) -> Vec<f32> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = s;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        })
        .collect()
}

/// Plain dense f64 reference of premultiplication: one mode product per axis, in axis order
/// (written independently of the library's planned chain).
pub fn dense_reference(
    q: &galerkin::tensor::Tensor,
    bases: &[&galerkin::tensor::Tensor],
) -> galerkin::tensor::Tensor {
    let mut t = q.clone();
    for (axis, b) in bases.iter().enumerate() {
        t = t.mode_product(axis, b).expect("bases fit the tensor");
    }
    t
}

/// A random sparse tensor of `order` axes with shape `5 + 3a` per axis and `nnz` entries
/// (duplicates allowed: they add up), values in [-1, 1).
pub fn random_sparse(order: usize, nnz: usize) -> galerkin::tensor::SparseTensor {
    let shape: Vec<usize> = (0..order).map(|a| 5 + 3 * a).collect();
    let mut q = galerkin::tensor::SparseTensor::new(&shape);
    let total: usize = shape.iter().product();
    for (e, p) in random_f32(nnz, order as u64).into_iter().map(f64::from).enumerate() {
        let mut flat = ((p.abs() * 1e6) as usize + e * 7919) % total;
        let mut index = vec![0; order];
        for a in (0..order).rev() {
            index[a] = flat % shape[a];
            flat /= shape[a];
        }
        q.push(&index, p);
    }
    q
}

/// Runs a test probe: the compute shader `spirv` with one storage buffer per entry of
/// `buffers` (bindings 0, 1, …), push constants `push` (checked against the shader's block)
/// and `groups` workgroups, and waits.
pub fn run_probe<P: galerkin::gpu::PushConstants + 'static>(
    gpu: &galerkin::gpu::Gpu,
    name: &str,
    spirv: &'static [u32],
    buffers: &[galerkin::gpu::BufferBinding],
    push: &P,
    groups: u32,
) {
    run_probe_specialized(gpu, name, spirv, buffers, push, groups, &[]);
}

galerkin::push_constants! {
    /// The probes' `Push { uint n; }`: how many inputs.
    pub struct CountPush {
        pub n: u32,
    }
}

/// [`run_probe`] with specialization constants 0, 1, … set to `specialization`.
pub fn run_probe_specialized<P: galerkin::gpu::PushConstants + 'static>(
    gpu: &galerkin::gpu::Gpu,
    name: &str,
    spirv: &'static [u32],
    buffers: &[galerkin::gpu::BufferBinding],
    push: &P,
    groups: u32,
    specialization: &[u32],
) {
    use galerkin::gpu::{BindingKind, ComputePipeline, ComputePipelineDesc, Resource};
    let bindings = vec![BindingKind::StorageBuffer; buffers.len()];
    let pipeline = ComputePipeline::new(
        gpu,
        &ComputePipelineDesc {
            name,
            spirv,
            bindings: &bindings,
            push: galerkin::gpu::PushLayout::of::<P>(),
            specialization,
        },
    )
    .expect("the probe pipeline builds");
    let resources: Vec<Resource> = buffers.iter().map(|&b| Resource::Storage(b)).collect();
    let set = pipeline.bind(gpu, &resources).expect("the probe binds");
    gpu.run(|rec| pipeline.record_dispatch(rec, &set, push, [groups, 1, 1])).expect("the probe runs");
}

/// A scratch directory for one test, removed (with everything in it) when dropped.
pub struct Scratch(tempfile::TempDir);

impl Scratch {
    /// A new empty directory under the system's temporary directory.
    pub fn new() -> Self {
        Self(tempfile::Builder::new().prefix("galerkin-test-").tempdir().expect("a scratch directory"))
    }

    /// The path of `name` inside it.
    pub fn file(&self, name: &str) -> std::path::PathBuf {
        self.0.path().join(name)
    }
}
