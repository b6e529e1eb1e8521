//! `galerkin bench reduce`: the reduction core against its targets (issue: premultiplication of
//! a V-like tensor at the paper's cavity size in under 60 s on 2 cores; reduced evaluation per
//! call and per batch; linear growth in cells).
//!
//! The tensor is the real fluid volume tensor of a Freudenthal tetrahedral grid
//! ([`crate::reduce::synthetic`]); bases are random (premultiplication cost does not depend on
//! their values) except where a reduced model is evaluated, which needs an invertible reduced
//! volume matrix: there the velocity basis is orthonormalised and the geometry basis spans the
//! grid's own coordinates.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

use crate::reduce::synthetic::{volume_tensor, TetGrid};
use crate::reduce::{premultiply_sparse_with, Bases, Basis, Expr, Model, PremultiplyOptions, ReduceError};
use crate::tensor::{SparseTensor, Tensor};

/// Deterministic pseudo-random values in [-0.5, 0.5) (xorshift; the benchmarks' inputs).
pub(crate) fn random(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect()
}

fn random_matrix(n: usize, m: usize, seed: u64) -> Tensor {
    Tensor::from_vec(&[n, m], random(n * m, seed)).expect("shape matches")
}

/// One premultiplication measurement.
#[derive(Clone, Debug)]
pub struct PremultiplyRun {
    /// Tetrahedra.
    pub cells: usize,
    /// Stored nonzeros of V.
    pub entries: usize,
    /// Reduced dimension of the result and velocity axes.
    pub m: usize,
    /// Reduced dimension of the geometry axes.
    pub m_g: usize,
    /// Wall time.
    pub time: Duration,
    /// Multiply–adds the plan performed.
    pub flops: f64,
}

impl PremultiplyRun {
    /// GFLOP/s (2 flops per multiply–add).
    pub fn gflops(&self) -> f64 {
        2.0 * self.flops / self.time.as_secs_f64() / 1e9
    }
}

/// Premultiplies the volume tensor of `cells` tetrahedra with random bases of `m` (result and
/// velocity axes) and `m_g` (geometry) columns, on the CPU backend, or on `gpu`'s GPU backend
/// when given; `progress` sees (done, total).
pub fn premultiply_volume(
    cells: usize,
    m: usize,
    m_g: usize,
    gpu: Option<&crate::gpu::Gpu>,
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
) -> Result<(PremultiplyRun, Tensor), ReduceError> {
    let grid = TetGrid::with_cells(cells);
    let v = volume_tensor(&grid);
    let bp = random_matrix(v.shape()[0], m, 1);
    let bg = random_matrix(v.shape()[2], m_g, 2);
    let bases = [&bp, &bp, &bg, &bg, &bg];
    let options = PremultiplyOptions { progress, ..PremultiplyOptions::default() };
    let t = Instant::now();
    let (out, plan) = match gpu {
        Some(g) => crate::reduce::premultiply_sparse_gpu(g, &v, &bases, options)?,
        None => premultiply_sparse_with(&v, &bases, options)
            .map_err(|cause| ReduceError::Tensor { context: "premultiplying V".into(), cause })?,
    };
    let run =
        PremultiplyRun { cells, entries: v.nnz(), m, m_g, time: t.elapsed(), flops: plan.total_flops() };
    Ok((run, out))
}

/// faer's plain f64 GEMM `C (m×n) = A (m×k) · B (k×n)` on every core: the peer of the
/// premultiplication's final stage, at that stage's shape. Returns GFLOP/s (median of `reps`).
pub fn faer_gemm_gflops(m: usize, k: usize, n: usize, reps: usize) -> f64 {
    let a = Mat::from_fn(m, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
    let b = Mat::from_fn(k, n, |i, j| ((i * 11 + j * 5) % 19) as f64 - 9.0);
    let mut c = Mat::<f64>::zeros(m, n);
    let mut rates: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let t = Instant::now();
            matmul(c.as_mut(), Accum::Replace, a.as_ref(), b.as_ref(), 1.0, Par::rayon(0));
            2.0 * (m * k * n) as f64 / t.elapsed().as_secs_f64() / 1e9
        })
        .collect();
    rates.sort_by(f64::total_cmp);
    rates[rates.len() / 2]
}

