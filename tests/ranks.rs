//! The precompute sharded over ranks (threads as ranks, 1–4 of them: uneven partitions) against
//! one rank: the sharded PCA (singular values, principal angles, orthonormality, also on an
//! ill-conditioned snapshot set), the sharded premultiplication (whole and streamed sparse
//! tensors), and the two trainings built on them — reduced radiosity and reduced fluids.
//!
//! Tolerances: sums split differently over ranks differ by rounding, about `ε` times the
//! sum of magnitudes; a Gram matrix's eigenvalues σ² then move by about `k ε σ_max²` (so σ² are
//! compared to 1e-12 of `σ_max²`: a σ of 1e-5 σ_max is only known to 1e-7 of itself by any
//! method of snapshots), eigenvectors by that over the spectral gap
//! (principal angles at 1e-10 for well-separated spectra), and reduced tensors, linear in the
//! bases, by the same relative amount: the fluid's to 1e-10 of each tensor's largest entry
//! (observed 2e-13 to 4e-13), the radiosity's to 1e-8 (observed 1.3e-9: its pair bases may
//! keep modes down to σ = 1e-5 σ_max, and the squared distances' basis `B_r`, which keeps every
//! mode above rounding by default, down to σ ≈ 1e-6 σ_max, whose directions rounding moves by
//! up to ε σ_max²/σ², and the reduced tensors carry them; with `B_r` truncated at 0.999 like the
//! others the same test measures 1e-10 to 2.5e-10).

mod common;

use std::ops::Range;
use std::path::Path;

use galerkin::fluid::reduced::{BasisSizes, ReducedFluidModel, TrainingSet};
use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::train::TrainOptions;
use galerkin::radiosity::train_stages::{train_and_save, WorkOptions};
use galerkin::reduce::{
    pca, pca_across, premultiply_streamed, Bases, Basis, BasisRows, Expr, FullTensor, Model,
    PremultiplyOptions, ReduceOptions, ReducedModel, SingleRank, SnapshotFn, TensorChunks, ThreadRanks,
    Truncation,
};
use galerkin::tensor::{SparseTensor, Tensor};

use common::models::{compare_models, max_relative, same_columns_up_to_sign};
use common::tunnel::tunnel_run;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// An orthonormal `n × m` matrix (Gram–Schmidt of random columns).
fn orthonormal(n: usize, m: usize, seed: u64) -> Tensor {
    let mut r = Lcg(seed);
    let cols = Tensor::from_vec(&[n, m], (0..n * m).map(|_| r.next()).collect()).unwrap();
    Basis::orthonormalize("random", &cols).unwrap().matrix().clone()
}

/// `U diag(σ) Vᵀ` (`n × k`), with random orthonormal `U` and `V`: snapshots of known SVD.
fn snapshots_with_spectrum(n: usize, sigma: &[f64], seed: u64) -> (Tensor, Tensor) {
    let k = sigma.len();
    let u = orthonormal(n, k, seed);
    let v = orthonormal(k, k, seed + 1);
    let mut s = vec![0.0; n * k];
    for i in 0..n {
        for j in 0..k {
            s[i * k + j] = (0..k).map(|c| u.data()[i * k + c] * sigma[c] * v.data()[j * k + c]).sum();
        }
    }
    (Tensor::from_vec(&[n, k], s).unwrap(), u)
}

fn rows_of(s: &Tensor) -> impl FnMut(Range<usize>) -> Tensor + '_ {
    let k = s.shape()[1];
    move |rows: Range<usize>| {
        Tensor::from_vec(&[rows.len(), k], s.data()[rows.start * k..rows.end * k].to_vec()).unwrap()
    }
}

/// `‖B₂ − B₁ B₁ᵀ B₂‖_F`: bounds the sine of the largest principal angle between the spans.
fn subspace_distance(b1: &Tensor, b2: &Tensor) -> f64 {
    let (n, m1, m2) = (b1.shape()[0], b1.shape()[1], b2.shape()[1]);
    let mut c = vec![0.0; m1 * m2];
    for i in 0..n {
        for a in 0..m1 {
            for b in 0..m2 {
                c[a * m2 + b] += b1.data()[i * m1 + a] * b2.data()[i * m2 + b];
            }
        }
    }
    let mut sum = 0.0;
    for i in 0..n {
        for b in 0..m2 {
            let p: f64 = (0..m1).map(|a| b1.data()[i * m1 + a] * c[a * m2 + b]).sum();
            sum += (b2.data()[i * m2 + b] - p).powi(2);
        }
    }
    sum.sqrt()
}

