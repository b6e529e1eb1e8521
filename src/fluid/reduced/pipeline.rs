//! From a scene to a reduced model in one resumable command (seed 000 §6.1, §7.2): simulate the
//! scene's training runs in the full space, build the bases, premultiply the tensors, write the
//! model. The cavity has 14 training runs (its compressions, [`crate::fluid::cavity`]); every
//! other scene one (the bird's whole animation).
//!
//! Everything it makes goes into a work directory, so a stopped training resumes where it
//! stopped: a run whose snapshot directory already holds all its frames is not simulated again
//! (one that holds fewer — the process stopped mid-run — is simulated again from its start),
//! and bases built from the same runs and sizes are read back instead of rebuilt. The work
//! directory remembers the scene and frames it was made for (`work.json`, the reduction
//! workflow's key, [`crate::reduce::reductor`]) and refuses another.
//! Nothing of size cells × frames is held in memory: runs stream to disk frame by frame, and
//! the bases and trajectories stream from it ([`super::training`]).
//!
//! A cavity's model also gets its motion model ([`super::cavity_motion`]), so it can be
//! driven by compressions at run time.
//!
//! Each stage reports its wall time and the process's peak memory during it
//! ([`crate::reduce::reductor::StageReport`]).

use std::path::{Path, PathBuf};

use crate::fluid::cavity::TRAINING_RUNS;
use crate::fluid::run::simulate_run;
use crate::fluid::scene::{FluidScene, Motion};
use crate::fluid::snapshots::SnapshotReader;
use crate::fluid::FluidError;
use crate::reduce::reductor::{fingerprint, Reductor, StageClock, StageReport};
use crate::reduce::{Communicator, RanksError, SingleRank};

use super::bases::{BasisSizes, FluidBases};
use super::cavity_motion::CavityMotion;
use super::model::ReducedFluidModel;
use super::training::TrainingSet;

/// What to train and where to keep the work.
#[derive(Clone, Debug)]
pub struct SceneTraining {
    /// Basis sizes (energy threshold and caps).
    pub sizes: BasisSizes,
    /// Frames per run (default: the scene's).
    pub frames: Option<usize>,
    /// The cavity's training runs to use (default: all 14); other scenes have one run.
    pub runs: Option<Vec<usize>>,
    /// The work directory (snapshot runs, bases).
    pub work: PathBuf,
}

/// What a training reports as it goes.
#[derive(Clone, Debug, PartialEq)]
pub enum TrainingEvent {
    /// A run starts: its number, how many runs, and its frames.
    RunStarted {
        /// The training run (the cavity's 0–13; 0 otherwise).
        run: usize,
        /// Its position among the runs trained, from 0.
        index: usize,
        /// Runs trained.
        of: usize,
        /// Frames it simulates.
        frames: usize,
    },
    /// A frame of the current run was simulated.
    Frame(usize),
    /// A stage finished: its name, wall seconds, the peak memory during it (MB, if known) and
    /// whether its result was already in the work directory.
    StageDone {
        /// `run N`, `bases`, `tensors`.
        stage: String,
        /// Wall time.
        seconds: f64,
        /// Peak resident memory during the stage.
        peak_mb: Option<f64>,
        /// Taken from the work directory, not computed.
        resumed: bool,
    },
    /// A part of the bases or tensors started (`f`, `u`, `g`, `h`, `d`, `trajectories`,
    /// `premultiply`).
    Part(String),
}

/// The training runs of `scene`: the cavity's asked-for or all 14; otherwise the one.
fn runs_of(scene: &FluidScene, asked: Option<&[usize]>) -> Result<Vec<usize>, FluidError> {
    match (&scene.motion, asked) {
        (Motion::Cavity { .. }, None) => Ok((0..TRAINING_RUNS).collect()),
        (Motion::Cavity { .. }, Some(r)) => {
            if let Some(bad) = r.iter().find(|&&k| k >= TRAINING_RUNS) {
                return Err(FluidError::State(format!(
                    "run {bad}: the cavity's training runs are 0 to {}",
                    TRAINING_RUNS - 1
                )));
            }
            if r.is_empty() {
                return Err(FluidError::State("no training runs asked for".into()));
            }
            Ok(r.to_vec())
        }
        (_, Some(r)) if r != [0] => Err(FluidError::State(
            "--runs applies to the cavity; this scene has one training run (its motion)".into(),
        )),
        _ => Ok(vec![0]),
    }
}

fn io(path: &Path, e: impl std::fmt::Display) -> FluidError {
    FluidError::State(format!("{}: {e}", path.display()))
}

/// Trains a reduced model of the scene at `scene_path` and writes it to `model_path` (see the
/// module docs); `on_event` hears every run, frame and stage. One rank:
/// [`train_scene_across`].
pub fn train_scene(
    scene_path: &Path,
    model_path: &Path,
    options: &SceneTraining,
    on_event: &mut dyn FnMut(TrainingEvent),
) -> Result<ReducedFluidModel, FluidError> {
    train_scene_across(scene_path, model_path, options, on_event, &SingleRank)
}

