//! Bases from snapshots: principal component analysis by the method of snapshots (§6.1, §8.3:
//! the paper built every basis by PCA of simulation snapshots).
//!
//! With snapshots as the columns of `S` (n × k, n ≫ k), the Gram matrix `G = SᵀS` (k × k) has
//! eigenpairs `G vᵢ = σᵢ² vᵢ`, and `uᵢ = S vᵢ / σᵢ` are the left singular vectors of `S`. The
//! streaming form reads `S` in blocks of rows, twice — once to accumulate `G`, once to form the
//! rows of the basis — so the snapshots never need to be in memory together (the paper used an
//! out-of-core SVD). Truncation keeps the fewest modes whose σ² add up to the requested energy
//! fraction (energy is σ², not σ), capped at a maximum count.

use std::io::{Read, Seek, SeekFrom};
use std::ops::Range;
use std::path::{Path, PathBuf};

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

use ash::vk;

use super::basis::Basis;
use super::error::ReduceError;
use super::gpu_eval::Backend;
use super::ranks::allreduce_parts;
use super::ranks::{bytes_f64, f64_bytes, Communicator, SingleRank};
use super::snapshot_basis::{orthonormal_in, product, transposed_product};
use crate::gpu::{Buffer, Gpu, MemoryKind, Submitter};
use crate::tensor::gpu::{Gemm, GemmShape};
use crate::tensor::{symmetric_eigen, Tensor};

/// Where snapshots come from, a block of rows at a time.
pub trait SnapshotSource {
    /// Full dimension `n` (rows).
    fn dim(&self) -> usize;
    /// Number of snapshots `k` (columns).
    fn count(&self) -> usize;
    /// Rows `rows` of every snapshot, as a `rows.len() × k` row-major tensor.
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError>;
}

/// Snapshots held in memory as the columns of an `n × k` matrix.
impl SnapshotSource for &Tensor {
    fn dim(&self) -> usize {
        self.shape()[0]
    }
    fn count(&self) -> usize {
        self.shape()[1]
    }
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError> {
        let k = self.count();
        Ok(Tensor::from_vec(&[rows.len(), k], self.data()[rows.start * k..rows.end * k].to_vec())
            .expect("shape matches"))
    }
}

/// Snapshots regenerated on demand: `f(rows)` returns those rows of every snapshot.
pub struct SnapshotFn<F> {
    /// Full dimension.
    pub dim: usize,
    /// Number of snapshots.
    pub count: usize,
    /// The generator.
    pub rows: F,
}

impl<F: FnMut(Range<usize>) -> Tensor> SnapshotSource for SnapshotFn<F> {
    fn dim(&self) -> usize {
        self.dim
    }
    fn count(&self) -> usize {
        self.count
    }
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError> {
        let want = [rows.len(), self.count];
        let t = (self.rows)(rows);
        if t.shape() != want {
            return Err(ReduceError::BadBasis {
                basis: "snapshots".into(),
                detail: format!("the generator returned shape {:?} for {want:?}", t.shape()),
            });
        }
        Ok(t)
    }
}

/// Snapshots in a file of little-endian f64, row-major `n × k` (row `i` holds component `i` of
/// every snapshot), read a block of rows at a time.
pub struct SnapshotFile {
    path: PathBuf,
    file: std::fs::File,
    dim: usize,
    count: usize,
}

impl SnapshotFile {
    /// Opens `path` holding `dim × count` f64 values; an error names the file if its size
    /// disagrees.
    pub fn open(path: &Path, dim: usize, count: usize) -> Result<Self, ReduceError> {
        let bad =
            |detail: String| ReduceError::BadBasis { basis: format!("snapshots {}", path.display()), detail };
        let file = std::fs::File::open(path).map_err(|e| bad(e.to_string()))?;
        let len = file.metadata().map_err(|e| bad(e.to_string()))?.len();
        let want = (dim * count * 8) as u64;
        if len != want {
            return Err(bad(format!("{len} bytes, but {dim} × {count} f64 values need {want}")));
        }
        Ok(Self { path: path.to_path_buf(), file, dim, count })
    }
}

