//! PCA bases by the method of snapshots: recovered subspaces of synthetic low-rank snapshots,
//! truncation by energy on σ² with a cap, streaming (file, generator) against an independent
//! thin SVD, orthonormality, and merged bases.

mod common;

use galerkin::reduce::{pca, Basis, SnapshotFile, SnapshotFn, Truncation};
use galerkin::tensor::{matmul, transpose, Tensor};

fn random_vec(n: usize, seed: u64) -> Vec<f64> {
    common::random_f32(n, seed).into_iter().map(f64::from).collect()
}

fn orthonormal(n: usize, m: usize, seed: u64) -> Tensor {
    let g = Tensor::from_vec(&[n, m], random_vec(n * m, seed)).unwrap();
    Basis::orthonormalize("u", &g).unwrap().matrix().clone()
}

/// Snapshots `S = U diag(σ) Vᵀ` with chosen singular values.
fn snapshots(n: usize, sigma: &[f64], seed: u64) -> (Tensor, Tensor) {
    let r = sigma.len();
    let k = r + 3;
    let u = orthonormal(n, r, seed);
    let v = orthonormal(k, r, seed + 1);
    let mut us = u.clone();
    for i in 0..n {
        for (j, s) in sigma.iter().enumerate() {
            let x = us.get(&[i, j]) * s;
            us.set(&[i, j], x);
        }
    }
    (matmul(&us, &transpose(&v)).unwrap(), u)
}

