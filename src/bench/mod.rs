//! Benchmarks. [`run`]: the device's ceilings, each next to its CPU peer on the same data: dispatch overhead,
//! upload/download bandwidth, FMA peak, streaming bandwidth and a tiled SGEMM (peer: faer).
//! `galerkin bench gpu` and `cargo bench` print the table that BENCHMARKS.md records; every
//! later kernel is judged against these numbers. GPU throughput is timed with timestamp
//! queries (kernel only); overheads and transfers with the wall clock. Medians throughout.

/// This part's shaders: SPIR-V compiled by build.rs from `shaders-glsl/bench/` (glslc), one
/// `&[u32]` constant per file (`foo.comp` is `FOO`, `bar.vert` is `BAR_VERT`).
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders_bench.rs"));
}
pub mod cpu;
pub mod fluid;
pub mod fluid_reduced;
pub mod kernels;
pub mod radiosity;
pub mod reduce;
pub mod report;
pub mod spacetime;
pub mod spectral;
pub mod spectral_derived;
pub mod spectral_iso;
pub mod spectral_volume;

use std::time::{Duration, Instant};

use ash::vk;

use crate::gpu::{Buffer, Gpu, GpuResult, MemoryKind, Profiler};
use kernels::{EmptyKernel, FmaKernel, SgemmKernel, TriadKernel};

/// Sizes and repetitions of a benchmark run.
#[derive(Clone, Copy, Debug)]
pub struct BenchConfig {
    /// Repetitions per measurement (the median is reported).
    pub reps: usize,
    /// Dispatches for the overhead measurement.
    pub dispatches: usize,
    /// Bytes per upload/download.
    pub transfer_bytes: u64,
    /// FMA iterations per chain on the GPU.
    pub fma_iterations: u32,
    /// FMA workgroups (256 invocations each).
    pub fma_groups: u32,
    /// Floats per triad array.
    pub triad_len: u64,
    /// SGEMM size (square).
    pub gemm_size: u32,
}

impl BenchConfig {
    /// The sizes BENCHMARKS.md records.
    pub fn full() -> Self {
        Self {
            reps: 5,
            dispatches: 200,
            transfer_bytes: 256 << 20,
            fma_iterations: 4096,
            fma_groups: 1024,
            triad_len: 16 << 20,
            gemm_size: 1024,
        }
    }

    /// Small sizes for a quick look (seconds, not minutes).
    pub fn quick() -> Self {
        Self {
            reps: 3,
            dispatches: 50,
            transfer_bytes: 32 << 20,
            fma_iterations: 512,
            fma_groups: 256,
            triad_len: 4 << 20,
            gemm_size: 512,
        }
    }
}

/// One line of the table.
#[derive(Clone, Debug)]
pub struct BenchRow {
    /// What was measured.
    pub name: String,
    /// Problem size, in words.
    pub size: String,
    /// The GPU figure.
    pub gpu: f64,
    /// The CPU peer's figure.
    pub cpu: f64,
    /// Unit of both figures.
    pub unit: &'static str,
    /// What the CPU peer is.
    pub peer: &'static str,
    /// True if smaller is better (times); false for rates.
    pub lower_is_better: bool,
    /// A correctness note (e.g. the largest error against the peer).
    pub check: String,
}

impl BenchRow {
    /// How many times faster the GPU is than the CPU peer (< 1: slower).
    pub fn speedup(&self) -> f64 {
        if self.lower_is_better {
            self.cpu / self.gpu
        } else {
            self.gpu / self.cpu
        }
    }
}

/// Median of durations (the middle one; the upper middle for even counts).
pub fn median(times: &mut [Duration]) -> Duration {
    if times.is_empty() {
        return Duration::ZERO;
    }
    times.sort();
    times[times.len() / 2]
}