impl SnapshotSource for SnapshotFile {
    fn dim(&self) -> usize {
        self.dim
    }
    fn count(&self) -> usize {
        self.count
    }
    fn rows(&mut self, rows: Range<usize>) -> Result<Tensor, ReduceError> {
        let bad = |e: std::io::Error| ReduceError::BadBasis {
            basis: format!("snapshots {}", self.path.display()),
            detail: e.to_string(),
        };
        let mut bytes = vec![0u8; rows.len() * self.count * 8];
        self.file.seek(SeekFrom::Start((rows.start * self.count * 8) as u64)).map_err(bad)?;
        self.file.read_exact(&mut bytes).map_err(bad)?;
        let data =
            bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect();
        Ok(Tensor::from_vec(&[rows.len(), self.count], data).expect("shape matches"))
    }
}

/// How many modes to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truncation {
    /// Keep the fewest modes whose σ² sum to at least this fraction of the total (0 < e ≤ 1).
    pub energy: f64,
    /// And never more than this many (the mean included, when centred).
    pub max_modes: usize,
    /// Analyse the *variance*: the modes of the snapshots minus their mean, the mean itself
    /// added to the basis. Without it the energy fraction is of the raw snapshots, which for
    /// quantities with a large common part (vertex positions: the mean holds 99.9 % of the
    /// energy of a deforming room) keeps nothing that varies.
    pub centred: bool,
}

impl Default for Truncation {
    fn default() -> Self {
        Self { energy: 0.9999, max_modes: usize::MAX, centred: false }
    }
}

/// A PCA basis with its spectrum.
#[derive(Clone, Debug)]
pub struct Pca {
    /// The orthonormal basis (n × m).
    pub basis: Basis,
    /// Every singular value σ of the snapshot matrix, descending.
    pub singular_values: Vec<f64>,
    /// Fraction of Σσ² the kept modes hold.
    pub energy: f64,
}

/// Rows per block when streaming.
pub(crate) const BLOCK_ROWS: usize = 4096;

/// PCA of the snapshots in `source`, streaming blocks of rows (see the module docs), on the CPU.
pub fn pca(name: &str, source: &mut impl SnapshotSource, truncation: Truncation) -> Result<Pca, ReduceError> {
    pca_with(name, source, truncation, Backend::Cpu, None)
}

/// [`pca`] with the Gram matrix `SᵀS` accumulated on the chosen backend: faer in f64, or the
/// tiled GEMM on the device in f32 (σ² below about 1e-6 of the largest are then not
/// resolved). The eigendecomposition and the basis rows are computed on the CPU in f64.
pub fn pca_with(
    name: &str,
    source: &mut impl SnapshotSource,
    truncation: Truncation,
    backend: Backend,
    gpu: Option<&Gpu>,
) -> Result<Pca, ReduceError> {
    match (backend.uses_gpu(gpu), gpu) {
        (true, Some(g)) => pca_inner(name, source, truncation, Some(&mut g.submitter()), &SingleRank),
        _ => pca_inner(name, source, truncation, None, &SingleRank),
    }
}

/// [`pca`] with the Gram matrix accumulated on the device through `submitter` (the engine's
/// queue or a host's): per block of rows, its upload and one accumulating GEMM; one readback
/// at the end.
pub fn pca_on(
    name: &str,
    source: &mut impl SnapshotSource,
    truncation: Truncation,
    submitter: &mut dyn Submitter,
) -> Result<Pca, ReduceError> {
    pca_inner(name, source, truncation, Some(submitter), &SingleRank)
}