/// The reduced fluid step of the benchmark: `û = (V̂ ⊗₂ ĝ ⊗₃ ĝ ⊗₄ ĝ)⁻¹ ⊗₁ p̂` — velocity
/// from momentum on the reduced deforming mesh (the paper's `B_u = B_p`).
pub fn velocity_from_momentum_model(v: SparseTensor) -> Model {
    let g = Expr::input("g");
    let volume = Expr::tensor("V").times(2, g.clone()).times(3, g.clone()).times(4, g);
    Model::new(volume.inverse().times(1, Expr::input("p")))
        .with_tensor("V", &["u", "u", "g", "g", "g"], v)
        .with_input("g", "g")
        .with_input("p", "u")
}

/// Reduced evaluation timings, medians: per call and per batch, on the CPU path and (when a
/// device is given) on the GPU path.
#[derive(Clone, Debug)]
pub struct EvalTimings {
    /// CPU, one input set.
    pub cpu_single: Duration,
    /// CPU, the whole batch (every core).
    pub cpu_batch: Duration,
    /// GPU, one input set, and the whole batch.
    pub gpu: Option<(Duration, Duration)>,
    /// Largest difference between the GPU and CPU results over the batch, relative to the
    /// largest |û|.
    pub gpu_error: Option<f64>,
}

/// Times the reduced fluid step for `batch` input sets (velocity basis of `m`, geometry basis
/// of 5 spanning the grid's rest pose) on the CPU and, with `gpu`, on the device.
pub fn reduced_evaluation(
    cells: usize,
    m: usize,
    batch: usize,
    reps: usize,
    gpu: Option<&crate::gpu::Gpu>,
) -> Result<EvalTimings, ReduceError> {
    let grid = TetGrid::with_cells(cells);
    let v = volume_tensor(&grid);
    let model = velocity_from_momentum_model(v);
    let n_u = 3 * grid.cells.len();
    let coords = grid.coordinates();
    // Geometry basis: the rest pose plus 4 random deformation modes; velocity basis random.
    let modes = random(4 * coords.len(), 4);
    let gcols: Vec<f64> = coords
        .iter()
        .enumerate()
        .flat_map(|(i, &c)| std::iter::once(c).chain(modes[4 * i..4 * i + 4].iter().copied()))
        .collect();
    let bg = Basis::orthonormalize("g", &Tensor::from_vec(&[coords.len(), 5], gcols).expect("shape"))?;
    let bu = Basis::orthonormalize("u", &random_matrix(n_u, m, 3))?;
    let mut bases = Bases::new();
    bases.insert("g".into(), bg);
    bases.insert("u".into(), bu);
    let reduced = model.reduce(&bases)?;
    let ghat = reduced.project_input("g", &coords)?;
    let ps: Vec<Vec<f64>> = (0..batch).map(|k| random(m, 100 + k as u64)).collect();
    let sets: Vec<BTreeMap<&str, &[f64]>> =
        ps.iter().map(|p| [("g", &ghat[..]), ("p", &p[..])].into_iter().collect()).collect();
    let time = |f: &dyn Fn() -> Result<Vec<Tensor>, ReduceError>| -> Result<Duration, ReduceError> {
        let t = Instant::now();
        f()?;
        Ok(t.elapsed())
    };
    let (mut cs, mut cb, mut gs, mut gb) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let device = gpu.map(|g| crate::reduce::GpuReducedModel::new(g, reduced.clone())).transpose()?;
    let mut gpu_error = None;
    for _ in 0..reps.max(1) {
        cs.push(time(&|| reduced.evaluate_batch(&sets[..1]))?);
        cb.push(time(&|| reduced.evaluate_batch(&sets))?);
        if let Some(d) = &device {
            gs.push(time(&|| d.evaluate_batch(&sets[..1]))?);
            gb.push(time(&|| d.evaluate_batch(&sets))?);
        }
    }
    if let Some(d) = &device {
        let (c, g) = (reduced.evaluate_batch(&sets)?, d.evaluate_batch(&sets)?);
        let scale = c.iter().fold(0.0f64, |m, t| m.max(t.max_abs()));
        gpu_error = Some(c.iter().zip(&g).fold(0.0f64, |m, (a, b)| m.max(a.max_abs_diff(b))) / scale);
    }
    let med = crate::bench::median;
    Ok(EvalTimings {
        cpu_single: med(&mut cs),
        cpu_batch: med(&mut cb),
        gpu: device.as_ref().map(|_| (med(&mut gs), med(&mut gb))),
        gpu_error,
    })
}