/// Median of values (the upper middle for even counts; NaN for none).
pub fn median_f64(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn time<R>(f: impl FnOnce() -> R) -> (Duration, R) {
    let t = Instant::now();
    let r = f();
    (t.elapsed(), r)
}

/// Runs every ceiling benchmark; `progress` is told each step's name as it starts.
pub fn run(gpu: &Gpu, config: &BenchConfig, mut progress: impl FnMut(&str)) -> GpuResult<Vec<BenchRow>> {
    let mut rows = Vec::new();
    let reps = config.reps.max(1);

    progress("dispatch overhead");
    let empty = EmptyKernel::new(gpu)?;
    gpu.run(|rec| empty.record(rec))?; // warm-up
    let mut t = Vec::with_capacity(config.dispatches);
    for _ in 0..config.dispatches {
        let (dt, r) = time(|| gpu.run(|rec| empty.record(rec)));
        r?;
        t.push(dt);
    }
    let gpu_us = median(&mut t).as_secs_f64() * 1e6;
    let cpu_us = cpu::thread_round_trip(config.dispatches).as_secs_f64() * 1e6;
    rows.push(BenchRow {
        name: "dispatch overhead".into(),
        size: "1 empty dispatch, submit + wait".into(),
        gpu: gpu_us,
        cpu: cpu_us,
        unit: "µs",
        peer: "thread round trip",
        lower_is_better: true,
        check: String::new(),
    });

    progress("upload / download");
    let n = (config.transfer_bytes / 4) as usize;
    let host: Vec<f32> = (0..n).map(|i| i as f32).collect();
    let dev = Buffer::<f32>::new(
        gpu,
        "bench transfer",
        n as u64,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryKind::GpuOnly,
    )?;
    let (mut up, mut down, mut copy) = (Vec::new(), Vec::new(), Vec::new());
    let mut back = vec![0f32; n];
    let mut sink = vec![0f32; n];
    for _ in 0..reps {
        let (dt, r) = time(|| dev.upload(gpu, 0, &host));
        r?;
        up.push(dt);
        let (dt, r) = time(|| dev.download_into(gpu, 0, &mut back));
        r?;
        down.push(dt);
        let (dt, ()) = time(|| sink.copy_from_slice(&host));
        copy.push(dt);
    }
    std::hint::black_box(&sink);
    let gb = config.transfer_bytes as f64 / 1e9;
    let memcpy = gb / median(&mut copy).as_secs_f64();
    let ok = if back == host { "round trip exact".to_string() } else { "ROUND TRIP MISMATCH".to_string() };
    for (name, times) in [("upload (staged)", &mut up), ("download (staged, into a reused Vec)", &mut down)] {
        rows.push(BenchRow {
            name: name.into(),
            size: format!("{} MiB", config.transfer_bytes >> 20),
            gpu: gb / median(times).as_secs_f64(),
            cpu: memcpy,
            unit: "GB/s",
            peer: "memcpy",
            lower_is_better: false,
            check: ok.clone(),
        });
    }
    drop(dev);

    let mut profiler = Profiler::new(gpu, 1)?;

    progress("FMA peak");
    let fma = FmaKernel::new(gpu, config.fma_groups)?;
    let (a, b) = (0.999_9f32, 1e-4f32);
    let mut g = Vec::new();
    for _ in 0..reps {
        gpu.run(|rec| {
            profiler.record_reset(rec);
            profiler.scope(rec, "fma", |rec| fma.record(rec, config.fma_iterations, a, b));
        })?;
        g.push(fma.flops(config.fma_iterations) / (profiler.results()?[0].1 * 1e-3) / 1e9);
    }
    let sink0 = fma.sink.download_range(gpu, crate::gpu::Chunk { first: 0, len: 1 })?[0];
    let want = FmaKernel::reference(0, config.fma_iterations, a, b);
    let mut c = Vec::new();
    let cpu_iterations = u64::from(config.fma_iterations) * 4096;
    for _ in 0..reps {
        let (dt, (flops, checksum)) = time(|| cpu::fma_peak(cpu_iterations, a, b));
        std::hint::black_box(checksum);
        c.push(flops / dt.as_secs_f64() / 1e9);
    }
    rows.push(BenchRow {
        name: "FMA peak".into(),
        size: format!("{} invocations × 8 chains × {}", config.fma_groups * 256, config.fma_iterations),
        gpu: median_f64(&mut g),
        cpu: median_f64(&mut c),
        unit: "GFLOP/s",
        peer: match cpu::simd() {
            cpu::Simd::Avx512 => "AVX-512 FMA chains, all cores",
            cpu::Simd::Avx2Fma => "AVX2 FMA chains, all cores",
            cpu::Simd::Portable => "plain FMA-shaped loop, all cores",
        },
        lower_is_better: false,
        check: format!("rel. err {:.1e}", ((f64::from(sink0) - want) / want).abs()),
    });
    drop(fma);

    progress("streaming triad");
    let len = config.triad_len & !3;
    let bh = vec![1.0f32; len as usize];
    let ch: Vec<f32> = (0..len).map(|i| (i % 97) as f32).collect();
    let ab =
        Buffer::<f32>::new(gpu, "triad a", len, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)?;
    let bb = Buffer::from_slice(gpu, "triad b", &bh, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let cb = Buffer::from_slice(gpu, "triad c", &ch, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let triad = TriadKernel::new(gpu, &ab, &bb, &cb)?;
    let s = 0.5f32;
    let mut g = Vec::new();
    for _ in 0..reps {
        gpu.run(|rec| {
            profiler.record_reset(rec);
            profiler.scope(rec, "triad", |rec| triad.record(gpu, rec, s));
        })?;
        g.push(triad.bytes() / (profiler.results()?[0].1 * 1e-3) / 1e9);
    }
    let got = ab.download(gpu)?;
    let mut ah = vec![0f32; len as usize];
    let mut c = Vec::new();
    for _ in 0..reps {
        let (dt, ()) = time(|| cpu::triad(&mut ah, &bh, &ch, s));
        c.push(triad.bytes() / dt.as_secs_f64() / 1e9);
    }
    let exact = got == ah;
    rows.push(BenchRow {
        name: "streaming triad".into(),
        size: format!("3 × {} MiB", (len * 4) >> 20),
        gpu: median_f64(&mut g),
        cpu: median_f64(&mut c),
        unit: "GB/s",
        peer: "plain Rust loop, all cores",
        lower_is_better: false,
        check: if exact { "equal to CPU".into() } else { "DIFFERS FROM CPU".into() },
    });
    drop((triad, ab, bb, cb));

    progress("tiled SGEMM");
    let nn = config.gemm_size;
    let (gpu_rate, got, ah, bh) = sgemm_ceiling(gpu, nn, reps)?;
    let size = (nn as usize) * (nn as usize);
    let flops = 2.0 * f64::from(nn).powi(3);
    let mut ch = vec![0f32; size];
    let mut c = Vec::new();
    for _ in 0..reps {
        let (dt, ()) = time(|| cpu::gemm(&ah, &bh, &mut ch, nn as usize, nn as usize, nn as usize));
        c.push(flops / dt.as_secs_f64() / 1e9);
    }
    let scale = ch.iter().fold(0f32, |m, v| m.max(v.abs()));
    let err = got.iter().zip(&ch).fold(0f32, |m, (g, c)| m.max((g - c).abs())) / scale;
    rows.push(BenchRow {
        name: "tiled SGEMM".into(),
        size: format!("{nn}³"),
        gpu: gpu_rate,
        cpu: median_f64(&mut c),
        unit: "GFLOP/s",
        peer: "faer matmul, all cores",
        lower_is_better: false,
        check: format!("max err {err:.1e} of max |C|"),
    });
    Ok(rows)
}

/// The tiled SGEMM's kernel rate on `n³` (GFLOP/s, median of `reps`, timestamp queries), with
/// the product and its operands for checking.
#[allow(clippy::type_complexity)]
pub fn sgemm_ceiling(gpu: &Gpu, n: u32, reps: usize) -> GpuResult<(f64, Vec<f32>, Vec<f32>, Vec<f32>)> {
    let size = (n as usize) * (n as usize);
    let ah: Vec<f32> = (0..size).map(|i| ((i * 7919) % 1000) as f32 / 1000.0 - 0.5).collect();
    let bh: Vec<f32> = (0..size).map(|i| ((i * 104_729) % 1000) as f32 / 1000.0 - 0.5).collect();
    let ad = Buffer::from_slice(gpu, "sgemm A", &ah, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let bd = Buffer::from_slice(gpu, "sgemm B", &bh, vk::BufferUsageFlags::STORAGE_BUFFER)?;
    let cd = Buffer::<f32>::new(
        gpu,
        "sgemm C",
        size as u64,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        MemoryKind::GpuOnly,
    )?;
    let gemm = SgemmKernel::new(gpu, &ad, &bd, &cd, n, n, n)?;
    let mut profiler = Profiler::new(gpu, 1)?;
    let mut g = Vec::new();
    for _ in 0..reps.max(1) {
        gpu.run(|rec| {
            profiler.record_reset(rec);
            profiler.scope(rec, "sgemm", |rec| gemm.record(rec));
        })?;
        g.push(gemm.flops() / (profiler.results()?[0].1 * 1e-3) / 1e9);
    }
    Ok((median_f64(&mut g), cd.download(gpu)?, ah, bh))
}

/// The table as Markdown.
pub fn table(rows: &[BenchRow]) -> String {
    let mut s = String::from("| kernel | size | GPU | CPU peer | peer | GPU/CPU speed | check |\n|---|---|---:|---:|---|---:|---|\n");
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {:.3} {} | {:.3} {} | {} | {:.3}× | {} |\n",
            r.name,
            r.size,
            r.gpu,
            r.unit,
            r.cpu,
            r.unit,
            r.peer,
            r.speedup(),
            r.check
        ));
    }
    s
}
