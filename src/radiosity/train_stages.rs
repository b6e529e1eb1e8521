//! The reduced radiosity's training as the stages of the reduction workflow
//! ([`crate::reduce::reductor`]; seed 000 §8.2–8.3, §9):
//!
//! 1. `samples` — the design-space samples ([`sample_parameters`]);
//! 2. `solves` — the full radiosity of every sample, each kept as it finishes (a killed
//!    training solves only the ones not kept);
//! 3. `bases` — the Gram matrices of the pair quantities and of their modes and the per-face
//!    PCA bases, from which every basis of Table 2 is rebuilt in a moment;
//! 4. `tensors` — the premultiplied tensors and the learned visibility (§8.3);
//! 5. `correction` — the reduced operator's correction at every sample
//!    ([`super::operator_correction`]);
//! 6. `model` — the model assembled, its error estimate cross-validated
//!    ([`super::estimate`]), written to the output directory.
//!
//! [`super::train::train_across`] runs stages 3–6 in memory (greedy training, tests);
//! [`train_and_save`] runs all six in a work directory. Each stage's function is the same in
//! both, so a resumed training makes the model a straight one makes, bit for bit.

use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};

use super::chain::{radiosity as radiosity_expr, radiosity_corrected, stack_channels, table2_model};
use super::error::RadiosityError;
use super::mesh::FaceKind;
use super::operator_correction::{operator_corrections, CorrectionReport};
use super::reduced::{ReducedRadiosity, SkyLight, TrainedNearField};
use super::scene::LightMode;
use super::snapshots::{PairSnapshots, PAIR_QUANTITIES};
use super::train::{
    sample_parameters, snapshot_rows, Configuration, DesignSpace, Progress, Quantity, TrainOptions,
    TrainingReport,
};
use super::train_ranks::{decode, encode, solve_configurations_across};
use super::visibility::LearnedVisibility;
use crate::reduce::reductor::{fingerprint, Reductor, ReductorError, StageReport};
use crate::reduce::{
    basis_grams, load_arrays, pca_across, save_arrays, snapshot_grams, Bases, Basis, BasisRows, Communicator,
    ReduceOptions, ReducedModel, SnapshotBasis, SnapshotFn, SnapshotRows, Truncation,
};
use crate::tensor::Tensor;

