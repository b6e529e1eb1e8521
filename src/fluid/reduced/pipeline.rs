//! From a scene to a reduced model in one resumable command (seed 000 §6.1, §7.2): simulate the
//! scene's training runs in the full space, build the bases, premultiply the tensors, write the
//! model. The cavity has 14 training runs (its compressions, [`crate::fluid::cavity`]); every
//! other scene one (the bird's whole animation).
//!
//! Everything it makes goes into a work directory, so a stopped training resumes where it
//! stopped: a run whose snapshot directory already holds all its frames is not simulated again
//! (one that holds fewer — the process stopped mid-run — is simulated again from its start),
//! and bases built from the same runs and sizes are read back instead of rebuilt. The work
//! directory remembers the scene and frames it was made for (`work.json`) and refuses another.
//! Nothing of size cells × frames is held in memory: runs stream to disk frame by frame, and
//! the bases and trajectories stream from it ([`super::training`]).
//!
//! A cavity's model also gets its motion model ([`super::cavity_motion`]), so it can be
//! driven by compressions at run time.
//!
//! Each stage reports its wall time and the process's peak memory during it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::fluid::cavity::TRAINING_RUNS;
use crate::fluid::run::simulate_run;
use crate::fluid::scene::{FluidScene, Motion};
use crate::fluid::snapshots::SnapshotReader;
use crate::fluid::FluidError;
use crate::process::{peak_memory_mb, reset_peak_memory};
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

/// What a work directory was made for.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct WorkKey {
    scene: PathBuf,
    /// The scene file's text.
    scene_text: String,
    frames: usize,
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
    let runs = runs_of(&scene, options.runs.as_deref())?;
    drop(scene);
    let work = &options.work;
    let waiting = |e: RanksError| FluidError::State(format!("waiting for the other ranks: {e}"));
    // Rank 0 checks or writes the work directory's key; the others wait for it.
    if ranks.is_root() {
        check_work_key(scene_path, &scene_text, frames, work)?;
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
        let stage = Stage::start();
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
        on_event(stage.done(format!("run {run}"), done));
    }
    ranks.barrier().map_err(waiting)?;

    // The bases, kept in the work directory for a training that stops after them.
    let set = TrainingSet::open(&dirs)?;
    let bases_path = work.join("bases.safetensors");
    let bases_key = format!("{:?} {:?} {frames}", runs, options.sizes);
    let stage = Stage::start();
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
    on_event(stage.done("bases".into(), resumed));

    // The trajectories and the premultiplied tensors: the model.
    let stage = Stage::start();
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
    if ranks.is_root() {
        model.save(model_path)?;
    }
    on_event(stage.done("tensors".into(), false));
    Ok(model)
}

/// Refuses a work directory that holds the training of another scene or frame count, and
/// marks a new one as this training's.
fn check_work_key(scene_path: &Path, scene_text: &str, frames: usize, work: &Path) -> Result<(), FluidError> {
    std::fs::create_dir_all(work).map_err(|e| io(work, e))?;
    let key = WorkKey { scene: scene_path.to_path_buf(), scene_text: scene_text.to_string(), frames };
    let key_path = work.join("work.json");
    match std::fs::read_to_string(&key_path) {
        Ok(text) => {
            let old: WorkKey = serde_json::from_str(&text).map_err(|e| io(&key_path, e))?;
            if old.scene_text != key.scene_text || old.frames != key.frames {
                return Err(io(
                    work,
                    format!(
                        "holds the training of {} with {} frames per run; give another --work or remove it",
                        old.scene.display(),
                        old.frames
                    ),
                ));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let text = serde_json::to_string_pretty(&key).map_err(|e| io(&key_path, e))?;
            std::fs::write(&key_path, text).map_err(|e| io(&key_path, e))?;
        }
        Err(e) => return Err(io(&key_path, e)),
    }
    Ok(())
}

/// A stage's start: its clock, and the peak memory reset.
struct Stage(Instant);

impl Stage {
    fn start() -> Self {
        reset_peak_memory();
        Self(Instant::now())
    }

    fn done(self, stage: String, resumed: bool) -> TrainingEvent {
        TrainingEvent::StageDone {
            stage,
            seconds: self.0.elapsed().as_secs_f64(),
            peak_mb: peak_memory_mb(),
            resumed,
        }
    }
}
