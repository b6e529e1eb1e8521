//! `galerkin radiosity compare`: the reduced model against the full radiosity over the two
//! animation sequences through the design space (seed 000 §9: 420 and 500 frames, most of
//! them configurations no training sample had), with the error measured where it matters.
//!
//! **Error measures.** The relative error of a frame is area-weighted over faces and the three
//! channels, `‖b − b_full‖_A / ‖b_full‖_A` with `‖x‖²_A = Σᵢ Aᵢ Σ_c x_{i,c}²`. Over *all*
//! faces this includes the window and skylight faces, whose radiosity is their own emission
//! (exact in the reduced model too) and which hold most of the norm (about 92 % in the two
//! rooms): it understates the error on what a user looks at. The headline is therefore over
//! the **receiving surfaces** (every face that is not an opening); the all-faces figure is
//! kept beside it, and for the two-room scene the error of each room's receiving surfaces
//! (living room, bedroom, and the door's frame between them) too.
//!
//! The full frames can be kept on disk and reused by the next model's comparison
//! ([`super::full_frames`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};

use super::any_scene::AnyScene;
use super::estimate::Estimate;
use super::full_frames::{save_due, FullFrame, FullFramesFile};
use super::mesh::{FaceKind, SceneMesh};
use super::reduced::ReducedRadiosity;
use super::Rgb;

/// The most frames a compared sequence may have (each is a full solve: hours at this count).
pub const MAX_FRAMES: usize = 100_000;

/// How far a kept full frame may be from a fresh solve of the same frame (relative, area
/// weighted): the solve is deterministic (each face's sums in a fixed order), so anything above
/// rounding means the file is stale.
const KEPT_FRAME_TOLERANCE: f64 = 1e-9;

/// Parameter vector of frame `f` of `frames` on sequence `which` (0 or 1): a smooth closed path
/// through the parameter box, each parameter a sine of its own frequency and phase, within
/// 47 % of the half range around the middle.
pub fn sequence(ranges: &[[f64; 2]], which: usize, f: usize, frames: usize) -> Vec<f64> {
    let t = f as f64 / frames as f64;
    let (freq, phase): ([f64; 4], [f64; 4]) = if which == 0 {
        ([1.0, 2.0, 1.0, 1.5], [0.0, 1.0, 2.5, 0.5])
    } else {
        ([2.0, 1.0, 3.0, 1.0], [1.3, 0.2, 0.7, 2.9])
    };
    ranges
        .iter()
        .enumerate()
        .map(|(a, r)| {
            let u = 0.5
                + 0.47 * (2.0 * std::f64::consts::PI * freq[a % 4] * t + phase[a % 4] + (a / 4) as f64).sin();
            r[0] + u * (r[1] - r[0])
        })
        .collect()
}

/// Sets of faces an error is measured over: the receiving surfaces, then (two-room scene)
/// each room's receiving surfaces.
#[derive(Clone, Debug, PartialEq)]
pub struct FaceGroups {
    /// The groups' names, in order: `receiving` first.
    pub names: Vec<String>,
    /// The faces of each group.
    pub faces: Vec<Vec<usize>>,
}

impl FaceGroups {
    /// The groups of `mesh` (any frame: faces and their kinds are the same in every frame).
    /// The two rooms are told apart by where a face's centroid lies along x (the living room
    /// is x ≤ L₁, the bedroom x ≥ L₁ + t, the door's frame between; seed 000 §9's layout).
    pub fn of(scene: &AnyScene, mesh: &SceneMesh) -> Self {
        let receiving: Vec<usize> = (0..mesh.len()).filter(|&i| mesh.kind[i] == FaceKind::Surface).collect();
        let mut names = vec!["receiving".to_string()];
        let mut faces = vec![receiving.clone()];
        if let AnyScene::Rooms(spec) = scene {
            let geometry = mesh.geometry();
            let (l1, t) = (spec.rooms.living[0], spec.rooms.wall_thickness);
            let eps = 1e-9 * (l1 + t);
            let room = |i: &usize| {
                let x = geometry.centroids[*i].x;
                if x <= l1 + eps {
                    0
                } else if x >= l1 + t - eps {
                    2
                } else {
                    1
                }
            };
            for (k, name) in ["living room", "door frame", "bedroom"].iter().enumerate() {
                names.push((*name).to_string());
                faces.push(receiving.iter().copied().filter(|i| room(i) == k).collect());
            }
        }
        Self { names, faces }
    }
}