/// [`pca`] sharded over `ranks`: rows of the snapshot matrix partitioned over the ranks in
/// contiguous blocks (each rank asks `source` only for its own rows — the snapshots are
/// generated or read by the rank that owns them); each rank forms the Gram matrix of its rows,
/// one allreduce sums them, the eigendecomposition runs on every rank, and each rank forms its
/// rows of the basis. Those are orthonormalised by CholeskyQR2 in the form this module already
/// uses for bases held as coefficients — twice: the Gram matrix of the rows (one allreduce),
/// Gram–Schmidt in its metric ([`super::snapshot_basis`]), the rows multiplied by the
/// coefficients — and gathered, so every rank returns the whole basis (the per-face and
/// per-vertex bases are small; bases of `n²` rows are kept as coefficients instead,
/// [`super::SnapshotBasis`]).
///
/// Why a second pass: the columns `S vᵢ / σᵢ` carry the eigenvectors' rounding, about
/// `ε σ_max² / σᵢ²`, magnified by `1/σᵢ`; one Cholesky-like pass leaves an orthonormality
/// error of about `ε κ²` of what it was given, the second brings it to rounding ("twice is
/// enough"). On one rank the result is the same as on many, within rounding.
pub fn pca_across(
    name: &str,
    source: &mut impl SnapshotSource,
    truncation: Truncation,
    ranks: &dyn Communicator,
) -> Result<Pca, ReduceError> {
    pca_inner(name, source, truncation, None, ranks)
}

fn pca_inner(
    name: &str,
    source: &mut impl SnapshotSource,
    truncation: Truncation,
    submitter: Option<&mut dyn Submitter>,
    ranks: &dyn Communicator,
) -> Result<Pca, ReduceError> {
    let (n, k) = (source.dim(), source.count());
    let bad = |detail: String| ReduceError::BadBasis { basis: name.to_string(), detail };
    if n == 0 || k == 0 {
        return Err(bad(format!("no snapshots ({n} × {k})")));
    }
    if !(truncation.energy > 0.0 && truncation.energy <= 1.0) || truncation.max_modes == 0 {
        return Err(bad(format!("truncation needs 0 < energy ≤ 1 and max_modes ≥ 1, got {truncation:?}")));
    }
    // This rank's rows: a contiguous share, read in blocks.
    let share = ranks.share(n);
    let (first, last) = (share.start, share.end);
    // Pass 1: G = Σ_blocks Sᵀ_b S_b.
    let mut gram = vec![0.0; k * k];
    let mut device = match submitter {
        Some(submitter) => Some(DeviceGram::new(submitter, k)?),
        None => None,
    };
    for start in (first..last).step_by(BLOCK_ROWS) {
        let block = source.rows(start..(start + BLOCK_ROWS).min(last))?;
        if let Some(i) = block.data().iter().position(|v| !v.is_finite()) {
            return Err(bad(format!("snapshot {} row {} is not finite", i % k, start + i / k)));
        }
        match &mut device {
            Some(d) => d.accumulate(&block, start == first)?,
            None => {
                let s = MatRef::from_row_major_slice(block.data(), block.shape()[0], k);
                let g = MatMut::from_row_major_slice_mut(&mut gram, k, k);
                matmul(g, Accum::Add, s.transpose(), s, 1.0, Par::rayon(0));
            }
        }
    }
    if let Some(d) = &mut device {
        if last > first {
            gram = d.read()?;
        }
    }
    allreduce_parts(ranks, &mut [&mut gram], "the Gram matrix of the snapshots")?;
    let modes = modes_from_gram(name, gram, k, truncation, 0.0)?;
    let (vs, m, sigma2, kept, total) =
        (modes.coefficients, modes.columns, modes.sigma2, modes.kept, modes.total);
    // Pass 2: this rank's rows of B = S V.
    let rows = last - first;
    let mut b = vec![0.0; rows * m];
    for start in (first..last).step_by(BLOCK_ROWS) {
        let end = (start + BLOCK_ROWS).min(last);
        let block = source.rows(start..end)?;
        let s = MatRef::from_row_major_slice(block.data(), end - start, k);
        let out =
            MatMut::from_row_major_slice_mut(&mut b[(start - first) * m..(end - first) * m], end - start, m);
        matmul(out, Accum::Replace, s, MatRef::from_row_major_slice(&vs, k, m), 1.0, Par::rayon(0));
    }
    // CholeskyQR2 over the ranks (see above).
    let mut b = Tensor::from_vec(&[rows, m], b).expect("rows × m");
    for _ in 0..2 {
        let mut w = transposed_product(&b, &b).into_data();
        allreduce_parts(ranks, &mut [&mut w], "the Gram matrix of the basis rows")?;
        let cols = b.shape()[1];
        let u = orthonormal_in(name, &Tensor::from_vec(&[cols, cols], w).expect("m × m"))?;
        b = product(&b, &u);
    }
    let m = b.shape()[1];
    let whole = if ranks.size() == 1 {
        b
    } else {
        let parts = ranks.all_gather(&f64_bytes(b.data())).map_err(|cause| ReduceError::Ranks {
            context: format!("gathering the rows of basis `{name}`"),
            cause,
        })?;
        let mut data = Vec::with_capacity(n * m);
        for (r, part) in parts.iter().enumerate() {
            let values = bytes_f64(part).map_err(|detail| bad(format!("rows from rank {r}: {detail}")))?;
            data.extend_from_slice(&values);
        }
        Tensor::from_vec(&[n, m], data).map_err(|e| bad(format!("the gathered rows: {e}")))?
    };
    let basis = Basis::new(name, whole, ORTHONORMAL)?;
    let energy = if total > 0.0 { kept / total } else { 1.0 };
    Ok(Pca { basis, singular_values: sigma2.iter().map(|s| s.sqrt()).collect(), energy })
}