/// The whole `galerkin bench reduce` report as Markdown, section by section through `emit`:
/// premultiplication at the paper's cavity size next to faer's GEMM of its final stage, the GPU
/// backend against the tiled-SGEMM ceiling (with `gpu`), reduced evaluation on both paths, and
/// premultiplication time against cells and `m`. `progress` follows the cavity-size run.
pub fn report(
    quick: bool,
    gpu: Option<&crate::gpu::Gpu>,
    progress: Option<&(dyn Fn(f64, f64) + Sync)>,
    emit: &mut dyn FnMut(&str),
) -> Result<(), ReduceError> {
    use std::fmt::Write as _;
    let mut out = String::new();
    let threads = crate::bench::cpu::threads();
    let _ = writeln!(out, "CPU backend: faer, {threads} threads. GPU backend: compute shaders (f32), measured below on the device.\n");

    let (cells, m, m_g) = (if quick { 10_000 } else { 88_671 }, 128, 5);
    let (run, _) = premultiply_volume(cells, m, m_g, None, progress)?;
    let peer = faer_gemm_gflops(m, 3 * cells, m * (m_g * (m_g + 1) * (m_g + 2) / 6), 3);
    let _ = writeln!(
        out,
        "## Premultiplication of the volume tensor V (cells {cells}, m_p = m_u = {m}, m_g = {m_g})\n"
    );
    let _ =
        writeln!(out, "| stored entries | time | GFLOP/s | faer GEMM of the final stage's shape | ratio |");
    let _ = writeln!(out, "|---:|---:|---:|---:|---:|");
    let _ = writeln!(
        out,
        "| {} | {:.2} s | {:.1} | {:.1} GFLOP/s ({m} × {} × {}) | {:.2} |\n",
        run.entries,
        run.time.as_secs_f64(),
        run.gflops(),
        peer,
        3 * cells,
        m * 35,
        run.gflops() / peer
    );
    emit(&std::mem::take(&mut out));

    if let Some(g) = gpu {
        let cells_gpu = if quick { 2_000 } else { 10_000 };
        let (cpu_run, cpu_out) = premultiply_volume(cells_gpu, m, m_g, None, None)?;
        // Interleaved with the ceiling, three times: these shared machines drift by 2× over
        // minutes, so each premultiplication is compared with the ceiling measured next to it.
        let mut pairs = Vec::new();
        let mut gpu_out = None;
        for _ in 0..3 {
            let (run, result) = premultiply_volume(cells_gpu, m, m_g, Some(g), None)?;
            let (ceiling, ..) = crate::bench::sgemm_ceiling(g, if quick { 512 } else { 1024 }, 3)
                .map_err(ReduceError::device("SGEMM ceiling"))?;
            pairs.push((run, ceiling));
            gpu_out = Some(result);
        }
        let gpu_out = gpu_out.expect("three runs");
        let median = |mut v: Vec<f64>| super::median_f64(&mut v);
        let gpu_seconds = median(pairs.iter().map(|(r, _)| r.time.as_secs_f64()).collect());
        let gpu_gflops = median(pairs.iter().map(|(r, _)| r.gflops()).collect());
        let ceiling = median(pairs.iter().map(|&(_, c)| c).collect());
        let ratio = median(pairs.iter().map(|(r, c)| r.gflops() / c).collect());
        let err = cpu_out.max_abs_diff(&gpu_out) / cpu_out.max_abs();
        let _ = writeln!(
            out,
            "## Premultiplication on the GPU backend ({}), {cells_gpu} cells, m = {m}, m_g = {m_g}\n",
            g.caps().device_name
        );
        let _ =
            writeln!(out, "| backend | time | GFLOP/s | tiled-SGEMM ceiling, measured after each run | median ratio to ceiling |");
        let _ = writeln!(out, "|---|---:|---:|---:|---:|");
        let _ = writeln!(
            out,
            "| CPU (faer, f64) | {:.2} s | {:.1} | | |",
            cpu_run.time.as_secs_f64(),
            cpu_run.gflops()
        );
        let _ = writeln!(
            out,
            "| GPU (f32), median of 3 | {gpu_seconds:.2} s | {gpu_gflops:.2} | {ceiling:.2} GFLOP/s | {ratio:.2} |\n"
        );
        let auto = if crate::reduce::Backend::Auto.uses_gpu(Some(g)) { "GPU" } else { "CPU" };
        let _ = writeln!(out, "GPU vs CPU result: largest difference {err:.1e} of max |V̂|; `auto` picks the {auto} backend here.\n");
        emit(&std::mem::take(&mut out));
    }
    let (batch, reps) = (1024, if quick { 3 } else { 5 });
    let t = reduced_evaluation(10_000, m, batch, reps, gpu)?;
    let _ = writeln!(
        out,
        "## Reduced evaluation û = (V̂ ⊗₂ ĝ ⊗₃ ĝ ⊗₄ ĝ)⁻¹ ⊗₁ p̂ (m = {m}, m_g = {m_g}), medians of {reps}\n"
    );
    let _ = writeln!(out, "| path | per call | per batch of {batch} | per input in the batch |");
    let _ = writeln!(out, "|---|---:|---:|---:|");
    let row = |name: &str, single: Duration, batched: Duration| {
        format!(
            "| {name} | {:.3} ms | {:.1} ms | {:.3} ms |\n",
            single.as_secs_f64() * 1e3,
            batched.as_secs_f64() * 1e3,
            batched.as_secs_f64() * 1e3 / batch as f64
        )
    };
    out.push_str(&row(&format!("CPU (faer, {threads} threads)"), t.cpu_single, t.cpu_batch));
    if let (Some((s, b)), Some(g)) = (t.gpu, gpu) {
        out.push_str(&row(
            &format!(
                "GPU ({}): contractions as one GEMM per batch, solves as one batched LU (f32)",
                g.caps().device_name
            ),
            s,
            b,
        ));
        let _ = writeln!(
            out,
            "\nGPU vs CPU results: largest difference {:.1e} of max |û| (f32 on the device).",
            t.gpu_error.unwrap_or(f64::NAN)
        );
        let auto = if crate::reduce::Backend::Auto.uses_gpu(Some(g)) { "GPU" } else { "CPU" };
        let _ = writeln!(out, "`auto` picks the {auto} on this device.");
    }
    out.push('\n');
    emit(&std::mem::take(&mut out));

    let cell_counts: &[usize] = if quick { &[1_000, 10_000] } else { &[1_000, 10_000, 100_000] };
    let ms: &[usize] = if quick { &[16, 64] } else { &[16, 32, 64, 128] };
    let _ = writeln!(out, "## Premultiplication time against cells and m (m_g = {m_g})\n");
    let _ = write!(out, "| cells |");
    for m in ms {
        let _ = write!(out, " m = {m} |");
    }
    out.push('\n');
    let _ = writeln!(out, "|---:|{}", "---:|".repeat(ms.len()));
    for &c in cell_counts {
        let _ = write!(out, "| {c} |");
        for &m in ms {
            let (run, _) = premultiply_volume(c, m, m_g, None, None)?;
            let _ = write!(out, " {:.3} s |", run.time.as_secs_f64());
        }
        out.push('\n');
    }
    emit(&out);
    Ok(())
}
