//! The GPU backend of premultiplication (lavapipe, validation on) against a plain dense f64
//! reference, for random sparse tensors of orders 2–5 and a symmetric V-like tensor, in one
//! binding and split across many.

mod common;

use galerkin::gpu::Gpu;
use galerkin::reduce::{premultiply_sparse_gpu, Basis, PremultiplyOptions, Unit};
use galerkin::tensor::{SparseTensor, Tensor};

fn random_vec(n: usize, seed: u64) -> Vec<f64> {
    common::random_f32(n, seed).into_iter().map(f64::from).collect()
}

fn random_basis(n: usize, m: usize, seed: u64) -> Tensor {
    let g = Tensor::from_vec(&[n, m], random_vec(n * m, seed)).unwrap();
    Basis::orthonormalize("b", &g).unwrap().matrix().clone()
}

fn abs(t: &Tensor) -> Tensor {
    Tensor::from_vec(t.shape(), t.data().iter().map(|v| v.abs()).collect()).unwrap()
}

/// Checks GPU against f64 with the f32 summation bound: every output is a sum of at most
/// `terms` products (one per stored permutation of a nonzero), and a sum of N f32 terms is
/// within N·2⁻²⁴·Σ|terms| of the exact sum; Σ|terms| is the reference computed on |Q|, |B|.
fn check(gpu: &Gpu, q: &SparseTensor, bases: &[&Tensor], terms: usize) -> Vec<Vec<Unit>> {
    let (got, plan) = premultiply_sparse_gpu(gpu, q, bases, PremultiplyOptions::default()).unwrap();
    let dense = q.to_dense();
    let want = common::dense_reference(&dense, bases);
    let abs_bases: Vec<Tensor> = bases.iter().map(|b| abs(b)).collect();
    let scale = common::dense_reference(&abs(&dense), &abs_bases.iter().collect::<Vec<_>>());
    let eps = 2f64.powi(-24) * terms as f64;
    for i in 0..want.len() {
        let (g, w, s) = (got.data()[i], want.data()[i], scale.data()[i]);
        assert!((g - w).abs() <= eps * s + 1e-30, "entry {i}: gpu {g} vs {w} (bound {})", eps * s);
    }
    plan.stages
}

fn random_tensors() -> Vec<(SparseTensor, Vec<Tensor>)> {
    (2..=5usize)
        .map(|order| {
            let q = common::random_sparse(order, 300);
            let shape = q.shape().to_vec();
            let reduced: Vec<usize> = (0..order).map(|a| 2 + a % 3).collect();
            let bases = (0..order).map(|a| random_basis(shape[a], reduced[a], 100 + a as u64)).collect();
            (q, bases)
        })
        .collect()
}

fn v_like() -> (SparseTensor, Vec<Tensor>) {
    let (np, ng) = (12, 9);
    let mut q = SparseTensor::new(&[np, np, ng, ng, ng]).with_symmetric_axes(&[2, 3, 4]).unwrap();
    for (e, &v) in random_vec(600, 77).iter().enumerate() {
        let cell = e % 4;
        let p = 3 * cell + e % 3;
        let g = |k: usize| (2 * cell + (e / (3 + k)) % 3) % ng;
        q.push(&[p, p, g(0), g(1), g(2)], v);
    }
    let (bp, bg) = (random_basis(np, 5, 78), random_basis(ng, 4, 79));
    (q, vec![bp.clone(), bp, bg.clone(), bg.clone(), bg])
}

#[test]
fn gpu_premultiplication_matches_the_dense_reference() {
    let gpu = common::gpu();
    for (q, bases) in random_tensors() {
        check(&gpu, &q, &bases.iter().collect::<Vec<_>>(), q.nnz());
    }
    let (q, bases) = v_like();
    let stages = check(&gpu, &q, &bases.iter().collect::<Vec<_>>(), 6 * q.nnz());
    assert!(stages.iter().flatten().any(|u| *u == Unit::Group(vec![2, 3, 4])));
}