/// [`super::reduced::relative_error`] over some faces only: area-weighted over them and the
/// three channels.
pub fn relative_error_over(b: &[Rgb], reference: &[Rgb], areas: &[f64], faces: &[usize]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for &i in faces {
        for c in 0..3 {
            num += areas[i] * (b[i][c] - reference[i][c]).powi(2);
            den += areas[i] * reference[i][c].powi(2);
        }
    }
    (num / den.max(1e-300)).sqrt()
}

/// One frame's errors: over all faces, and over each of the [`FaceGroups`].
#[derive(Clone, Debug, PartialEq)]
pub struct FrameError {
    /// Over all faces, emitters included (the figure published before the receiving one).
    pub all: f64,
    /// Per group, in [`FaceGroups::names`]' order (`receiving` first).
    pub groups: Vec<f64>,
    /// The radiosity basis's own floor over the receiving surfaces: the full radiosity
    /// projected on `B_b` ([`ReducedRadiosity::best_fit`]) against the full radiosity — what
    /// the reduced solve would give with the exact operator, to within its quasi-optimality.
    pub best_fit: f64,
    /// The model's own estimate of its error over the receiving surfaces, and its stability
    /// check ([`super::estimate`]).
    pub estimate: Estimate,
}

/// The errors of reduced radiosity `b` against the full `frame`, over all faces and each group,
/// `model`'s best fit of the frame, and the model's `estimate` beside them.
pub fn frame_error(
    b: &[Rgb],
    frame: &FullFrame,
    groups: &FaceGroups,
    model: &ReducedRadiosity,
    estimate: Estimate,
) -> FrameError {
    let fit = model.best_fit(&frame.radiosity);
    FrameError {
        all: super::reduced::relative_error(b, &frame.radiosity, &frame.areas),
        groups: groups
            .faces
            .iter()
            .map(|faces| relative_error_over(b, &frame.radiosity, &frame.areas, faces))
            .collect(),
        best_fit: relative_error_over(&fit, &frame.radiosity, &frame.areas, &groups.faces[0]),
        estimate,
    }
}

/// A row's parameters and errors for the tables (`compare.csv`, `corners.csv`,
/// `random.csv`): the parameters, the all-faces error, each group's, the best fit's, then the
/// estimate, the reduced operator's least singular value and its margin.
pub fn csv_fields(p: &[f64], error: &FrameError) -> String {
    let values: Vec<String> = p.iter().map(|v| v.to_string()).collect();
    let group_values: Vec<String> = error.groups.iter().map(|e| format!("{e:.6}")).collect();
    let e = &error.estimate;
    format!(
        "{},{:.6},{},{:.6},{:.6},{:.6},{:.6}",
        values.join(","),
        error.all,
        group_values.join(","),
        error.best_fit,
        e.error,
        e.stability,
        e.margin
    )
}

/// The header of [`csv_fields`]' columns for a scene's parameter `names` and error groups.
pub fn csv_header(names: &[String], groups: &FaceGroups) -> String {
    let group_columns: Vec<String> =
        groups.names.iter().map(|n| format!("error_{}", n.replace(' ', "_"))).collect();
    format!(
        "{},relative_error,{},best_fit_receiving,estimated_error,operator_sigma_min,operator_margin",
        names.join(","),
        group_columns.join(",")
    )
}