impl From<ReductorError> for RadiosityError {
    fn from(e: ReductorError) -> Self {
        RadiosityError::Solve(e.to_string())
    }
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> RadiosityError {
    RadiosityError::File { path: path.to_path_buf(), message: e.to_string() }
}

/// Megabytes this rank has sent in collectives so far (for the stage logs).
pub(crate) fn sent_mb(ranks: &dyn Communicator) -> f64 {
    ranks.bytes_sent() as f64 / 1e6
}

/// Each quantity's truncation under `options`.
fn truncation(options: &TrainOptions, q: Quantity) -> Truncation {
    Truncation {
        energy: match q {
            Quantity::G => options.geometry_energy,
            Quantity::R => options.squared_distance_energy.unwrap_or(options.energy),
            Quantity::E | Quantity::B => options.radiosity_energy.unwrap_or(options.energy),
            _ => options.energy,
        },
        max_modes: if matches!(q, Quantity::E | Quantity::B) {
            options.radiosity_cap / 2
        } else {
            options.cap
        },
        centred: true,
    }
}

fn slot(q: Quantity) -> usize {
    PAIR_QUANTITIES.iter().position(|&p| p == q).expect("a pair quantity")
}

/// The Gram matrices wanted of the pair modes: each with itself, then `s`–`h` and `d`–`p`
/// (the bases that are merged).
fn wanted_mode_grams() -> Vec<(usize, usize)> {
    let mut wanted: Vec<(usize, usize)> = (0..PAIR_QUANTITIES.len()).map(|i| (i, i)).collect();
    wanted.push((slot(Quantity::S), slot(Quantity::H)));
    wanted.push((slot(Quantity::D), slot(Quantity::P)));
    wanted
}

/// The `bases` stage's result: what every basis of Table 2 is rebuilt from.
#[derive(Clone, Debug, PartialEq)]
pub struct BasisParts {
    /// The pair quantities' snapshot Gram matrices (`T × T`, in [`PAIR_QUANTITIES`]' order).
    pub grams: Vec<Tensor>,
    /// The Gram matrices of their PCA modes ([`wanted_mode_grams`]' order).
    pub mode_grams: Vec<Tensor>,
    /// The per-face quantities' stored bases (`g`, `n`, `a`, `e`, `b`).
    pub stored: BTreeMap<String, Basis>,
    /// Per quantity: name, full dimension, vectors kept, energy kept.
    pub report: Vec<(String, usize, usize, f64)>,
}

/// The pair quantities' PCA bases from their Gram matrices (a `T × T` eigenproblem each).
fn pair_bases<'a>(
    refs: &[&'a dyn SnapshotRows],
    grams: &[Tensor],
    options: &TrainOptions,
) -> Result<Vec<(SnapshotBasis<'a>, f64)>, RadiosityError> {
    PAIR_QUANTITIES
        .iter()
        .enumerate()
        .map(|(i, q)| {
            let (basis, spectrum) = SnapshotBasis::pca(q.name(), refs[i], &grams[i], truncation(options, *q))
                .map_err(RadiosityError::from)?;
            Ok((basis, spectrum.energy))
        })
        .collect()
}

/// Stage `bases`: one pass over blocks of pairs for the pair quantities' Gram matrices, their
/// PCA, a second pass for the Gram matrices of the modes (to orthonormalise and merge them to
/// rounding), and the stored PCA of every per-face quantity.
pub fn basis_parts(
    configurations: &[Configuration],
    options: &TrainOptions,
    progress: Progress<'_>,
    ranks: &dyn Communicator,
) -> Result<BasisParts, RadiosityError> {
    let first =
        configurations.first().ok_or_else(|| RadiosityError::Solve("no training configurations".into()))?;
    let (n, vertices) = (first.geometry.areas.len(), first.g.len() / 3);
    let pairs = PairSnapshots::new(configurations, options.near);
    let sources: Vec<_> =
        PAIR_QUANTITIES.iter().map(|&q| pairs.quantity(q).expect("a pair quantity")).collect();
    let refs: Vec<&dyn SnapshotRows> = sources.iter().map(|s| s as &dyn SnapshotRows).collect();
    let diagonal: Vec<(usize, usize)> = (0..PAIR_QUANTITIES.len()).map(|i| (i, i)).collect();
    let gram_progress = |done: f64, total: f64| progress("gram", done as u64, total as u64);
    let clock = std::time::Instant::now();
    let grams =
        snapshot_grams(&refs, &diagonal, Some(&gram_progress), ranks).map_err(RadiosityError::from)?;
    tracing::info!(
        seconds = clock.elapsed().as_secs_f64(),
        sent_mb = sent_mb(ranks),
        "training: Gram matrices of the pair quantities"
    );
    let clock = std::time::Instant::now();
    let pair = pair_bases(&refs, &grams, options)?;
    let mut stored = BTreeMap::new();
    let mut report = Vec::new();
    for (qi, q) in Quantity::ALL.iter().enumerate() {
        progress("pca", qi as u64, Quantity::ALL.len() as u64);
        let (vectors, energy) = if q.is_pair() {
            let (basis, energy) = &pair[slot(*q)];
            (basis.reduced_dim(), *energy)
        } else {
            let mut source = SnapshotFn {
                dim: q.dim(n, vertices),
                count: configurations.len(),
                rows: |rows: Range<usize>| snapshot_rows(*q, configurations, rows, options.near),
            };
            let p = pca_across(q.name(), &mut source, truncation(options, *q), ranks)
                .map_err(RadiosityError::from)?;
            let m = p.basis.reduced_dim();
            stored.insert(q.name().to_string(), p.basis);
            (m, p.energy)
        };
        report.push((q.name().to_string(), q.dim(n, vertices), vectors, energy));
    }
    progress("pca", Quantity::ALL.len() as u64, Quantity::ALL.len() as u64);
    tracing::info!(seconds = clock.elapsed().as_secs_f64(), sent_mb = sent_mb(ranks), "training: PCA");
    let rows: Vec<&dyn BasisRows> = pair.iter().map(|(b, _)| b as &dyn BasisRows).collect();
    let own_progress = |done: f64, total: f64| progress("orthonormalise", done as u64, total as u64);
    let clock = std::time::Instant::now();
    let mode_grams =
        basis_grams(&rows, &wanted_mode_grams(), Some(&own_progress), ranks).map_err(RadiosityError::from)?;
    tracing::info!(
        seconds = clock.elapsed().as_secs_f64(),
        sent_mb = sent_mb(ranks),
        "training: Gram matrices of the pair modes"
    );
    Ok(BasisParts { grams, mode_grams, stored, report })
}

/// The `format` of the work directory's stage files.
const STAGE_FORMAT: &str = "galerkin-radiosity-training-stage";

impl BasisParts {
    /// Writes the parts to `path` (f64 arrays; the report in the metadata).
    pub fn save(&self, path: &Path) -> Result<(), RadiosityError> {
        let mut arrays: Vec<(String, &Tensor)> = Vec::new();
        arrays.extend(self.grams.iter().enumerate().map(|(i, t)| (format!("gram/{i}"), t)));
        arrays.extend(self.mode_grams.iter().enumerate().map(|(i, t)| (format!("mode_gram/{i}"), t)));
        arrays.extend(self.stored.iter().map(|(n, b)| (format!("basis/{n}"), b.matrix())));
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), STAGE_FORMAT.to_string());
        meta.insert(
            "report".to_string(),
            serde_json::to_string(&self.report).map_err(|e| file_err(path, e))?,
        );
        save_arrays(path, meta, &arrays).map_err(RadiosityError::from)
    }

    /// Reads what [`Self::save`] wrote.
    pub fn load(path: &Path) -> Result<Self, RadiosityError> {
        let (meta, mut arrays) = load_arrays(path).map_err(RadiosityError::from)?;
        if meta.get("format").map(String::as_str) != Some(STAGE_FORMAT) {
            return Err(file_err(path, "not a radiosity training stage file"));
        }
        let report = serde_json::from_str(meta.get("report").map_or("", String::as_str))
            .map_err(|e| file_err(path, format!("report: {e}")))?;
        let mut take =
            |name: String| arrays.remove(&name).ok_or_else(|| file_err(path, format!("no array {name}")));
        let grams =
            (0..PAIR_QUANTITIES.len()).map(|i| take(format!("gram/{i}"))).collect::<Result<_, _>>()?;
        let mode_grams = (0..wanted_mode_grams().len())
            .map(|i| take(format!("mode_gram/{i}")))
            .collect::<Result<_, _>>()?;
        let mut stored = BTreeMap::new();
        for q in Quantity::ALL.iter().filter(|q| !q.is_pair()) {
            let matrix = take(format!("basis/{}", q.name()))?;
            stored.insert(
                q.name().to_string(),
                Basis::new(q.name(), matrix, 1e-9).map_err(RadiosityError::from)?,
            );
        }
        Ok(Self { grams, mode_grams, stored, report })
    }
}

