//! The reduced radiosity trains through the reduction workflow (issue 53 item 1;
//! `reduce::reductor`, `radiosity::train_stages`): a training stopped after any stage — or
//! killed part way through its full solves — and run again resumes without redoing what was
//! kept, and writes the model a straight training writes, bit for bit. A work directory made
//! for other options is refused, naming both trainings.

use std::path::Path;
use std::sync::Mutex;

use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::train::TrainOptions;
use galerkin::radiosity::train_stages::{train_and_save, TrainedScene, WorkOptions};
use galerkin::radiosity::RadiosityError;
use galerkin::reduce::reductor::StageReport;
use galerkin::reduce::SingleRank;

const SMALL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");

const STAGES: [&str; 6] = ["samples", "solves", "bases", "tensors", "correction", "model"];

/// A deliberately small model (12 samples, capped bases), trained into `out` with `work`;
/// returns the result, the stages reported and the most full solves one "solve" progress
/// call announced.
fn run(
    out: &Path,
    work: &WorkOptions,
    samples: usize,
) -> (Result<TrainedScene, RadiosityError>, Vec<StageReport>, u64) {
    let scene = AnyScene::load(Path::new(SMALL), None).unwrap();
    let options =
        TrainOptions { samples, energy: 0.99, cap: 6, radiosity_cap: 12, ..TrainOptions::default() };
    let mut stages = Vec::new();
    let solves = Mutex::new(0u64);
    let result = train_and_save(
        scene.space(),
        &options,
        out,
        Some((Path::new(SMALL), "a fixed hash".to_string())),
        work,
        &|stage, _, total| {
            if stage == "solve" {
                let mut s = solves.lock().unwrap();
                *s = (*s).max(total);
            }
        },
        &mut |s| stages.push(s.clone()),
        &SingleRank,
    );
    let solves = *solves.lock().unwrap();
    (result, stages, solves)
}

fn model_bytes(dir: &Path) -> Vec<Vec<u8>> {
    ["model.safetensors", "visibility.safetensors"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect()
}

#[test]
fn a_stopped_training_resumes_to_the_same_model() {
    let dir = tempfile::Builder::new().prefix("galerkin-reductor-").tempdir().unwrap();
    let straight = dir.path().join("straight");
    let (t, stages, solves) = run(&straight, &WorkOptions::default(), 12);
    t.unwrap();
    assert_eq!(stages.iter().map(|s| s.stage.as_str()).collect::<Vec<_>>(), STAGES);
    assert!(stages.iter().all(|s| !s.resumed && s.seconds >= 0.0 && s.line().contains(&s.stage)));
    assert_eq!(solves, 12);
    assert!(!straight.join("work").exists(), "the work directory is removed once the model is written");
    let expected = model_bytes(&straight);

    for (i, stop) in STAGES[..5].iter().enumerate() {
        let out = dir.path().join(format!("stopped-after-{stop}"));
        let stopping = WorkOptions { stop_after: Some(stop.to_string()), ..WorkOptions::default() };
        let (t, stages, _) = run(&out, &stopping, 12);
        let e = t.err().expect("stopped").to_string();
        assert!(e.contains(&format!("stopped after stage `{stop}`")), "{e}");
        assert_eq!(stages.len(), i + 1);
        assert!(!out.join("model.safetensors").exists(), "no model before the last stage");

        let (t, stages, solves) = run(&out, &WorkOptions::default(), 12);
        t.unwrap();
        let resumed: Vec<bool> = stages.iter().map(|s| s.resumed).collect();
        let want: Vec<bool> = (0..STAGES.len()).map(|k| k <= i).collect();
        assert_eq!(resumed, want, "after a stop at {stop}");
        assert_eq!(solves, if i >= 1 { 0 } else { 12 }, "full solves redone after a stop at {stop}");
        assert_eq!(model_bytes(&out), expected, "resumed after {stop}: the model differs");
    }

    // Killed part way through the solves: the stage is not finished, 5 of its 12 solves kept.
    let out = dir.path().join("killed-in-solves");
    let keep = WorkOptions { stop_after: Some("solves".into()), keep: true, ..WorkOptions::default() };
    let _ = run(&out, &keep, 12);
    let solves_dir = out.join("work").join("solves");
    std::fs::remove_file(solves_dir.join("done")).unwrap();
    for k in [0, 3, 4, 7, 8, 9, 11] {
        std::fs::remove_file(solves_dir.join(format!("{k:06}.bin"))).unwrap();
    }
    let keep_going = WorkOptions { keep: true, ..WorkOptions::default() };
    let (t, stages, solves) = run(&out, &keep_going, 12);
    t.unwrap();
    assert_eq!(solves, 7, "only the solves not kept are redone");
    assert!(stages[0].resumed && !stages[1].resumed);
    assert_eq!(model_bytes(&out), expected, "resumed in the solves: the model differs");
    assert!(out.join("work").join("work.json").exists(), "--keep-work keeps it");

    // Other options with the same work directory: refused, naming both.
    let (t, _, _) = run(&out, &keep_going, 13);
    let e = t.err().expect("refused").to_string();
    assert!(
        e.contains("12 samples") && e.contains("13 samples") && e.contains("another work directory"),
        "{e}"
    );
}