/// Mean and worst of a series.
pub fn mean_worst(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = v.clone().count().max(1) as f64;
    (v.clone().sum::<f64>() / n, v.fold(0.0f64, f64::max))
}

/// One sequence's result.
#[derive(Clone, Debug)]
pub struct SequenceReport {
    /// The errors of every frame.
    pub errors: Vec<FrameError>,
}

impl SequenceReport {
    /// Mean and worst over all faces.
    pub fn all_faces(&self) -> (f64, f64) {
        mean_worst(self.errors.iter().map(|e| e.all))
    }

    /// Mean and worst over group `k` of the [`FaceGroups`] (0: the receiving surfaces).
    pub fn group(&self, k: usize) -> (f64, f64) {
        mean_worst(self.errors.iter().map(move |e| e.groups.get(k).copied().unwrap_or(f64::NAN)))
    }

    /// Mean and worst of the radiosity basis's best fit over the receiving surfaces.
    pub fn best_fit(&self) -> (f64, f64) {
        mean_worst(self.errors.iter().map(|e| e.best_fit))
    }
}

/// What a comparison measured, and where it wrote its table and plot.
#[derive(Clone, Debug)]
pub struct CompareReport {
    /// The face groups the errors are measured over.
    pub groups: FaceGroups,
    /// Per sequence.
    pub sequences: Vec<SequenceReport>,
    /// The design space's corners ([`super::train::box_corners`]; in the training set, since
    /// the sampler takes them all): each corner's parameters and errors.
    pub corners: Vec<(Vec<f64>, FrameError)>,
    /// The random configurations' parameters and errors (`random.csv`).
    pub random: Vec<(Vec<f64>, FrameError)>,
    /// Median seconds of a full frame solved in this run, and how many were.
    pub full_median_s: f64,
    /// Full frames solved in this run.
    pub full_solved: usize,
    /// Median seconds of a reduced frame (mesh build and lift included).
    pub reduced_median_s: f64,
    /// Seconds in the reduced frame's stages, summed: projecting g, the learned visibility
    /// (and the sky's direct light), Table 2's chain and the solve, the error estimate and
    /// stability check, lifting b.
    pub stage_seconds: [f64; 5],
    /// The table written (one row per frame).
    pub csv: PathBuf,
    /// The plot written (error per frame per sequence).
    pub plot: PathBuf,
}

impl CompareReport {
    /// Mean and worst over every frame of every sequence, over group `k` (`None`: all faces).
    pub fn overall(&self, k: Option<usize>) -> (f64, f64) {
        let all = self.sequences.iter().flat_map(|s| &s.errors);
        mean_worst(all.map(move |e| pick(e, k)))
    }

    /// Mean and worst of the best fit over every frame of every sequence (receiving surfaces).
    pub fn overall_best_fit(&self) -> (f64, f64) {
        mean_worst(self.sequences.iter().flat_map(|s| &s.errors).map(|e| e.best_fit))
    }

    /// Mean and worst over the corners, over group `k` (`None`: all faces), and the worst
    /// corner's parameters (`None` without corners).
    pub fn corners_overall(&self, k: Option<usize>) -> Option<(f64, f64, &[f64])> {
        let worst = self.corners.iter().max_by(|a, b| pick(&a.1, k).total_cmp(&pick(&b.1, k)))?;
        let (mean, top) = mean_worst(self.corners.iter().map(|(_, e)| pick(e, k)));
        Some((mean, top, &worst.0))
    }
}

/// Error `e` over group `k` (`None`: all faces).
fn pick(e: &FrameError, k: Option<usize>) -> f64 {
    match k {
        None => e.all,
        Some(k) => e.groups.get(k).copied().unwrap_or(f64::NAN),
    }
}

