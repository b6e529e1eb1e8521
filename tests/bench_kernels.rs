//! The ceiling kernels compute what they claim, against CPU f64 references, before their
//! timings are trusted; timestamp scopes measure positive time.

mod common;

use galerkin::bench::kernels::{EmptyKernel, FmaKernel, SgemmKernel, TriadKernel};
use galerkin::gpu::{vk, Buffer, MemoryKind, Profiler};

#[test]
fn sgemm_matches_a_cpu_f64_product_at_odd_sizes() {
    let gpu = common::gpu();
    for &(m, n, k) in &[(64u32, 64u32, 64u32), (70, 33, 100), (1, 129, 17)] {
        let a = common::random_f32((m * k) as usize, 11);
        let b = common::random_f32((k * n) as usize, 12);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let ab = Buffer::from_slice(&gpu, "A", &a, usage).unwrap();
        let bb = Buffer::from_slice(&gpu, "B", &b, usage).unwrap();
        let cb = Buffer::<f32>::new(&gpu, "C", u64::from(m * n), usage, MemoryKind::GpuOnly).unwrap();
        let gemm = SgemmKernel::new(&gpu, &ab, &bb, &cb, m, n, k).unwrap();
        gpu.run(|rec| gemm.record(rec)).unwrap();
        let c = cb.download(&gpu).unwrap();
        for i in 0..m as usize {
            for j in 0..n as usize {
                let (mut exact, mut scale) = (0f64, 0f64);
                for l in 0..k as usize {
                    let t = f64::from(a[i * k as usize + l]) * f64::from(b[l * n as usize + j]);
                    exact += t;
                    scale += t.abs();
                }
                // f32 accumulation of k products: |error| ≤ k·2⁻²⁴·Σ|a||b| (standard bound).
                let tol = f64::from(k) * 2f64.powi(-24) * scale + 1e-30;
                let got = f64::from(c[i * n as usize + j]);
                assert!((got - exact).abs() <= tol, "{m}x{n}x{k} C[{i}][{j}] = {got} vs {exact} (tol {tol})");
            }
        }
    }
}

#[test]
fn triad_and_fma_compute_their_references() {
    let gpu = common::gpu();
    let n = 4096 + 4;
    let b = common::random_f32(n, 21);
    let c = common::random_f32(n, 22);
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let ab = Buffer::<f32>::new(&gpu, "a", n as u64, usage, MemoryKind::GpuOnly).unwrap();
    let bb = Buffer::from_slice(&gpu, "b", &b, usage).unwrap();
    let cb = Buffer::from_slice(&gpu, "c", &c, usage).unwrap();
    let triad = TriadKernel::new(&gpu, &ab, &bb, &cb).unwrap();
    gpu.run(|rec| triad.record(&gpu, rec, 0.5)).unwrap();
    let got = ab.download(&gpu).unwrap();
    for i in 0..n {
        // b + 0.5c: the product is exact, one rounding in the sum.
        let exact = f64::from(b[i]) + 0.5 * f64::from(c[i]);
        assert!((f64::from(got[i]) - exact).abs() <= 2f64.powi(-24) * exact.abs() + 1e-45, "a[{i}]");
    }

    let fma = FmaKernel::new(&gpu, 2).unwrap();
    let (iters, a, bb) = (100, 0.999f32, 1e-3f32);
    gpu.run(|rec| fma.record(rec, iters, a, bb)).unwrap();
    let sink = fma.sink.download(&gpu).unwrap();
    for (i, &s) in sink.iter().enumerate() {
        let want = FmaKernel::reference(i as u32, iters, a, bb);
        // 100 contracting steps (|a| < 1) keep the f32 error near a few ulps of 8.
        assert!((f64::from(s) - want).abs() < 1e-5 * want.abs(), "invocation {i}: {s} vs {want}");
    }
    assert_eq!(fma.flops(iters), 2.0 * 8.0 * 100.0 * 512.0);
}

#[test]
fn timestamp_scopes_measure_work() {
    let gpu = common::gpu();
    let empty = EmptyKernel::new(&gpu).unwrap();
    let fma = FmaKernel::new(&gpu, 64).unwrap();
    let mut profiler = Profiler::new(&gpu, 2).unwrap();
    gpu.run(|rec| {
        profiler.record_reset(rec);
        profiler.scope(rec, "empty", |rec| empty.record(rec));
        profiler.scope(rec, "fma", |rec| fma.record(rec, 2000, 0.9, 0.1));
    })
    .unwrap();
    let r = profiler.results().unwrap();
    assert_eq!(r.iter().map(|s| s.0.as_str()).collect::<Vec<_>>(), ["empty", "fma"]);
    assert!(r[1].1 > 0.0 && r[1].1 < 60_000.0, "fma scope took {} ms", r[1].1);
    assert!(r[0].1 >= 0.0);
}