/// The `tensors` stage's result.
#[derive(Clone, Debug)]
pub struct Premultiplied {
    /// Table 2's premultiplied tensors (without the visibility's input basis).
    pub reduced: ReducedModel,
    /// The learned visibility: `B_gᵀ G` and `B_vᵀ V` (§8.3).
    pub learned: LearnedVisibility,
    /// Merged bases: name and vectors.
    pub merged: Vec<(String, usize)>,
}

/// The pair bases `a` and `b` merged into one orthonormal basis `name` (their modes' Gram
/// matrices in `own`, their cross Gram matrix `cross`).
fn merge_pair<'a>(
    name: &str,
    pair: &[Option<SnapshotBasis<'a>>],
    own: &[Tensor],
    (a, b): (Quantity, Quantity),
    cross: &Tensor,
) -> Result<SnapshotBasis<'a>, RadiosityError> {
    let (a, b) = (slot(a), slot(b));
    let (Some(ba), Some(bb)) = (&pair[a], &pair[b]) else {
        return Err(RadiosityError::Solve(format!("basis {name}: a merged basis is missing")));
    };
    SnapshotBasis::merge(name, (ba, &own[a]), (bb, &own[b]), cross).map_err(RadiosityError::from)
}

/// Stage `tensors`: every basis rebuilt from `parts` (merging `B_s = B_h`, `B_d = B_p`,
/// `B_e = B_b`), Table 2's tensors premultiplied (the pair tensors chunk by chunk against basis
/// rows regenerated from the snapshots), and the learned visibility.
pub fn premultiplied(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    parts: &BasisParts,
    progress: Progress<'_>,
    ranks: &dyn Communicator,
) -> Result<Premultiplied, RadiosityError> {
    let first =
        configurations.first().ok_or_else(|| RadiosityError::Solve("no training configurations".into()))?;
    let pairs = PairSnapshots::new(configurations, options.near);
    let sources: Vec<_> =
        PAIR_QUANTITIES.iter().map(|&q| pairs.quantity(q).expect("a pair quantity")).collect();
    let refs: Vec<&dyn SnapshotRows> = sources.iter().map(|s| s as &dyn SnapshotRows).collect();
    let mut pair: Vec<Option<SnapshotBasis<'_>>> =
        pair_bases(&refs, &parts.grams, options)?.into_iter().map(|(b, _)| Some(b)).collect();
    let own = &parts.mode_grams;
    let sh = merge_pair("sh", &pair, own, (Quantity::S, Quantity::H), &own[PAIR_QUANTITIES.len()])?;
    let dp = merge_pair("dp", &pair, own, (Quantity::D, Quantity::P), &own[PAIR_QUANTITIES.len() + 1])?;
    let mut finished: BTreeMap<&str, SnapshotBasis<'_>> = BTreeMap::new();
    for q in [Quantity::R, Quantity::C, Quantity::V] {
        let i = slot(q);
        let basis =
            pair[i].take().expect("made above").orthonormalized(&own[i]).map_err(RadiosityError::from)?;
        finished.insert(q.name(), basis);
    }
    let mut bases = Bases::new();
    for name in ["g", "n", "a"] {
        bases.insert(name.to_string(), parts.stored[name].clone());
    }
    bases.insert(
        "b".into(),
        Basis::merge("b", &parts.stored["e"], &parts.stored["b"]).map_err(RadiosityError::from)?,
    );
    let mut row_bases: BTreeMap<String, &dyn BasisRows> = BTreeMap::new();
    row_bases.insert("sh".into(), &sh);
    row_bases.insert("dp".into(), &dp);
    for name in ["r", "c", "v"] {
        row_bases.insert(name.into(), &finished[name]);
    }
    let merged = vec![
        ("sh".into(), sh.reduced_dim()),
        ("dp".into(), dp.reduced_dim()),
        ("b".into(), bases["b"].reduced_dim()),
    ];
    // Premultiply Table 2's tensors (topology and albedo: any configuration's mesh).
    let mesh = space.mesh(&first.params)?;
    let model = table2_model(&mesh, options.near, radiosity_expr());
    let premultiply_progress = |done: f64, total: f64| progress("premultiply", done as u64, total as u64);
    let clock = std::time::Instant::now();
    let mut reduced = model
        .reduce_with_rows(
            &bases,
            &row_bases,
            &ReduceOptions { progress: Some(&premultiply_progress), ranks, ..ReduceOptions::default() },
        )
        .map_err(RadiosityError::from)?;
    tracing::info!(
        seconds = clock.elapsed().as_secs_f64(),
        sent_mb = sent_mb(ranks),
        "training: premultiplication"
    );
    // The visibility is always given reduced (Eq. 17): its n²-row basis stays out of the model.
    reduced.forget_input_basis("v").map_err(RadiosityError::from)?;
    // The learned visibility: B_gᵀ G, and B_vᵀ V from the visibility's Gram matrix.
    let t = configurations.len();
    let bg = &bases["g"];
    let mut gt = vec![0.0; bg.reduced_dim() * t];
    for (c, conf) in configurations.iter().enumerate() {
        for (i, x) in bg.project(&conf.g).into_iter().enumerate() {
            gt[i * t + c] = x;
        }
    }
    let vt =
        finished["v"].project_snapshots(&parts.grams[slot(Quantity::V)]).map_err(RadiosityError::from)?;
    let geometry =
        Tensor::from_vec(&[bg.reduced_dim(), t], gt).map_err(|e| RadiosityError::Solve(e.to_string()))?;
    let learned = LearnedVisibility::new(geometry, vt).map_err(|e| RadiosityError::Solve(e.to_string()))?;
    Ok(Premultiplied { reduced, learned, merged })
}

