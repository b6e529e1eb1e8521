//! `fluid::reduced::train_scene` (`galerkin fluid train-scene`): a scene to a reduced model in
//! one command that resumes — finished runs and bases are read back from the work directory,
//! an interrupted run is simulated again, and the resumed training gives the same model (every
//! basis, trajectory and tensor equal); a work directory of another scene is refused; stages report their time and peak
//! memory. On the small cavity, two of its training runs, a few frames.

use std::path::Path;

use galerkin::fluid::reduced::{train_scene, BasisSizes, ReducedFluidModel, SceneTraining, TrainingEvent};
use galerkin::fluid::snapshots::SnapshotMeta;

const SCENE: &str = "scenes/fluid/cavity_small.toml";

fn options(work: &Path) -> SceneTraining {
    SceneTraining {
        sizes: BasisSizes { energy: 0.9999, m_f: Some(8), m_u: Some(12), m_g: Some(4), m_h: Some(6) },
        frames: Some(6),
        runs: Some(vec![0, 3]),
        work: work.to_path_buf(),
    }
}

/// Trains and returns the model and the stages reported (name, resumed).
fn train(work: &Path, model: &Path) -> (ReducedFluidModel, Vec<(String, bool)>, usize) {
    let mut stages = Vec::new();
    let mut frames = 0;
    let m = train_scene(Path::new(SCENE), model, &options(work), &mut |e| match e {
        TrainingEvent::StageDone { stage, seconds, resumed, .. } => {
            assert!(seconds >= 0.0);
            stages.push((stage, resumed));
        }
        TrainingEvent::Frame(_) => frames += 1,
        _ => {}
    })
    .expect("training");
    (m, stages, frames)
}

#[test]
fn a_scene_trains_in_one_command_and_resumes_where_it_stopped() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (work, model_path) = (dir.path().join("work"), dir.path().join("cavity.safetensors"));
    let (first, stages, frames) = train(&work, &model_path);
    assert_eq!(frames, 12, "two runs of six frames simulated");
    let names: Vec<&str> = stages.iter().map(|(s, _)| s.as_str()).collect();
    assert_eq!(names, ["run 0", "run 3", "bases", "tensors"]);
    assert!(stages.iter().all(|(_, resumed)| !resumed));
    assert_eq!(first.trajectories.len(), 2);
    assert!((2..=4).contains(&first.dim_of("g")), "m_g within its cap: {}", first.dim_of("g"));

    // Stop run 3 halfway (its header says 4 of 7 frames) and lose the model: the training
    // simulates run 3 again, reads run 0 and the bases back, and writes the same model.
    let header = work.join("run-03").join("snapshots.json");
    let mut meta: SnapshotMeta = serde_json::from_str(&std::fs::read_to_string(&header).unwrap()).unwrap();
    meta.frames = 4;
    std::fs::write(&header, serde_json::to_string(&meta).unwrap()).unwrap();
    std::fs::remove_file(&model_path).unwrap();
    let (second, stages, frames) = train(&work, &model_path);
    assert_eq!(frames, 6, "only run 3 simulated again");
    assert_eq!(
        stages,
        [("run 0".into(), true), ("run 3".into(), false), ("bases".into(), true), ("tensors".into(), false)]
    );
    // The same bases (read back bit for bit), the same re-simulated run, the same model.
    assert!(model_path.exists(), "the model is written again");
    for name in ["u", "f", "g", "h", "d"] {
        assert_eq!(first.basis(name).map(|b| b.matrix()), second.basis(name).map(|b| b.matrix()), "B_{name}");
    }
    assert_eq!(first.trajectories, second.trajectories);
    for ((name, _, t), (_, _, other)) in first.core.tensors().zip(second.core.tensors()) {
        assert_eq!(t, other, "tensor {name}");
    }

    // Other sizes rebuild the bases (the kept ones were built for the first sizes).
    let mut other = options(&work);
    other.sizes.m_u = Some(10);
    let mut resumed_bases = None;
    train_scene(Path::new(SCENE), &model_path, &other, &mut |e| {
        if let TrainingEvent::StageDone { stage, resumed, .. } = e {
            if stage == "bases" {
                resumed_bases = Some(resumed);
            }
        }
    })
    .expect("training with other sizes");
    assert_eq!(resumed_bases, Some(false));
}

#[test]
fn a_work_directory_of_another_scene_or_bad_runs_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let work = dir.path().join("work");
    let model = dir.path().join("m.safetensors");
    let mut opts = options(&work);
    opts.runs = Some(vec![0]);
    opts.frames = Some(2);
    opts.sizes = BasisSizes::default();
    train_scene(Path::new(SCENE), &model, &opts, &mut |_| {}).expect("a first training");
    // The same work directory for more frames per run: refused, naming it.
    opts.frames = Some(3);
    let e = train_scene(Path::new(SCENE), &model, &opts, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("work") && e.contains("2 frames per run"), "{e}");
    // Runs the cavity does not have, and runs of a scene that has one.
    let mut bad = options(&dir.path().join("other"));
    bad.runs = Some(vec![14]);
    let e = train_scene(Path::new(SCENE), &model, &bad, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("run 14"), "{e}");
    bad.runs = Some(vec![1]);
    let tunnel = Path::new("scenes/fluid/tunnel_small.toml");
    let e = train_scene(tunnel, &model, &bad, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("--runs applies to the cavity"), "{e}");
}