#[test]
fn sharded_pca_matches_one_rank_at_every_rank_count() {
    // 20,011 rows: uneven shares, several blocks of rows for one rank.
    let sigma: Vec<f64> = (0..30).map(|i| 0.8f64.powi(i)).collect();
    let (s, _) = snapshots_with_spectrum(20_011, &sigma, 7);
    for centred in [false, true] {
        let truncation = Truncation { energy: 0.9999, max_modes: 60, centred };
        let one =
            pca("x", &mut SnapshotFn { dim: 20_011, count: 30, rows: rows_of(&s) }, truncation).unwrap();
        for size in 1..=4 {
            let results = ThreadRanks::run(size, |ranks| {
                pca_across(
                    "x",
                    &mut SnapshotFn { dim: 20_011, count: 30, rows: rows_of(&s) },
                    truncation,
                    ranks,
                )
            });
            for r in results {
                let p = r.unwrap();
                let smax = one.singular_values[0];
                for (a, b) in p.singular_values.iter().zip(&one.singular_values) {
                    assert!((a * a - b * b).abs() <= 1e-12 * smax * smax, "{size} ranks: σ {a} vs {b}");
                }
                assert_eq!(p.basis.reduced_dim(), one.basis.reduced_dim(), "{size} ranks, centred {centred}");
                assert!(p.basis.orthonormality_error() < 1e-13, "{:e}", p.basis.orthonormality_error());
                let d = subspace_distance(one.basis.matrix(), p.basis.matrix());
                assert!(d < 1e-10, "{size} ranks, centred {centred}: principal angles up to {d:e}");
                same_columns_up_to_sign(p.basis.matrix(), one.basis.matrix(), 1e-10);
            }
        }
    }
}

#[test]
fn sharded_pca_of_ill_conditioned_snapshots_is_orthonormal_to_rounding() {
    // σ from 1 down to 1e-7.5: the Gram matrix's condition number is 1e15, at the end of f64.
    let sigma: Vec<f64> = (0..16).map(|i| 10f64.powf(-(i as f64) / 2.0)).collect();
    let (s, u) = snapshots_with_spectrum(9_001, &sigma, 11);
    let truncation = Truncation { energy: 1.0, max_modes: 16, centred: false };
    let results = ThreadRanks::run(3, |ranks| {
        pca_across("ill", &mut SnapshotFn { dim: 9_001, count: 16, rows: rows_of(&s) }, truncation, ranks)
    });
    for r in results {
        let p = r.unwrap();
        // CholeskyQR2: orthonormal to rounding whatever the conditioning of the columns S V Σ⁻¹.
        assert!(p.basis.orthonormality_error() < 1e-13, "{:e}", p.basis.orthonormality_error());
        // The Gram matrix resolves σ² to about k ε σ_max² (σ_max = 1 here).
        for (a, b) in p.singular_values.iter().zip(&sigma) {
            assert!((a * a - b * b).abs() < 1e-13, "σ {a} vs {b}");
        }
        // The well-resolved leading modes (σ ≥ 1e-3) span the true leading singular vectors.
        let lead = sigma.iter().filter(|&&x| x >= 1e-3).count();
        let take = |t: &Tensor, m: usize| {
            let (n, c) = (t.shape()[0], t.shape()[1]);
            Tensor::from_vec(
                &[n, m],
                (0..n).flat_map(|i| (0..m).map(move |j| (i, j))).map(|(i, j)| t.data()[i * c + j]).collect(),
            )
            .unwrap()
        };
        let d = subspace_distance(&take(p.basis.matrix(), lead), &take(&u, lead));
        assert!(d < 1e-8, "leading {lead} modes off the true span by {d:e}");
    }
}