impl Premultiplied {
    /// Writes `dir/model.safetensors` and `dir/visibility.safetensors`.
    pub fn save(&self, dir: &Path) -> Result<(), RadiosityError> {
        self.reduced.save(&dir.join("model.safetensors")).map_err(RadiosityError::from)?;
        let path = dir.join("visibility.safetensors");
        let mut meta = HashMap::new();
        meta.insert("format".to_string(), STAGE_FORMAT.to_string());
        meta.insert(
            "merged".to_string(),
            serde_json::to_string(&self.merged).map_err(|e| file_err(&path, e))?,
        );
        let arrays = [
            ("geometry".to_string(), self.learned.geometry()),
            ("visibility".to_string(), self.learned.visibility()),
        ];
        save_arrays(&path, meta, &arrays).map_err(RadiosityError::from)
    }

    /// Reads what [`Self::save`] wrote.
    pub fn load(dir: &Path) -> Result<Self, RadiosityError> {
        let reduced = ReducedModel::load(&dir.join("model.safetensors")).map_err(RadiosityError::from)?;
        let path = dir.join("visibility.safetensors");
        let (meta, mut arrays) = load_arrays(&path).map_err(RadiosityError::from)?;
        let merged = serde_json::from_str(meta.get("merged").map_or("", String::as_str))
            .map_err(|e| file_err(&path, format!("merged: {e}")))?;
        let mut take =
            |name: &str| arrays.remove(name).ok_or_else(|| file_err(&path, format!("no array {name}")));
        let (geometry, visibility) = (take("geometry")?, take("visibility")?);
        let learned = LearnedVisibility::new(geometry, visibility).map_err(|e| file_err(&path, e))?;
        Ok(Self { reduced, learned, merged })
    }
}

