//! Jobs that need several submissions run through a host's own `Submitter` (its command
//! buffers, fences and queue, `common::host::HostSubmitter`) exactly as through the engine's:
//! the batched solve, the streamed premultiplication, the reduced evaluation and lifting, and
//! the PCA Gram matrix give bit-identical results both ways (same kernels, same data, same
//! order of operations on one device; each is tested against the CPU f64 reference in its own
//! test file). Small bindings force many batches, so every job crosses many submissions, each
//! holding its staging buffers alive until the host's fence (validation reports any object
//! destroyed while in use). What orders the steps is the full barrier `Submitter::submit`
//! records first in each: lavapipe runs submissions in order anyway, and the validation
//! layer here (1.3.239) does not follow hazards across submissions, so these tests cannot see
//! a missing one (checked by removing it: they still pass) — it is recorded unconditionally.
//! A readback cannot be read before its work completed.

mod common;

use std::collections::BTreeMap;

use common::host::HostSubmitter;
use galerkin::gpu::{vk, Buffer, GpuError, MemoryKind, Submitter};
use galerkin::reduce::synthetic::{volume_tensor, TetGrid};
use galerkin::reduce::{
    pca_on, pca_with, premultiply_sparse_gpu, premultiply_sparse_on, Backend, Bases, Basis, GpuReducedModel,
    PremultiplyOptions, Truncation,
};
use galerkin::tensor::gpu::BatchedSolve;
use galerkin::tensor::Tensor;

fn random(n: usize, seed: u64) -> Vec<f64> {
    common::random_f32(n, seed).into_iter().map(f64::from).collect()
}

fn random_basis(n: usize, m: usize, seed: u64) -> Tensor {
    Basis::orthonormalize("b", &Tensor::from_vec(&[n, m], random(n * m, seed)).unwrap())
        .unwrap()
        .matrix()
        .clone()
}

#[test]
fn a_readback_is_refused_until_its_work_completed() {
    let gpu = common::gpu();
    let b = Buffer::<u32>::new(&gpu, "source", 64, vk::BufferUsageFlags::STORAGE_BUFFER, MemoryKind::GpuOnly)
        .unwrap();
    let mut host = HostSubmitter::new(&gpu);
    let sub: &mut dyn Submitter = &mut host;
    sub.upload(&b, 0, &(0..64).collect::<Vec<u32>>()).unwrap();
    let readback = sub.record_readback(&b, 8, 16).unwrap();
    assert!(matches!(readback.read(), Err(GpuError::NotMappable { .. })), "read while pending");
    sub.complete().unwrap();
    assert_eq!(readback.read().unwrap(), (8..24).collect::<Vec<u32>>());
    assert_eq!(host.submissions, 2);
}

#[test]
fn batched_solves_through_a_host_submitter_equal_the_engines() {
    // 1 KiB bindings: 9 systems of 10 × 10 run in 5 chunks of at most 2.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(1024));
    let solver = BatchedSolve::new(&gpu).unwrap();
    let n = 10;
    let mats: Vec<Tensor> = (0..9)
        .map(|s| {
            let mut a = random(n * n, 40 + s);
            (0..n).for_each(|i| a[i * n + i] += 4.0);
            Tensor::from_vec(&[n, n], a).unwrap()
        })
        .collect();
    let rhs: Vec<Vec<f64>> = (0..9).map(|s| random(n, 60 + s)).collect();
    let (m, r): (Vec<&Tensor>, Vec<&[f64]>) = (mats.iter().collect(), rhs.iter().map(|v| &v[..]).collect());
    let engine = solver.solve(&gpu, "A", &m, &r).unwrap();
    let mut host = HostSubmitter::new(&gpu);
    let hosted = solver.solve_with(&mut host, "A", &m, &r).unwrap();
    // Per chunk: three uploads, the solve, two readbacks.
    assert_eq!(host.submissions, 5 * 6, "every chunk uploads, solves and reads back");
    for (e, h) in engine.iter().zip(&hosted) {
        assert_eq!(e.as_ref().unwrap(), h.as_ref().unwrap());
    }
}