/// What [`pca_across`] guarantees of its basis: max |BᵀB − I| after CholeskyQR2 (rounding of
/// Gram matrices summed over up to millions of rows).
const ORTHONORMAL: f64 = 1e-10;

/// The modes a PCA keeps, from the Gram matrix of its snapshots (shared by [`pca_with`] and
/// the snapshot-coefficient bases of [`super::snapshot_basis`]).
pub(crate) struct Modes {
    /// `k × columns` row-major: basis column `c` is `S · coefficients[:, c]` (centred: the mean
    /// first, scaled to unit length like the modes, then `(I − 11ᵀ/k) vᵢ / σᵢ`), orthonormal up
    /// to rounding except for the mean.
    pub coefficients: Vec<f64>,
    /// Number of columns (modes, plus the mean when centred).
    pub columns: usize,
    /// σ² of every mode, descending.
    pub sigma2: Vec<f64>,
    /// Σσ² of the kept modes.
    pub kept: f64,
    /// Σσ² of all modes.
    pub total: f64,
}

/// Eigendecomposes the `k × k` Gram matrix `gram` (`SᵀS`, uncentred) and truncates as
/// `truncation` says, never keeping a mode whose σ² is below `floor_ratio` (at least `k ε`) of
/// the largest.
pub(crate) fn modes_from_gram(
    name: &str,
    mut gram: Vec<f64>,
    k: usize,
    truncation: Truncation,
    floor_ratio: f64,
) -> Result<Modes, ReduceError> {
    let bad = |detail: String| ReduceError::BadBasis { basis: name.to_string(), detail };
    // |S 1/k|² = 1ᵀG1/k²: the mean column is scaled to unit length, so that a column far
    // shorter than the others is rounding whatever the data's scale.
    let mean_norm2 = gram.iter().sum::<f64>() / (k * k) as f64;
    if truncation.centred {
        // The Gram matrix of the centred snapshots S(I − 11ᵀ/k) is (I − 11ᵀ/k) G (I − 11ᵀ/k).
        let row_mean: Vec<f64> =
            (0..k).map(|i| gram[i * k..(i + 1) * k].iter().sum::<f64>() / k as f64).collect();
        let all_mean = row_mean.iter().sum::<f64>() / k as f64;
        for i in 0..k {
            for j in 0..k {
                gram[i * k + j] += all_mean - row_mean[i] - row_mean[j];
            }
        }
    }
    let (values, vectors) = symmetric_eigen(name, &Tensor::from_vec(&[k, k], gram).expect("k×k"))
        .map_err(|cause| ReduceError::Tensor { context: format!("PCA of `{name}`"), cause })?;
    // Descending; tiny negative eigenvalues of G are rounding.
    let order: Vec<usize> = (0..k).rev().collect();
    let sigma2: Vec<f64> = order.iter().map(|&i| values[i].max(0.0)).collect();
    let total: f64 = sigma2.iter().sum();
    if total <= 0.0 && !truncation.centred {
        return Err(bad("every snapshot is zero".into()));
    }
    let floor = sigma2[0] * floor_ratio.max(k as f64 * f64::EPSILON);
    let max_modes = truncation.max_modes - usize::from(truncation.centred);
    let mut m = 0;
    let mut kept = 0.0;
    while m < k && m < max_modes && sigma2[m] > floor && kept < truncation.energy * total {
        kept += sigma2[m];
        m += 1;
    }
    let m = if truncation.centred { m } else { m.max(1) };
    // The basis is B = S V_m Σ_m⁻¹ (centred: the mean S 1/k first, and the centred
    // coefficients (I − 11ᵀ/k) vᵢ / σᵢ).
    let offset = usize::from(truncation.centred);
    let cols = m + offset;
    let mut vs = vec![0.0; k * cols];
    if truncation.centred {
        let unit = if mean_norm2 > 0.0 { mean_norm2.sqrt() } else { 1.0 };
        for r in 0..k {
            vs[r * cols] = 1.0 / (k as f64 * unit);
        }
    }
    for (c, &i) in order.iter().take(m).enumerate() {
        let s = sigma2[c].sqrt();
        let mean = (0..k).map(|r| vectors.data()[r * k + i]).sum::<f64>() / k as f64;
        let centre = if truncation.centred { mean } else { 0.0 };
        for r in 0..k {
            vs[r * cols + c + offset] = (vectors.data()[r * k + i] - centre) / s;
        }
    }
    Ok(Modes { coefficients: vs, columns: cols, sigma2, kept, total })
}