/// A random sparse tensor of shape `[n, n, n]`, axes 1 and 2 symmetric.
fn random_sparse(n: usize, nnz: usize, seed: u64) -> SparseTensor {
    let mut r = Lcg(seed);
    let mut t = SparseTensor::new(&[n, n, n]).with_symmetric_axes(&[1, 2]).unwrap();
    for _ in 0..nnz {
        let mut idx = [0usize; 3];
        for i in &mut idx {
            *i = ((r.next() + 1.0) / 2.0 * n as f64) as usize % n;
        }
        let (a, b) = (idx[1].min(idx[2]), idx[1].max(idx[2]));
        t.push(&[idx[0], a, b], r.next());
    }
    t
}

/// A sparse tensor served in chunks of consecutive entries.
struct Chunked {
    whole: SparseTensor,
    chunk: usize,
}

impl TensorChunks for Chunked {
    fn shape(&self) -> Vec<usize> {
        self.whole.shape().to_vec()
    }
    fn chunks(&self) -> usize {
        self.whole.nnz().div_ceil(self.chunk)
    }
    fn chunk(&self, c: usize) -> SparseTensor {
        self.whole.entries(c * self.chunk..(c + 1) * self.chunk)
    }
}

#[test]
fn sharded_premultiplication_matches_one_rank() {
    let n = 300;
    let q = random_sparse(n, 20_000, 3);
    let b0 = Basis::new("a", orthonormal(n, 12, 21), 1e-12).unwrap();
    let b1 = Basis::new("b", orthonormal(n, 9, 22), 1e-12).unwrap();
    // Streamed: 20,000 entries in 37 chunks, shared unevenly.
    let chunked = Chunked { whole: q.clone(), chunk: 547 };
    let bases: [&dyn BasisRows; 3] = [&b0, &b1, &b1];
    let one = premultiply_streamed("q", &chunked, &bases, PremultiplyOptions::default()).unwrap();
    // Whole, through a model.
    let model =
        Model::new(Expr::tensor("q")).with_tensor("q", &["a", "b", "b"], FullTensor::Sparse(q.clone()));
    let mut bs = Bases::new();
    bs.insert("a".into(), b0.clone());
    bs.insert("b".into(), b1.clone());
    let whole_one = model.reduce(&bs).unwrap();
    let tensor_of = |m: &ReducedModel| m.tensor("q").unwrap().clone();
    assert!(max_relative(&tensor_of(&whole_one), &one) < 1e-12);
    for size in 1..=4 {
        for r in ThreadRanks::run(size, |ranks| {
            let options = PremultiplyOptions { ranks, ..PremultiplyOptions::default() };
            let streamed = premultiply_streamed("q", &chunked, &bases, options)?;
            let whole = model.reduce_with(&bs, &ReduceOptions { ranks, ..ReduceOptions::default() })?;
            Ok::<_, galerkin::reduce::ReduceError>((streamed, tensor_of(&whole)))
        }) {
            let (streamed, whole) = r.unwrap();
            let (e1, e2) = (max_relative(&streamed, &one), max_relative(&whole, &one));
            assert!(e1 < 1e-12 && e2 < 1e-12, "{size} ranks: {e1:e}, {e2:e}");
        }
    }
}

#[test]
fn radiosity_training_over_ranks_matches_one_rank() {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let scene = AnyScene::load(&scene_path, None).unwrap();
    let options = TrainOptions { samples: 10, ..TrainOptions::default() };
    let dir = tempfile::tempdir().unwrap();
    let one = train_and_save(
        scene.space(),
        &options,
        &dir.path().join("one"),
        None,
        &WorkOptions::default(),
        &|_, _, _| {},
        &mut |_| {},
        &SingleRank,
    )
    .unwrap();
    for size in [2, 3] {
        let out = dir.path().join(format!("ranks-{size}"));
        let results = ThreadRanks::run(size, |ranks| {
            train_and_save(
                scene.space(),
                &options,
                &out,
                None,
                &WorkOptions::default(),
                &|_, _, _| {},
                &mut |_| {},
                ranks,
            )
        });
        for (rank, r) in results.into_iter().enumerate() {
            let t = r.unwrap();
            assert_eq!(t.configurations, 10);
            let worst = compare_models(t.model.model(), one.model.model()).worst;
            eprintln!("radiosity, {size} ranks, rank {rank}: reduced tensors within {worst:.1e}");
            assert!(
                worst < RADIOSITY_TOLERANCE,
                "{size} ranks, rank {rank}: reduced tensors differ by {worst:e}"
            );
            // Rank 0 alone writes the model.
            assert_eq!(t.bytes_on_disk > 0, rank == 0);
        }
        assert!(out.join("model.safetensors").is_file());
    }
}