/// Stage `correction`: `Q̂` at every training configuration ([`operator_corrections`]).
pub fn correction(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    tensors: &Premultiplied,
    progress: Progress<'_>,
    ranks: &dyn Communicator,
) -> Result<(Tensor, CorrectionReport), RadiosityError> {
    let first =
        configurations.first().ok_or_else(|| RadiosityError::Solve("no training configurations".into()))?;
    let mesh = space.mesh(&first.params)?;
    let clock = std::time::Instant::now();
    let correct_progress = |done: usize, total: usize| progress("correct", done as u64, total as u64);
    let (q, found) = operator_corrections(
        &tensors.reduced,
        &tensors.learned,
        configurations,
        &mesh.albedo,
        options.near,
        &correct_progress,
        ranks,
    )?;
    tracing::info!(
        seconds = clock.elapsed().as_secs_f64(),
        mean_discrepancy = found.mean_discrepancy,
        worst_discrepancy = found.worst_discrepancy,
        "training: the operator correction"
    );
    Ok((q, found))
}

fn save_correction(path: &Path, (q, found): &(Tensor, CorrectionReport)) -> Result<(), RadiosityError> {
    let mut meta = HashMap::new();
    meta.insert("format".to_string(), STAGE_FORMAT.to_string());
    let numbers = [found.mean_discrepancy, found.worst_discrepancy, found.worst_configuration as f64];
    meta.insert("report".to_string(), serde_json::to_string(&numbers).map_err(|e| file_err(path, e))?);
    save_arrays(path, meta, &[("Q".to_string(), q)]).map_err(RadiosityError::from)
}

fn load_correction(path: &Path) -> Result<(Tensor, CorrectionReport), RadiosityError> {
    let (meta, mut arrays) = load_arrays(path).map_err(RadiosityError::from)?;
    let [mean, worst, at]: [f64; 3] = serde_json::from_str(meta.get("report").map_or("", String::as_str))
        .map_err(|e| file_err(path, format!("report: {e}")))?;
    let q = arrays.remove("Q").ok_or_else(|| file_err(path, "no array Q"))?;
    Ok((
        q,
        CorrectionReport {
            mean_discrepancy: mean,
            worst_discrepancy: worst,
            worst_configuration: at as usize,
        },
    ))
}