#[test]
fn gpu_premultiplication_split_across_small_bindings_matches() {
    // 4 KiB bindings (1024 floats): stages run in many batches, the final GEMM in many chunks.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(4096));
    for (q, bases) in random_tensors().into_iter().take(3) {
        check(&gpu, &q, &bases.iter().collect::<Vec<_>>(), q.nnz());
    }
    let (q, bases) = v_like();
    check(&gpu, &q, &bases.iter().collect::<Vec<_>>(), 6 * q.nnz());
    // A tensor whose data exceed one binding: 3000 nonzeros = 12 KB of f32 against 4 KiB.
    let shape = [8, 10, 12];
    let mut q = SparseTensor::new(&shape);
    for (e, p) in random_vec(3000, 31).iter().enumerate() {
        q.push(&[e % 8, (e / 8) % 10, (e * 7) % 12], *p);
    }
    let bases: Vec<Tensor> =
        shape.iter().enumerate().map(|(a, &n)| random_basis(n, 2 + a, 40 + a as u64)).collect();
    check(&gpu, &q, &bases.iter().collect::<Vec<_>>(), q.nnz());
}

#[test]
fn too_large_for_one_binding_is_a_clear_error() {
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(256));
    let (q, bases) = v_like();
    let err =
        premultiply_sparse_gpu(&gpu, &q, &bases.iter().collect::<Vec<_>>(), PremultiplyOptions::default())
            .unwrap_err();
    assert!(err.to_string().contains("CPU backend"), "{err}");
}

#[test]
fn a_model_reduces_on_either_backend_and_auto_picks_the_cpu_here() {
    use galerkin::bench::reduce::velocity_from_momentum_model;
    use galerkin::reduce::synthetic::{volume_tensor, TetGrid};
    use galerkin::reduce::{Backend, Bases, ReduceOptions};
    let gpu = common::gpu();
    let grid = TetGrid::with_cells(24);
    let model = velocity_from_momentum_model(volume_tensor(&grid));
    let n_g = grid.vertices.len() * 3;
    let mut bases = Bases::new();
    bases.insert("g".into(), Basis::new("g", random_basis(n_g, 4, 1), 1e-12).unwrap());
    bases.insert("u".into(), Basis::new("u", random_basis(72, 6, 2), 1e-12).unwrap());
    let cpu = model.reduce(&bases).unwrap();
    let on_gpu = model
        .reduce_with(
            &bases,
            &ReduceOptions {
                backend: Backend::Gpu,
                gpu: Some(&gpu),
                progress: None,
                ..ReduceOptions::default()
            },
        )
        .unwrap();
    let (a, b) = (cpu.tensor("V").unwrap(), on_gpu.tensor("V").unwrap());
    // 24 monomials × 3 components per cell, 6 permutations each: f32 sums of a few hundred
    // terms of size ≤ 1 (orthonormal bases, coefficients 1/36).
    assert!(a.max_abs_diff(b) <= 1e-5 * a.max_abs(), "{}", a.max_abs_diff(b));
    let auto = model
        .reduce_with(
            &bases,
            &ReduceOptions {
                backend: Backend::Auto,
                gpu: Some(&gpu),
                progress: None,
                ..ReduceOptions::default()
            },
        )
        .unwrap();
    if gpu.caps().is_cpu() {
        assert_eq!(auto.tensor("V").unwrap(), a, "auto takes the CPU backend on a CPU rasteriser");
    }
}

#[test]
fn a_final_stage_of_three_or_more_units_matches() {
    // Few nonzeros with distinct coordinates: the planner contracts every unit in one final
    // stage, so the inner units go through unit stages per chunk before the fused GEMM.
    let shape = [7, 9, 11, 13];
    let mut q = SparseTensor::new(&shape);
    for (e, p) in random_vec(6, 5).iter().enumerate() {
        q.push(&[e % 7, (2 * e + 1) % 9, (3 * e + 2) % 11, (5 * e + 3) % 13], *p);
    }
    let bases: Vec<Tensor> =
        shape.iter().enumerate().map(|(a, &n)| random_basis(n, 2, 60 + a as u64)).collect();
    let refs: Vec<&Tensor> = bases.iter().collect();
    for gpu in [common::gpu(), common::gpu_with(|d| d.max_binding_bytes = Some(256))] {
        let stages = check(&gpu, &q, &refs, q.nnz());
        assert!(stages.last().is_some_and(|s| s.len() >= 3), "plan {stages:?}");
    }
}
