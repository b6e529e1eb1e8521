//! The CPU peers of the ceiling kernels, on the same data: an FMA chain (AVX2+FMA where the
//! CPU has it, on every core), the STREAM triad as a plain Rust loop on every core, `memcpy`,
//! faer's GEMM, and a thread round trip as the peer of a dispatch.

use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Threads the CPU peers use: every core.
pub fn threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Eight independent chains of `v ← v·a + b`, `iterations` rounds, per lane and thread.
/// Returns (floating-point operations, a checksum that keeps the work alive).
pub fn fma_peak(iterations: u64, a: f32, b: f32) -> (f64, f32) {
    let t = threads();
    let sums: Vec<f32> = std::thread::scope(|s| {
        let handles: Vec<_> =
            (0..t).map(|i| s.spawn(move || fma_thread(iterations, a, b, i as f32))).collect();
        handles.into_iter().map(|h| h.join().unwrap_or(f32::NAN)).collect()
    });
    let lanes = match simd() {
        Simd::Avx512 => 16.0,
        Simd::Avx2Fma => 8.0,
        Simd::Portable => 4.0,
    };
    (2.0 * 8.0 * lanes * iterations as f64 * t as f64, sums.iter().sum())
}

/// The widest FMA the CPU has.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
pub enum Simd {
    /// 16 f32 lanes.
    Avx512,
    /// 8 f32 lanes.
    Avx2Fma,
    /// Whatever the compiler makes of a plain loop (4 lanes assumed).
    Portable,
}

/// Detects [`Simd`] at run time.
pub fn simd() -> Simd {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f") {
            return Simd::Avx512;
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            return Simd::Avx2Fma;
        }
    }
    Simd::Portable
}

fn fma_thread(iterations: u64, a: f32, b: f32, seed: f32) -> f32 {
    #[cfg(target_arch = "x86_64")]
    match simd() {
        // SAFETY: the CPU supports AVX-512F (detected at run time).
        Simd::Avx512 => return unsafe { fma_avx512(iterations, a, b, seed) },
        // SAFETY: the CPU supports AVX2 and FMA (detected at run time).
        Simd::Avx2Fma => return unsafe { fma_avx2(iterations, a, b, seed) },
        Simd::Portable => {}
    }
    // Portable: 8 chains of 4 lanes, written so the compiler vectorises them (SSE2 baseline).
    let mut v = [[seed; 4]; 8];
    for (c, chain) in v.iter_mut().enumerate() {
        for (l, x) in chain.iter_mut().enumerate() {
            *x += (c * 4 + l) as f32 * 1e-3;
        }
    }
    for _ in 0..iterations {
        for chain in v.iter_mut() {
            for x in chain.iter_mut() {
                *x = *x * a + b;
            }
        }
    }
    v.iter().flatten().sum()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn fma_avx2(iterations: u64, a: f32, b: f32, seed: f32) -> f32 {
    use std::arch::x86_64::*;
    let va = _mm256_set1_ps(a);
    let vb = _mm256_set1_ps(b);
    let mut v: [__m256; 8] = std::array::from_fn(|c| _mm256_set1_ps(seed + c as f32 * 1e-3));
    for _ in 0..iterations {
        for x in v.iter_mut() {
            *x = _mm256_fmadd_ps(*x, va, vb);
        }
    }
    let mut out = [0f32; 8];
    let mut total = _mm256_setzero_ps();
    for x in v {
        total = _mm256_add_ps(total, x);
    }
    // SAFETY: `out` holds 8 floats, the unaligned store writes exactly 8.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), total) };
    out.iter().sum()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn fma_avx512(iterations: u64, a: f32, b: f32, seed: f32) -> f32 {
    use std::arch::x86_64::*;
    let va = _mm512_set1_ps(a);
    let vb = _mm512_set1_ps(b);
    let mut v: [__m512; 8] = std::array::from_fn(|c| _mm512_set1_ps(seed + c as f32 * 1e-3));
    for _ in 0..iterations {
        for x in v.iter_mut() {
            *x = _mm512_fmadd_ps(*x, va, vb);
        }
    }
    v.iter().map(|&x| _mm512_reduce_add_ps(x)).sum()
}

/// STREAM triad `a ← b + s·c`, the arrays split across every core.
pub fn triad(a: &mut [f32], b: &[f32], c: &[f32], s: f32) {
    let t = threads();
    let chunk = a.len().div_ceil(t).max(1);
    std::thread::scope(|scope| {
        for ((a, b), c) in a.chunks_mut(chunk).zip(b.chunks(chunk)).zip(c.chunks(chunk)) {
            scope.spawn(move || {
                for ((a, &b), &c) in a.iter_mut().zip(b).zip(c) {
                    *a = b + s * c;
                }
            });
        }
    });
}

/// `C ← A·B` with faer (row-major slices), on every core.
pub fn gemm(a: &[f32], b: &[f32], c: &mut [f32], m: usize, n: usize, k: usize) {
    use faer::linalg::matmul::matmul;
    use faer::{Accum, MatMut, MatRef, Par};
    let a = MatRef::from_row_major_slice(a, m, k);
    let b = MatRef::from_row_major_slice(b, k, n);
    let c = MatMut::from_row_major_slice_mut(c, m, n);
    matmul(c, Accum::Replace, a, b, 1.0f32, Par::rayon(0));
}

/// Median time of a round trip to a waiting worker thread and back (the CPU's "submit and
/// wait"), over `reps` trips.
pub fn thread_round_trip(reps: usize) -> Duration {
    let (to_worker, worker_rx) = mpsc::channel::<()>();
    let (to_main, main_rx) = mpsc::channel::<()>();
    let worker = std::thread::spawn(move || {
        while worker_rx.recv().is_ok() {
            if to_main.send(()).is_err() {
                break;
            }
        }
    });
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        if to_worker.send(()).is_err() || main_rx.recv().is_err() {
            break;
        }
        times.push(t.elapsed());
    }
    drop(to_worker);
    let _ = worker.join();
    super::median(&mut times)
}