/// The Gram matrix accumulated on the device: `G (k × k) += S_bᵀ · S_b` per block of rows.
struct DeviceGram<'s> {
    submitter: &'s mut dyn Submitter,
    gemm: Gemm,
    g: Buffer<f32>,
    k: usize,
}

fn device_err(e: crate::gpu::GpuError) -> ReduceError {
    ReduceError::device("PCA on the device")(e)
}

impl<'s> DeviceGram<'s> {
    fn new(submitter: &'s mut dyn Submitter, k: usize) -> Result<Self, ReduceError> {
        let gpu = submitter.gpu();
        let gemm = Gemm::new(gpu).map_err(device_err)?;
        let g = Buffer::new(
            gpu,
            "Gram matrix",
            (k * k) as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuOnly,
        )
        .map_err(device_err)?;
        Ok(Self { submitter, gemm, g, k })
    }

    fn accumulate(&mut self, block: &Tensor, first: bool) -> Result<(), ReduceError> {
        let (rows, k) = (block.shape()[0], self.k);
        let st: Vec<f32> =
            (0..k).flat_map(|j| (0..rows).map(move |i| block.data()[i * k + j] as f32)).collect();
        let s: Vec<f32> = block.data().iter().map(|&v| v as f32).collect();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let sub = &mut *self.submitter;
        let a = sub.buffer_from_slice("snapshot block transposed", &st, usage).map_err(device_err)?;
        let b = sub.buffer_from_slice("snapshot block", &s, usage).map_err(device_err)?;
        let whole = |x| Buffer::<f32>::whole(x);
        let shape = GemmShape { m: k as u32, n: k as u32, k: rows as u32 };
        let gpu = sub.gpu().clone();
        let binding =
            self.gemm.bind(&gpu, whole(&a), whole(&b), whole(&self.g), shape).map_err(device_err)?;
        let gemm = &self.gemm;
        sub.submit(&mut |rec| gemm.record(rec, &binding, !first)).map_err(device_err)
    }

    fn read(&mut self) -> Result<Vec<f64>, ReduceError> {
        let v = self.submitter.download(&self.g).map_err(device_err)?;
        Ok(v.into_iter().map(f64::from).collect())
    }
}