/// Stage `model`: the reduced radiosity assembled from its tensors and correction (sky lighting
/// keeps the face–opening visibility of every configuration for the run time's direct light)
/// and, if `options.estimate`, its error estimate cross-validated.
pub fn assemble(
    space: &dyn DesignSpace,
    configurations: &[Configuration],
    options: &TrainOptions,
    tensors: Premultiplied,
    correction: Option<Tensor>,
) -> Result<ReducedRadiosity, RadiosityError> {
    let first =
        configurations.first().ok_or_else(|| RadiosityError::Solve("no training configurations".into()))?;
    let n = first.geometry.areas.len();
    let mesh = space.mesh(&first.params)?;
    let Premultiplied { mut reduced, learned, .. } = tensors;
    if let Some(q) = correction {
        // Q's configuration axis has the identity basis: Eq. 17's weights are given whole.
        reduced
            .extend(radiosity_corrected(), ("Q", &["b", "b", "x"], q), ("x", "x"))
            .map_err(RadiosityError::from)?;
    }
    let b = reduced.basis("b").ok_or_else(|| RadiosityError::Solve("the model has no basis b".into()))?;
    let emission_hat = b.project(&stack_channels(&first.emission));
    let sky = (space.lights().mode == LightMode::Sky).then(|| {
        let openings: Vec<u32> = (0..n as u32).filter(|&j| mesh.kind[j as usize].is_opening()).collect();
        let no = openings.len();
        let bits = configurations
            .iter()
            .map(|c| {
                let mut b = vec![0u64; (n * no).div_ceil(64)];
                for i in 0..n {
                    for (o, &j) in openings.iter().enumerate() {
                        if c.visible(n * i + j as usize) {
                            let k = i * no + o;
                            b[k / 64] |= 1 << (k % 64);
                        }
                    }
                }
                b
            })
            .collect();
        SkyLight { lights: space.lights().clone(), openings, bits, near: options.near }
    });
    let trained_near =
        if options.near_correction.is_some() { TrainedNearField::Exact } else { TrainedNearField::Centroid };
    let model = ReducedRadiosity::new(reduced, learned, emission_hat, n, sky, trained_near)?;
    if !options.estimate {
        return Ok(model);
    }
    let clock = std::time::Instant::now();
    let receiving: Vec<usize> = (0..n).filter(|&i| mesh.kind[i] == FaceKind::Surface).collect();
    let validation = model.cross_validate(configurations, &receiving)?;
    tracing::info!(
        seconds = clock.elapsed().as_secs_f64(),
        median_left_out_error = validation.median_left_out(),
        "training: the error estimate (each sample left out of Eq. 17)"
    );
    model.with_estimate(validation)
}

/// Where a training keeps its work and what it does with it ([`train_and_save`]).
#[derive(Clone, Debug, Default)]
pub struct WorkOptions {
    /// The work directory (default: `work` inside the output directory).
    pub dir: Option<PathBuf>,
    /// Keep it once the model is written (by default it is removed).
    pub keep: bool,
    /// Stop once this stage is kept (what a kill right after it leaves; for tests).
    pub stop_after: Option<String>,
}

/// A model trained and saved by [`train_and_save`].
pub struct TrainedScene {
    /// The model.
    pub model: ReducedRadiosity,
    /// Its bases.
    pub report: TrainingReport,
    /// Configurations solved in full.
    pub configurations: usize,
    /// Seconds of the full solves (0 where they were all kept from a stopped training).
    pub solve_seconds: f64,
    /// Seconds of the rest.
    pub train_seconds: f64,
    /// The saved model's size on disk, bytes.
    pub bytes_on_disk: u64,
}

/// Full solves kept per batch: the solves of a batch run in parallel and are written as the
/// batch ends, so a kill loses at most one batch.
const SOLVE_BATCH: usize = 16;

fn solve_file(folder: &Path, k: usize) -> PathBuf {
    folder.join(format!("{k:06}.bin"))
}