/// How far the radiosity model trained over ranks may differ from one rank's (see the header).
const RADIOSITY_TOLERANCE: f64 = 1e-8;

#[test]
fn fluid_training_over_ranks_matches_one_rank() {
    let dir = tempfile::tempdir().unwrap();
    let runs = vec![tunnel_run(dir.path(), 0.6, 20), tunnel_run(dir.path(), 1.4, 20)];
    let set = TrainingSet::open(&runs).unwrap();
    let sizes = BasisSizes::default();
    let one = ReducedFluidModel::fit(&set, &sizes, &mut |_| {}).unwrap();
    for size in [2, 4] {
        for r in
            ThreadRanks::run(size, |ranks| ReducedFluidModel::fit_across(&set, &sizes, &mut |_| {}, ranks))
        {
            let model = r.unwrap();
            let a = compare_models(&model.core, &one.core);
            eprintln!("fluid, {size} ranks: reduced tensors within {a:?}");
            assert!(a.worst < 1e-10 && a.constraint < 1e-6, "{size} ranks: reduced tensors differ by {a:?}");
        }
    }
}

#[test]
fn a_scene_trains_over_ranks_each_simulating_its_runs() {
    use galerkin::fluid::reduced::{train_scene, train_scene_across, SceneTraining, TrainingEvent};
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/cavity_small.toml");
    let dir = tempfile::tempdir().unwrap();
    let options = SceneTraining {
        sizes: BasisSizes {
            energy: 0.9999,
            m_f: Some(8),
            m_u: Some(12),
            m_g: Some(4),
            m_h: Some(6),
            mid_step: false,
        },
        frames: Some(6),
        runs: Some(vec![0, 3]),
        work: dir.path().join("work"),
    };
    let over_ranks = |resuming: bool| {
        let results = ThreadRanks::run(2, |ranks| {
            let mut stages = Vec::new();
            let mut on_event = |e: TrainingEvent| {
                if let TrainingEvent::StageDone { stage, resumed, .. } = e {
                    stages.push((stage, resumed));
                }
            };
            let model = train_scene_across(
                &scene,
                &dir.path().join("ranks.safetensors"),
                &options,
                &mut on_event,
                ranks,
            )?;
            Ok::<_, galerkin::fluid::FluidError>((model, stages))
        });
        results
            .into_iter()
            .enumerate()
            .map(|(rank, r)| {
                let (model, stages) = r.unwrap();
                // Each rank simulated (or, resuming, found) its own run only.
                let own = if rank == 0 { "run 0" } else { "run 3" };
                let runs: Vec<&(String, bool)> =
                    stages.iter().filter(|(s, _)| s.starts_with("run ")).collect();
                assert_eq!(runs, [&(own.to_string(), resuming)], "rank {rank}: {stages:?}");
                model
            })
            .collect::<Vec<_>>()
    };
    let trained = over_ranks(false);
    // One rank on the same runs (read back from the work directory, not simulated again): the
    // bases and tensors again, from the same snapshots.
    std::fs::remove_file(dir.path().join("work/bases.safetensors")).unwrap();
    let one = train_scene(&scene, &dir.path().join("one.safetensors"), &options, &mut |_| {}).unwrap();
    for model in &trained {
        let a = compare_models(&model.core, &one.core);
        eprintln!("cavity scene, 2 ranks: reduced tensors within {a:?}");
        assert!(a.worst < 1e-10 && a.constraint < 1e-6, "reduced tensors differ by {a:?}");
    }
    let saved = ReducedFluidModel::load(&dir.path().join("ranks.safetensors")).unwrap();
    let a = compare_models(&saved.core, &one.core);
    assert!(a.worst < 1e-10 && a.constraint < 1e-6, "{a:?}");
    // Resumed over ranks: every run is found in the work directory.
    over_ranks(true);
}