/// [`train_scene`] shared over `ranks` (`mpirun -n N galerkin fluid train-scene …`): each rank
/// simulates its contiguous share of the training runs into the work directory (each run its
/// own snapshot directory), then the bases and tensors are built over the ranks
/// ([`ReducedFluidModel::fit_across`]'s sharding). Rank 0 alone writes the work directory's
/// key, the bases and the model; every rank returns the same model, within rounding of one
/// rank's. Resuming works as on one rank, whatever the number of ranks of the stopped run.
pub fn train_scene_across(
    scene_path: &Path,
    model_path: &Path,
    options: &SceneTraining,
    on_event: &mut dyn FnMut(TrainingEvent),
    ranks: &dyn Communicator,
) -> Result<ReducedFluidModel, FluidError> {
    let scene_text = std::fs::read_to_string(scene_path).map_err(|e| io(scene_path, e))?;
    let scene = FluidScene::parse(&scene_text, scene_path)?;
    let frames = options.frames.unwrap_or(scene.frames);
    if frames == 0 {
        return Err(FluidError::State("0 frames: a training run needs at least one".into()));
    }
    scene.check_frames(frames)?;
    let runs = runs_of(&scene, options.runs.as_deref())?;
    drop(scene);
    let work = &options.work;
    let waiting = |e: RanksError| FluidError::State(format!("waiting for the other ranks: {e}"));
    // Rank 0 checks or writes the work directory's key; the others wait for it.
    if ranks.is_root() {
        let made_for = format!("{} with {frames} frames per run", scene_path.display());
        let key = fingerprint(&[scene_text.as_bytes(), &(frames as u64).to_le_bytes()]);
        Reductor::open(work, &made_for, &key, true, |_: &StageReport| {})
            .map_err(|e| FluidError::State(e.to_string()))?;
    }
    ranks.barrier().map_err(waiting)?;

    // The full-space runs, each into its own snapshot directory, each by the rank that owns it.
    let share = ranks.share(runs.len());
    let mut dirs = Vec::new();
    for (index, &run) in runs.iter().enumerate() {
        let dir = work.join(format!("run-{run:02}"));
        dirs.push(dir.clone());
        if !share.contains(&index) {
            continue;
        }
        let stage = StageClock::start();
        let done = SnapshotReader::open(&dir).is_ok_and(|r| r.meta().frames == frames + 1);
        if !done {
            on_event(TrainingEvent::RunStarted { run, index, of: runs.len(), frames });
            let mut scene = FluidScene::parse(&scene_text, scene_path)?;
            if matches!(scene.motion, Motion::Cavity { .. }) {
                scene.set_run(run)?;
            }
            scene.frames = frames;
            simulate_run(&mut scene, frames, &dir, true, &mut |k, _, _, _| {
                on_event(TrainingEvent::Frame(k))
            })?;
        }
        on_event(stage.done(&format!("run {run}"), done).into());
    }
    ranks.barrier().map_err(waiting)?;

    // The bases, kept in the work directory for a training that stops after them.
    let set = TrainingSet::open(&dirs)?;
    let bases_path = work.join("bases.safetensors");
    let bases_key = format!("{:?} {:?} {frames}", runs, options.sizes);
    let stage = StageClock::start();
    let kept = if bases_path.exists() { FluidBases::load(&bases_path, &bases_key)? } else { None };
    let resumed = kept.is_some();
    let bases = match kept {
        Some(b) => b,
        None => {
            let b = FluidBases::build(
                &set,
                &options.sizes,
                &mut |p| on_event(TrainingEvent::Part(p.into())),
                ranks,
            )?;
            if ranks.is_root() {
                b.save(&bases_path, &bases_key)?;
            }
            b
        }
    };
    on_event(stage.done("bases", resumed).into());

    // The trajectories and the premultiplied tensors: the model.
    let stage = StageClock::start();
    let mut model = ReducedFluidModel::train(
        &set,
        bases,
        &options.sizes,
        &mut |p| on_event(TrainingEvent::Part(p.into())),
        ranks,
    )?;
    // The cavity is driven at run time by its compressions: its reduced motion model.
    if let Motion::Cavity { cavity, .. } = &FluidScene::parse(&scene_text, scene_path)?.motion {
        let b_g = model.basis("g").ok_or_else(|| FluidError::State("the model has no basis g".into()))?;
        model.cavity = Some(CavityMotion::new(cavity, b_g));
    }
    // Its scene, so that `fluid compare` needs no --scene (the scene file's content hashed).
    let scene_sha256 = crate::reduce::provenance::files_sha256(&[scene_path]).map_err(FluidError::State)?;
    let runs_as_samples: Vec<Vec<f64>> = runs.iter().map(|&r| vec![r as f64]).collect();
    model.provenance.source = Some(crate::reduce::provenance::Provenance::new(
        scene_path,
        scene_sha256,
        format!("{frames} frames per run, runs {runs:?}, sizes {:?}", options.sizes),
        &runs_as_samples,
    ));
    if ranks.is_root() {
        model.save(model_path)?;
    }
    on_event(stage.done("tensors", false).into());
    Ok(model)
}

impl From<StageReport> for TrainingEvent {
    fn from(r: StageReport) -> Self {
        TrainingEvent::StageDone {
            stage: r.stage,
            seconds: r.seconds,
            peak_mb: r.peak_mb,
            resumed: r.resumed,
        }
    }
}