/// What to compare.
#[derive(Clone, Debug)]
pub struct CompareOptions {
    /// Frames of each sequence (the paper: 420 and 500).
    pub frames: Vec<usize>,
    /// Where full frames are kept between runs (see [`super::full_frames`]).
    pub full_frames: Option<PathBuf>,
    /// With kept full frames: how many per sequence are solved again (timed and checked).
    pub timed_full: usize,
    /// Where `compare.csv` and `compare.png` go (created).
    pub out: PathBuf,
    /// The full frames' form factors: centroid (what the model was trained on) or with the
    /// exact near field (the accurate ground truth: the error of the whole approximation).
    pub full_form_factors: super::near_field::FormFactorMethod,
    /// Random configurations of the design space to solve full and reduced besides the
    /// sequences and corners (`random.csv`; [`crate::reduce::effectivity::random_parameters`]).
    pub random: usize,
    /// Their seed.
    pub random_seed: u64,
}

/// The full-frames files' key for a lighting and a form-factor method (frames of another
/// method are never reused).
fn frames_key(mode: super::LightMode, method: super::near_field::FormFactorMethod) -> String {
    match method {
        super::near_field::FormFactorMethod::Centroid => format!("{mode:?}"),
        super::near_field::FormFactorMethod::ExactNear { reach } => {
            format!("{mode:?} exact near field {reach}")
        }
    }
}

/// Progress of a comparison, for a progress display.
#[derive(Debug)]
pub enum Progress<'a> {
    /// A sequence starts: its index, its frame count and what it does.
    Sequence(usize, usize, &'a str),
    /// A frame of the current sequence is done.
    Frame,
    /// A sequence is done (its report, and the groups' names).
    SequenceDone(usize, &'a SequenceReport, &'a FaceGroups),
}

/// Checks the sequences' frame counts: each 1 to [`MAX_FRAMES`].
pub fn check_frames(frames: &[usize]) -> Result<()> {
    if frames.is_empty() || frames.contains(&0) || frames.iter().any(|&f| f > MAX_FRAMES) {
        bail!("--frames {frames:?}: each sequence needs 1 to {MAX_FRAMES} frames");
    }
    Ok(())
}