#[test]
fn the_streamed_premultiplication_through_a_host_submitter_equals_the_engines() {
    // 4 KiB bindings: the stages run in many batches and the final GEMM in many chunks.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(4096));
    let q = common::random_sparse(4, 300);
    let bases: Vec<Tensor> =
        q.shape().iter().enumerate().map(|(a, &n)| random_basis(n, 2 + a % 3, 100 + a as u64)).collect();
    let refs: Vec<&Tensor> = bases.iter().collect();
    let (engine, _) = premultiply_sparse_gpu(&gpu, &q, &refs, PremultiplyOptions::default()).unwrap();
    let mut host = HostSubmitter::new(&gpu);
    let (hosted, _) = premultiply_sparse_on(&mut host, &q, &refs, PremultiplyOptions::default()).unwrap();
    assert!(host.submissions > 10, "many batches: {}", host.submissions);
    assert_eq!(engine.data(), hosted.data());
}

#[test]
fn reduced_evaluation_and_lifting_through_a_host_submitter_equal_the_engines() {
    // 4 KiB bindings: contractions in column blocks and row chunks, the basis in row blocks.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(4096));
    let grid = TetGrid::with_cells(60);
    let model = galerkin::bench::reduce::velocity_from_momentum_model(volume_tensor(&grid));
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
    bases.insert("u".into(), Basis::new("u", random_basis(180, 12, 2), 1e-12).unwrap());
    let reduced = model.reduce(&bases).unwrap();
    let ghat = reduced.project_input("g", &coords).unwrap();
    let gs: Vec<Vec<f64>> = (0..7)
        .map(|b| ghat.iter().zip(random(ghat.len(), 10 + b)).map(|(g, r)| g + 0.05 * r).collect())
        .collect();
    let ps: Vec<Vec<f64>> = (0..7).map(|b| random(12, 100 + b)).collect();
    let sets: Vec<BTreeMap<&str, &[f64]>> =
        gs.iter().zip(&ps).map(|(g, p)| [("g", &g[..]), ("p", &p[..])].into_iter().collect()).collect();
    let engine_model = GpuReducedModel::new(&gpu, reduced.clone()).unwrap();
    let engine = engine_model.evaluate_batch(&sets).unwrap();
    let host_model = GpuReducedModel::new(&gpu, reduced).unwrap();
    let mut host = HostSubmitter::new(&gpu);
    let hosted = host_model.evaluate_batch_with(&mut host, &sets).unwrap();
    for (e, h) in engine.iter().zip(&hosted) {
        assert_eq!(e.data(), h.data());
    }
    let uhat: Vec<Vec<f64>> = engine.iter().map(|t| t.data().to_vec()).collect();
    assert_eq!(
        engine_model.lift_batch(&uhat).unwrap(),
        host_model.lift_batch_with(&mut host, &uhat).unwrap()
    );
    assert!(host.submissions > 10, "{}", host.submissions);
}

#[test]
fn the_pca_gram_matrix_through_a_host_submitter_equals_the_engines() {
    let gpu = common::gpu();
    // 9,000 rows: three 4,096-row blocks, each uploaded and accumulated in its own steps.
    let (n, k) = (9_000, 6);
    let s = Tensor::from_vec(&[n, k], random(n * k, 5)).unwrap();
    let truncation = Truncation { energy: 1.0, max_modes: k, centred: false };
    let engine = pca_with("s", &mut &s, truncation, Backend::Gpu, Some(&gpu)).unwrap();
    let mut host = HostSubmitter::new(&gpu);
    let hosted = pca_on("s", &mut &s, truncation, &mut host).unwrap();
    assert_eq!(engine.singular_values, hosted.singular_values);
    assert_eq!(engine.basis.matrix().data(), hosted.basis.matrix().data());
    assert!(host.submissions >= 3 * 3, "{}", host.submissions);
}