/// The solved configuration `k` kept in `folder`, if it is there and solved at `params`.
fn kept_solve(folder: &Path, k: usize, params: &[f64]) -> Result<Option<Configuration>, RadiosityError> {
    let path = solve_file(folder, k);
    let Ok(bytes) = std::fs::read(&path) else { return Ok(None) };
    let mut solved = decode(&bytes, &path.display().to_string())?;
    match solved.pop() {
        Some(c) if solved.is_empty() && c.params == params => Ok(Some(c)),
        _ => Ok(None),
    }
}

/// Stage `solves`: every configuration not yet kept in `folder` solved (over `ranks`, a batch
/// at a time) and, by the `writer`, kept there.
fn solves(
    space: &dyn DesignSpace,
    params: &[Vec<f64>],
    options: &TrainOptions,
    folder: &Path,
    writer: bool,
    progress: Progress<'_>,
    ranks: &dyn Communicator,
) -> Result<Vec<Configuration>, RadiosityError> {
    let mut all: Vec<Option<Configuration>> =
        params.iter().enumerate().map(|(k, p)| kept_solve(folder, k, p)).collect::<Result<_, _>>()?;
    let missing: Vec<usize> = (0..params.len()).filter(|&k| all[k].is_none()).collect();
    let total = missing.len() as u64;
    for (b, batch) in missing.chunks(SOLVE_BATCH).enumerate() {
        let batch_params: Vec<Vec<f64>> = batch.iter().map(|&k| params[k].clone()).collect();
        let before = (b * SOLVE_BATCH) as u64;
        let share = ranks.share(batch.len()).len() as u64 * ranks.size() as u64;
        let solved = solve_configurations_across(
            space,
            &batch_params,
            options,
            &|done| progress("solve", before + (done as u64 * ranks.size() as u64).min(share), total),
            ranks,
        )?;
        for (&k, c) in batch.iter().zip(solved) {
            if writer {
                let mut bytes = Vec::new();
                encode(&c, &mut bytes);
                let path = solve_file(folder, k);
                crate::atomic_file::write(&path, &bytes).map_err(|e| file_err(&path, e))?;
            }
            all[k] = Some(c);
        }
    }
    progress("solve", total, total);
    Ok(all.into_iter().map(|c| c.expect("every configuration solved or kept")).collect())
}

/// Every configuration kept in a finished `solves` stage's `folder`.
fn load_solves(folder: &Path, params: &[Vec<f64>]) -> Result<Vec<Configuration>, RadiosityError> {
    params
        .iter()
        .enumerate()
        .map(|(k, p)| {
            kept_solve(folder, k, p)?.ok_or_else(|| {
                file_err(
                    &solve_file(folder, k),
                    "a finished stage's solve is missing or for other parameters",
                )
            })
        })
        .collect()
}