/// Largest distance of `u`'s columns from the span of `b`: max ‖uⱼ − B Bᵀ uⱼ‖.
fn distance_from_span(u: &Tensor, b: &Basis) -> f64 {
    let (n, m) = (u.shape()[0], u.shape()[1]);
    (0..m)
        .map(|j| {
            let col: Vec<f64> = (0..n).map(|i| u.get(&[i, j])).collect();
            let back = b.lift(&b.project(&col));
            col.iter().zip(&back).map(|(a, c)| (a - c).powi(2)).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max)
}

#[test]
fn pca_recovers_a_low_rank_subspace() {
    let (s, u) = snapshots(300, &[4.0, 3.0, 1.5, 0.5], 1);
    let p = pca("u", &mut &s, Truncation { energy: 1.0, max_modes: 100, centred: false }).unwrap();
    assert_eq!(p.basis.reduced_dim(), 4, "rank 4: the zero singular values are not kept");
    // Orthonormal to 1e-12: Gram–Schmidt twice leaves O(n·ε) ≈ 1e-13 here.
    assert!(p.basis.orthonormality_error() < 1e-12);
    assert!(distance_from_span(&u, &p.basis) < 1e-10);
    for (got, want) in p.singular_values.iter().zip([4.0, 3.0, 1.5, 0.5]) {
        assert!((got - want).abs() < 1e-10, "σ {got} vs {want}");
    }
    assert!((p.energy - 1.0).abs() < 1e-12);
}

#[test]
fn truncation_counts_energy_in_sigma_squared_and_respects_the_cap() {
    let sigma = [10.0, 5.0, 2.0, 1.0, 0.1];
    let (s, _) = snapshots(200, &sigma, 7);
    // Σσ² = 130.01: two modes hold 125/130.01 = 0.9615 ≥ 0.95 (in σ they would hold only 0.83).
    let p = pca("u", &mut &s, Truncation { energy: 0.95, max_modes: 10, centred: false }).unwrap();
    assert_eq!(p.basis.reduced_dim(), 2);
    assert!((p.energy - 125.0 / 130.01).abs() < 1e-12, "{}", p.energy);
    let capped = pca("u", &mut &s, Truncation { energy: 0.95, max_modes: 1, centred: false }).unwrap();
    assert_eq!(capped.basis.reduced_dim(), 1);
    assert!(pca("u", &mut &s, Truncation { energy: 0.0, max_modes: 1, centred: false }).is_err());
}

/// Centred PCA: snapshots that share a large common part (a mean holding almost all the raw
/// energy) keep their variation. Raw PCA at 99.9 % keeps just the mean direction; centred PCA
/// keeps the mean and the variation modes, and then reproduces every snapshot.
#[test]
fn centred_pca_keeps_the_variation_beside_a_dominant_mean() {
    let (variation, _) = snapshots(400, &[0.5, 0.2], 3);
    let (n, k) = (variation.shape()[0], variation.shape()[1]);
    let mut data = variation.data().to_vec();
    for i in 0..n {
        for j in 0..k {
            data[i * k + j] += 10.0 * (1.0 + (i as f64 * 0.01).sin());
        }
    }
    let s = galerkin::tensor::Tensor::from_vec(&[n, k], data).unwrap();
    let raw = pca("g", &mut &s, Truncation { energy: 0.999, max_modes: 60, centred: false }).unwrap();
    assert_eq!(raw.basis.reduced_dim(), 1, "the raw energy is all in the mean");
    let centred = pca("g", &mut &s, Truncation { energy: 0.999, max_modes: 60, centred: true }).unwrap();
    assert_eq!(centred.basis.reduced_dim(), 3, "the mean and two variation modes");
    assert!(centred.basis.orthonormality_error() < 1e-12);
    assert!(distance_from_span(&s, &centred.basis) < 1e-9 * 10.0 * (n as f64).sqrt());
    // Snapshots that do not vary at all: the mean alone.
    let same = galerkin::tensor::Tensor::from_vec(&[3, 2], vec![1.0, 1.0, 2.0, 2.0, 3.0, 3.0]).unwrap();
    let p = pca("e", &mut &same, Truncation { energy: 0.999, max_modes: 60, centred: true }).unwrap();
    assert_eq!(p.basis.reduced_dim(), 1);
}

#[test]
fn streaming_pca_matches_an_independent_thin_svd() {
    // n spans several 4096-row blocks; the reference is faer's thin SVD of the whole matrix.
    let (n, sigma) = (10_000, [6.0, 2.0, 1.0, 0.25, 0.125]);
    let (s, _) = snapshots(n, &sigma, 11);
    let k = s.shape()[1];
    let svd = faer::Mat::from_fn(n, k, |i, j| s.get(&[i, j])).thin_svd().unwrap();
    let reference = Tensor::from_vec(
        &[n, 5],
        (0..n).flat_map(|i| (0..5).map(move |j| (i, j))).map(|(i, j)| svd.U()[(i, j)]).collect(),
    )
    .unwrap();
    let truncation = Truncation { energy: 1.0, max_modes: 5, centred: false };

    // From a file, read in blocks.
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let path = dir.join("snapshots.f64");
    std::fs::write(&path, s.data().iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
    let from_file = pca("u", &mut SnapshotFile::open(&path, n, k).unwrap(), truncation).unwrap();
    // Regenerated by a callback, never all in memory at once.
    let mut calls = 0;
    let mut generator = SnapshotFn {
        dim: n,
        count: k,
        rows: |rows: std::ops::Range<usize>| {
            calls += 1;
            Tensor::from_vec(&[rows.len(), k], s.data()[rows.start * k..rows.end * k].to_vec()).unwrap()
        },
    };
    let from_fn = pca("u", &mut generator, truncation).unwrap();
    assert!(calls >= 2 * 3, "two passes over at least three blocks, got {calls} calls");
    for p in [&from_file, &from_fn] {
        assert_eq!(p.basis.reduced_dim(), 5);
        assert!(distance_from_span(&reference, &p.basis) < 1e-9);
        for (got, want) in p.singular_values.iter().zip(sigma) {
            assert!((got - want).abs() < 1e-10);
        }
    }
    std::fs::write(&path, [0u8; 16]).unwrap();
    let err = SnapshotFile::open(&path, n, k).err().unwrap().to_string();
    assert!(err.contains("snapshots.f64") && err.contains("16 bytes"), "{err}");
}

#[test]
fn merged_bases_span_both_and_stay_orthonormal() {
    let n = 40;
    let a = Basis::new("a", orthonormal(n, 3, 21), 1e-12).unwrap();
    let b = Basis::new("b", orthonormal(n, 4, 22), 1e-12).unwrap();
    let both = Basis::merge("ab", &a, &b).unwrap();
    assert_eq!(both.reduced_dim(), 7);
    assert!(both.orthonormality_error() < 1e-12);
    assert!(distance_from_span(a.matrix(), &both) < 1e-12);
    assert!(distance_from_span(b.matrix(), &both) < 1e-12);
    // Merging a basis with itself adds nothing.
    assert_eq!(Basis::merge("aa", &a, &a).unwrap().reduced_dim(), 3);
    // A non-orthonormal matrix is refused with the measured error.
    let skew = Tensor::from_vec(&[2, 2], vec![1.0, 0.5, 0.0, 1.0]).unwrap();
    assert!(Basis::new("skew", skew, 1e-12).unwrap_err().to_string().contains("not orthonormal"));
    // … and so is one holding a NaN (whose error is NaN, not the largest finite entry).
    let mut data = orthonormal(n, 3, 23).data().to_vec();
    data[7] = f64::NAN;
    let nan = Tensor::from_vec(&[n, 3], data).unwrap();
    assert!(Basis::new("nan", nan, 1e-12).unwrap_err().to_string().contains("NaN"));
}

#[test]
fn pca_with_the_gram_matrix_on_the_gpu_finds_the_same_subspace() {
    use galerkin::reduce::{pca_with, Backend};
    let gpu = common::gpu();
    // Rows span two 4096-row blocks; a well-separated spectrum, so f32 Gram entries resolve it.
    let (s, u) = snapshots(6000, &[5.0, 3.0, 2.0, 1.0], 31);
    let truncation = Truncation { energy: 0.999, max_modes: 10, centred: false };
    let cpu = pca("u", &mut &s, truncation).unwrap();
    let on_gpu = pca_with("u", &mut &s, truncation, Backend::Gpu, Some(&gpu)).unwrap();
    assert_eq!(on_gpu.basis.reduced_dim(), cpu.basis.reduced_dim());
    // f32 Gram: relative error ~1e-7 of σ₁² per entry, so subspaces agree to ~1e-6 here.
    assert!(distance_from_span(&u, &on_gpu.basis) < 1e-5);
    for (a, b) in on_gpu.singular_values.iter().zip(&cpu.singular_values).take(4) {
        assert!((a - b).abs() < 1e-5 * cpu.singular_values[0], "{a} vs {b}");
    }
    assert!(on_gpu.basis.orthonormality_error() < 1e-12, "the basis itself is formed in f64");
}

#[test]
fn orthonormalizing_at_most_m_columns_gives_the_whole_basis_first_m() {
    // Eight columns, the third a combination of the first two (dropped either way).
    let (n, k) = (30, 8);
    let mut data = random_vec(n * k, 31);
    for i in 0..n {
        data[i * k + 2] = 2.0 * data[i * k] - 0.5 * data[i * k + 1];
    }
    let columns = Tensor::from_vec(&[n, k], data).unwrap();
    let whole = Basis::orthonormalize("w", &columns).unwrap();
    assert_eq!(whole.reduced_dim(), 7, "the dependent column is dropped");
    for cap in [1, 4, 7, 100] {
        let part = Basis::orthonormalize_at_most("p", &columns, cap).unwrap();
        let m = cap.min(7);
        assert_eq!(part.reduced_dim(), m);
        for i in 0..n {
            for j in 0..m {
                assert_eq!(
                    part.matrix().get(&[i, j]),
                    whole.matrix().get(&[i, j]),
                    "({i}, {j}) with cap {cap}"
                );
            }
        }
    }
}