/// Runs the comparison of `model` with the full radiosity of `scene` (read from
/// `scene_path`) and writes the table and the plot (the table after each sequence, so a long
/// run stopped in its second sequence leaves the first).
pub fn compare(
    scene: &AnyScene,
    scene_path: &Path,
    model: &ReducedRadiosity,
    options: &CompareOptions,
    progress: &mut dyn FnMut(Progress),
) -> Result<CompareReport> {
    check_frames(&options.frames)?;
    let spec = scene.space();
    if model.light_mode() != spec.lights().mode {
        bail!(
            "the model was trained with {:?} lighting, the scene is lit by {:?}",
            model.light_mode(),
            spec.lights().mode
        );
    }
    std::fs::create_dir_all(&options.out).with_context(|| format!("creating {}", options.out.display()))?;
    let ranges = spec.ranges();
    let first = sequence(&ranges, 0, 0, options.frames[0]);
    let groups = FaceGroups::of(scene, &spec.mesh(&first)?);
    let mut rows = vec![format!("sequence,frame,{},full_ms,reduced_ms", csv_header(&scene.names(), &groups))];
    let mut sequences: Vec<SequenceReport> = Vec::new();
    let (mut full_times, mut reduced_times) = (Vec::new(), Vec::new());
    let mut stages = [0.0f64; 5];
    let lighting = frames_key(spec.lights().mode, options.full_form_factors);
    let csv = options.out.join("compare.csv");
    for (which, &frames) in options.frames.iter().enumerate() {
        let params: Vec<Vec<f64>> = (0..frames).map(|f| sequence(&ranges, which % 2, f, frames)).collect();
        let file = match &options.full_frames {
            Some(dir) => Some(FullFramesFile::new(dir, scene_path, &lighting, which, frames)?),
            None => None,
        };
        let mut kept = file.as_ref().map_or_else(Vec::new, |file| file.load_or_none(model.faces(), &params));
        // Kept frames are read back, and every stride-th of them solved again (timed, and
        // checked); the others are solved, timed, and kept.
        let reused = kept.len();
        let stride = (frames / options.timed_full.max(1)).max(1);
        let label = match &file {
            Some(file) if reused > 0 => {
                format!(
                    "sequence {} (reduced; {reused} full frames from {})",
                    which + 1,
                    file.path().display()
                )
            }
            _ => format!("sequence {} (full and reduced)", which + 1),
        };
        progress(Progress::Sequence(which, frames, &label));
        let mut errors = Vec::with_capacity(frames);
        for (f, p) in params.iter().enumerate() {
            let from_file = f < reused;
            let fresh = if !from_file || f % stride == 0 {
                let frame = FullFrame::solve(spec, p, options.full_form_factors)?;
                full_times.push(frame.seconds);
                if from_file {
                    // Solved again, the kept frame must be what the solver gives now.
                    let d =
                        super::reduced::relative_error(&kept[f].radiosity, &frame.radiosity, &frame.areas);
                    if d > KEPT_FRAME_TOLERANCE {
                        let path = file.as_ref().map_or(PathBuf::new(), |file| file.path().to_path_buf());
                        bail!(
                            "{}: frame {f} differs from a fresh full solve by {d:.2e} (relative); delete the file",
                            path.display()
                        );
                    }
                }
                Some(frame)
            } else {
                None
            };
            let t = Instant::now();
            let mesh = spec.mesh(p)?;
            let (b, times, estimate) = model.evaluate_estimated(&mesh)?;
            let reduced_s = t.elapsed().as_secs_f64();
            stages[0] += times.project;
            stages[1] += times.visibility + times.direct;
            stages[2] += times.chain;
            stages[3] += times.estimate;
            stages[4] += times.lift;
            let full_ms = fresh.as_ref().map_or(String::new(), |frame| format!("{:.3}", frame.seconds * 1e3));
            let reference = match (&fresh, from_file) {
                (_, true) => &kept[f],
                (Some(frame), false) => frame,
                (None, false) => bail!("frame {f} of sequence {} was neither kept nor solved", which + 1),
            };
            let error = frame_error(&b, reference, &groups, model, estimate);
            rows.push(format!(
                "{},{f},{},{full_ms},{:.4}",
                which + 1,
                csv_fields(p, &error),
                reduced_s * 1e3
            ));
            errors.push(error);
            reduced_times.push(reduced_s);
            if let (false, Some(frame), Some(file)) = (from_file, fresh, &file) {
                kept.push(frame);
                if save_due(kept.len() - reused, kept.len(), frames) {
                    file.save(model.faces(), &kept)?;
                }
            }
            progress(Progress::Frame);
        }
        let report = SequenceReport { errors };
        progress(Progress::SequenceDone(which, &report, &groups));
        std::fs::write(&csv, rows.join("\n") + "\n").with_context(|| format!("writing {}", csv.display()))?;
        sequences.push(report);
    }
    // The corners of the design space, solved in full and reduced like frames.
    let mut corners = Vec::new();
    let mut corner_rows = vec![csv_header(&scene.names(), &groups)];
    for p in super::train::box_corners(&ranges) {
        let full = FullFrame::solve(spec, &p, options.full_form_factors)?;
        let mesh = spec.mesh(&p)?;
        let (b, _, estimate) = model.evaluate_estimated(&mesh)?;
        let error = frame_error(&b, &full, &groups, model, estimate);
        corner_rows.push(csv_fields(&p, &error));
        corners.push((p, error));
    }
    // Random configurations from a seed unrelated to training.
    if options.random > crate::reduce::effectivity::MAX_RANDOM {
        bail!(
            "--random {}: at most {} configurations",
            options.random,
            crate::reduce::effectivity::MAX_RANDOM
        );
    }
    let mut random = Vec::with_capacity(options.random);
    let mut random_rows = vec![csv_header(&scene.names(), &groups)];
    let random_csv = options.out.join("random.csv");
    if options.random > 0 {
        progress(Progress::Sequence(
            options.frames.len(),
            options.random,
            "random configurations (full and reduced)",
        ));
    }
    for p in crate::reduce::effectivity::random_parameters(&ranges, options.random, options.random_seed) {
        let full = FullFrame::solve(spec, &p, options.full_form_factors)?;
        let mesh = spec.mesh(&p)?;
        let (b, _, estimate) = model.evaluate_estimated(&mesh)?;
        let error = frame_error(&b, &full, &groups, model, estimate);
        random_rows.push(csv_fields(&p, &error));
        random.push((p, error));
        progress(Progress::Frame);
    }
    if options.random > 0 {
        std::fs::write(&random_csv, random_rows.join("\n") + "\n")
            .with_context(|| format!("writing {}", random_csv.display()))?;
    }
    let corners_csv = options.out.join("corners.csv");
    std::fs::write(&corners_csv, corner_rows.join("\n") + "\n")
        .with_context(|| format!("writing {}", corners_csv.display()))?;
    let plot = options.out.join("compare.png");
    let mut lines: Vec<crate::plot::Line> = Vec::new();
    for (label, pick) in [("receiving surfaces", Some(0)), ("all faces, emitters included", None)] {
        for (which, s) in sequences.iter().enumerate() {
            lines.push(crate::plot::Line {
                label: format!("sequence {} ({} frames), {label}", which + 1, s.errors.len()),
                points: s
                    .errors
                    .iter()
                    .enumerate()
                    .map(|(f, e)| (f as f64, pick.map_or(e.all, |k| e.groups[k])))
                    .collect(),
            });
        }
    }
    crate::plot::line_chart(
        &plot,
        &format!("Reduced against full radiosity: {}", scene_path.display()),
        "frame of the animation sequence",
        "relative error, area-weighted (%)",
        &lines,
        &|v| format!("{:.2} %", 100.0 * v),
    )?;
    let full_solved = full_times.len();
    Ok(CompareReport {
        groups,
        sequences,
        corners,
        random,
        full_median_s: crate::bench::median_f64(&mut full_times),
        full_solved,
        reduced_median_s: crate::bench::median_f64(&mut reduced_times),
        stage_seconds: stages,
        csv,
        plot,
    })
}