/// The whole precompute of §8.2–8.3 and §9 as the reduction workflow's stages (module docs):
/// samples the design space of `space`, solves every sample in full (progress stage
/// `"solve"`), trains, and saves the model to `out`, keeping each stage in the work directory
/// (`work`; a training killed at any point and started again resumes at the stage it was in)
/// and reporting each to `on_stage`.
///
/// Over several `ranks` (`mpirun -n N galerkin radiosity train …`), each rank solves its
/// share of every batch of samples and trains on its share of rows and chunks
/// ([`solve_configurations_across`], [`basis_parts`], [`premultiplied`]); rank 0 alone writes
/// the work directory and the model (the others report 0 bytes on disk). With `source` — the
/// scene file and its content's hash ([`super::any_scene::AnyScene::content_sha256`]) — the
/// model records its provenance ([`crate::reduce::provenance`]).
#[allow(clippy::too_many_arguments)]
pub fn train_and_save(
    space: &dyn DesignSpace,
    options: &TrainOptions,
    out: &Path,
    source: Option<(&Path, String)>,
    work: &WorkOptions,
    progress: Progress<'_>,
    on_stage: &mut dyn FnMut(&StageReport),
    ranks: &dyn Communicator,
) -> Result<TrainedScene, RadiosityError> {
    options.check()?;
    options.check_lights(space.lights().mode)?;
    let start = std::time::Instant::now();
    let dir = work.dir.clone().unwrap_or_else(|| out.join("work"));
    let options_text = format!("{options:?}");
    let scene_text = match &source {
        Some((scene, sha256)) => format!("{} (SHA-256 {sha256})", scene.display()),
        None => format!("a design space {:?} at {:?}", space.ranges(), space.defaults()),
    };
    let engine = crate::reduce::provenance::ENGINE;
    let key = fingerprint(&[scene_text.as_bytes(), options_text.as_bytes(), engine.as_bytes()]);
    let made_for = format!("{scene_text} with {} samples, seed {}", options.samples, options.seed);
    let mut reductor = Reductor::open(&dir, &made_for, &key, ranks.is_root(), |s: &StageReport| on_stage(s))?
        .stop_after(work.stop_after.as_deref());

    let params = reductor.stage(
        "samples",
        |f| read_samples(&f.join("samples.json")),
        |f, writer| {
            let params = sample_parameters(&space.ranges(), &space.defaults(), options.samples, options.seed);
            if writer {
                let path = f.join("samples.json");
                let text = serde_json::to_string(&params).map_err(|e| file_err(&path, e))?;
                crate::atomic_file::write(&path, text.as_bytes()).map_err(|e| file_err(&path, e))?;
            }
            Ok::<_, RadiosityError>(params)
        },
    )?;
    let solve_start = std::time::Instant::now();
    let configurations = reductor.stage(
        "solves",
        |f| load_solves(f, &params),
        |f, writer| solves(space, &params, options, f, writer, progress, ranks),
    )?;
    let solve_seconds = solve_start.elapsed().as_secs_f64();
    tracing::info!(seconds = solve_seconds, sent_mb = sent_mb(ranks), "training: full solves, gathered");
    let parts = reductor.stage(
        "bases",
        |f| BasisParts::load(&f.join("bases.safetensors")),
        |f, writer| {
            let parts = basis_parts(&configurations, options, progress, ranks)?;
            if writer {
                parts.save(&f.join("bases.safetensors"))?;
            }
            Ok(parts)
        },
    )?;
    let tensors = reductor.stage("tensors", Premultiplied::load, |f, writer| {
        let tensors = premultiplied(space, &configurations, options, &parts, progress, ranks)?;
        if writer {
            tensors.save(f)?;
        }
        Ok(tensors)
    })?;
    let mut report =
        TrainingReport { bases: parts.report.clone(), merged: tensors.merged.clone(), correction: None };
    let corrected = if options.operator_correction {
        let (q, found) = reductor.stage(
            "correction",
            |f| load_correction(&f.join("correction.safetensors")),
            |f, writer| {
                let c = correction(space, &configurations, options, &tensors, progress, ranks)?;
                if writer {
                    save_correction(&f.join("correction.safetensors"), &c)?;
                }
                Ok(c)
            },
        )?;
        report.correction = Some(found);
        Some(q)
    } else {
        None
    };
    let model = reductor.stage(
        "model",
        |_| ReducedRadiosity::load(out),
        |_, writer| {
            let model = assemble(space, &configurations, options, tensors, corrected)?;
            let model = match &source {
                Some((scene, sha256)) => model.with_provenance(crate::reduce::provenance::Provenance::new(
                    scene,
                    sha256.clone(),
                    options_text.clone(),
                    &params,
                )),
                None => model,
            };
            if writer {
                model.save(out)?;
            }
            Ok::<_, RadiosityError>(model)
        },
    )?;
    let bytes_on_disk = if ranks.is_root() {
        ["model.safetensors", "visibility.safetensors"]
            .iter()
            .filter_map(|f| std::fs::metadata(out.join(f)).ok())
            .map(|m| m.len())
            .sum()
    } else {
        0
    };
    // Every rank is past its last read of the work directory before it goes.
    ranks.barrier().map_err(|e| RadiosityError::Solve(format!("waiting for the other ranks: {e}")))?;
    if !work.keep {
        reductor.remove()?;
    }
    Ok(TrainedScene {
        model,
        report,
        configurations: configurations.len(),
        solve_seconds,
        train_seconds: start.elapsed().as_secs_f64() - solve_seconds,
        bytes_on_disk,
    })
}

fn read_samples(path: &Path) -> Result<Vec<Vec<f64>>, RadiosityError> {
    let text = std::fs::read_to_string(path).map_err(|e| file_err(path, e))?;
    serde_json::from_str(&text).map_err(|e| file_err(path, e))
}
