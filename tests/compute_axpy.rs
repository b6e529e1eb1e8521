//! The first compute pass against its CPU f64 reference, every element, in one binding and in
//! chunks (forced small, and for real past lavapipe's 128 MiB `maxStorageBufferRange`).

mod common;

use galerkin::demo::axpy::{axpy_error_ratio, Axpy};
use galerkin::gpu::{vk, Buffer};

fn check_axpy(gpu: &galerkin::gpu::Gpu, n: usize, a: f32, expect_chunks: Option<usize>) {
    let x = common::random_f32(n, 1);
    let y = common::random_f32(n, 2);
    let xb = Buffer::from_slice(gpu, "x", &x, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let yb = Buffer::from_slice(gpu, "y", &y, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
    let axpy = Axpy::new(gpu).unwrap();
    let binding = axpy.bind(gpu, &xb, &yb).unwrap();
    if let Some(c) = expect_chunks {
        assert_eq!(binding.chunk_count(), c, "chunks for {n} floats");
    }
    gpu.run(|rec| axpy.record(gpu, rec, &binding, a)).unwrap();
    let out = yb.download(gpu).unwrap();
    // Tolerance: the device's fma(a, x, y) in f32 is within two roundings of the exact value
    // (one if fused); `axpy_error_ratio` divides each error by that bound.
    let (ratio, at) = axpy_error_ratio(f64::from(a), &x, &y, &out);
    assert!(
        ratio <= 1.0,
        "element {at}: error {ratio} times the f32 bound (gpu {} vs x {} y {})",
        out[at],
        x[at],
        y[at]
    );
}

#[test]
fn axpy_ten_million_in_one_binding() {
    let gpu = common::gpu();
    check_axpy(&gpu, 10_000_000, 2.5, Some(1));
}

#[test]
fn axpy_in_forced_small_chunks() {
    // 1 MiB bindings: 3 000 017 floats (12 MB, not a multiple of anything) need 12 chunks.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(1 << 20));
    check_axpy(&gpu, 3_000_017, -0.75, Some(12));
}

#[test]
fn axpy_past_one_real_binding() {
    // 40 M floats = 160 MB per array: over lavapipe's 128 MiB maxStorageBufferRange.
    let gpu = common::gpu();
    let n = 40_000_000usize;
    let expected = (n as u64 * 4).div_ceil(gpu.max_binding_bytes()) as usize;
    check_axpy(&gpu, n, 1.5, Some(expected));
    assert!(expected >= 2 || gpu.max_binding_bytes() >= 160_000_000);
}