/// `compare --full-only`: solves every frame of the sequences not yet kept in `dir` and keeps
/// it (saved as [`save_due`] says), without a model — the full frames depend on the scene
/// alone, so they can be made before or while a model trains.
pub fn keep_full_frames(
    scene: &AnyScene,
    scene_path: &Path,
    frames: &[usize],
    dir: &Path,
    method: super::near_field::FormFactorMethod,
    progress: &mut dyn FnMut(Progress),
) -> Result<Vec<PathBuf>> {
    check_frames(frames)?;
    let spec = scene.space();
    let lighting = frames_key(spec.lights().mode, method);
    let ranges = spec.ranges();
    let mut files = Vec::new();
    for (which, &count) in frames.iter().enumerate() {
        let params: Vec<Vec<f64>> = (0..count).map(|f| sequence(&ranges, which % 2, f, count)).collect();
        let Some(first) = params.first() else { continue };
        let faces = spec.mesh(first)?.len();
        let file = FullFramesFile::new(dir, scene_path, &lighting, which, count)?;
        let mut kept = file.load_or_none(faces, &params);
        let reused = kept.len();
        let label = format!("sequence {} (full frames; {reused} kept)", which + 1);
        progress(Progress::Sequence(which, count, &label));
        for _ in 0..reused {
            progress(Progress::Frame);
        }
        for p in &params[reused..] {
            kept.push(FullFrame::solve(spec, p, method)?);
            if save_due(kept.len() - reused, kept.len(), count) {
                file.save(faces, &kept)?;
            }
            progress(Progress::Frame);
        }
        files.push(file.path().to_path_buf());
    }
    Ok(files)
}
