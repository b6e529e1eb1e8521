//! Reduced evaluation and lifting on the device (lavapipe, validation on) against the CPU f64
//! evaluator, in one binding and split across many (forced small bindings).

mod common;

use std::collections::BTreeMap;

use galerkin::bench::reduce::velocity_from_momentum_model;
use galerkin::gpu::Gpu;
use galerkin::reduce::synthetic::{volume_tensor, TetGrid};
use galerkin::reduce::{Backend, Bases, Basis, GpuReducedModel, ReducedModel};
use galerkin::tensor::Tensor;

fn random(n: usize, seed: u64) -> Vec<f64> {
    common::random_f32(n, seed).into_iter().map(f64::from).collect()
}

fn volume_model() -> (ReducedModel, Vec<f64>) {
    let grid = TetGrid::with_cells(60);
    let model = velocity_from_momentum_model(volume_tensor(&grid));
    let coords = grid.coordinates();
    let mut gcols = random(coords.len() * 4, 1);
    for (i, &c) in coords.iter().enumerate() {
        gcols[4 * i] = c;
    }
    let mut bases = Bases::new();
    bases.insert(
        "g".into(),
        Basis::orthonormalize("g", &Tensor::from_vec(&[coords.len(), 4], gcols).unwrap()).unwrap(),
    );
    bases.insert(
        "u".into(),
        Basis::orthonormalize("u", &Tensor::from_vec(&[180, 12], random(180 * 12, 2)).unwrap()).unwrap(),
    );
    let reduced = model.reduce(&bases).unwrap();
    let ghat = reduced.project_input("g", &coords).unwrap();
    (reduced, ghat)
}

fn check(gpu: &Gpu) {
    let (reduced, ghat) = volume_model();
    // Deformed geometries around the rest pose, one momentum each.
    let batch = 37;
    let gs: Vec<Vec<f64>> = (0..batch)
        .map(|b| ghat.iter().zip(random(ghat.len(), 10 + b)).map(|(g, r)| g + 0.05 * r).collect())
        .collect();
    let ps: Vec<Vec<f64>> = (0..batch).map(|b| random(12, 100 + b)).collect();
    let sets: Vec<BTreeMap<&str, &[f64]>> =
        gs.iter().zip(&ps).map(|(g, p)| [("g", &g[..]), ("p", &p[..])].into_iter().collect()).collect();
    let cpu = reduced.evaluate_batch(&sets).unwrap();
    let device = GpuReducedModel::new(gpu, reduced.clone()).unwrap();
    let got = device.evaluate_batch(&sets).unwrap();
    for (b, (c, g)) in cpu.iter().zip(&got).enumerate() {
        // f32 GEMM over K = 4³ products of O(1) terms: relative error ~K·2⁻²⁴ ≈ 4e-6 in the
        // reduced volume matrix, whose condition number here is ≈ 1 (≈ I/6): 1e-4 is 25× that.
        let scale = c.max_abs();
        assert!(c.max_abs_diff(g) <= 1e-4 * scale, "input set {b}: {} vs scale {scale}", c.max_abs_diff(g));
    }
    // Lifting: y = B_u û for the whole batch.
    let uhat: Vec<Vec<f64>> = cpu.iter().map(|t| t.data().to_vec()).collect();
    let lifted = device.lift_batch(&uhat).unwrap();
    for (u, y) in uhat.iter().zip(&lifted) {
        let want = reduced.lift(u).unwrap();
        let scale = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = want.iter().zip(y).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // 12-term f32 dot products.
        assert!(err <= 1e-5 * scale, "lift error {err} of {scale}");
    }
}

#[test]
fn gpu_batched_evaluation_matches_the_cpu() {
    let gpu = common::gpu();
    check(&gpu);
}

#[test]
fn gpu_evaluation_split_across_small_bindings_matches_the_cpu() {
    // 4 KiB bindings: V̂'s 12·12 × 4³ layout splits into column blocks, the batch into
    // row chunks, the basis into row blocks.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(4096));
    check(&gpu);
}

#[test]
fn auto_picks_the_cpu_on_a_cpu_rasteriser() {
    let gpu = common::gpu();
    assert_eq!(Backend::Auto.uses_gpu(Some(&gpu)), !gpu.caps().is_cpu());
    assert!(!Backend::Auto.uses_gpu(None));
    assert!(Backend::Gpu.uses_gpu(Some(&gpu)));
    assert!(!Backend::Cpu.uses_gpu(Some(&gpu)));
}
