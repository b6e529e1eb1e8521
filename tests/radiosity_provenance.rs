//! A reduced radiosity model records where it came from (issue 53; `reduce::provenance`): the
//! scene file and its content's SHA-256, the training options and samples, the engine. The
//! commands that use a model need no scene argument, and a scene that changed since training is
//! refused, naming the stored and the current hash.

use std::process::Command;

use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::reduced::ReducedRadiosity;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, TrainOptions};
use galerkin::reduce::provenance::{samples_sha256, ENGINE};

const SMALL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");

#[test]
fn a_model_names_its_scene_and_refuses_a_changed_one() {
    let dir = tempfile::Builder::new().prefix("galerkin-provenance-").tempdir().unwrap();
    let scene_path = dir.path().join("rooms.toml");
    std::fs::copy(SMALL, &scene_path).unwrap();
    let scene = AnyScene::load(&scene_path, None).unwrap();
    let space = scene.space();
    // A deliberately small model (6 samples, capped bases).
    let params = sample_parameters(&space.ranges(), &space.defaults(), 6, 5);
    let options =
        TrainOptions { samples: 6, energy: 0.99, cap: 4, radiosity_cap: 8, ..TrainOptions::default() };
    let configurations = solve_configurations(space, &params, &options, &|_| {}).unwrap();
    let (model, _) = train(space, &configurations, &options, &|_, _, _| {}).unwrap();
    let provenance = scene.provenance(&scene_path, format!("{options:?}"), &params).unwrap();
    let model_dir = dir.path().join("model");
    model.clone().with_provenance(provenance.clone()).save(&model_dir).unwrap();

    let back = ReducedRadiosity::load(&model_dir).unwrap();
    let p = back.provenance().expect("recorded");
    assert_eq!(p, &provenance);
    assert_eq!(
        (p.samples, p.samples_sha256.as_str(), p.engine.as_str()),
        (6, samples_sha256(&params).as_str(), ENGINE)
    );
    assert!(p.options.contains("samples: 6"), "{}", p.options);
    // No scene given: the one recorded; the same scene given: accepted.
    assert_eq!(back.scene_file(None).unwrap(), std::path::absolute(&scene_path).unwrap());
    assert_eq!(back.scene_file(Some(&scene_path)).unwrap(), scene_path);

    // A model another engine version trained: refused at load, naming both versions and the file.
    let mut foreign = provenance.clone();
    foreign.engine = "galerkin 0.0.9".into();
    let foreign_dir = dir.path().join("foreign");
    model.clone().with_provenance(foreign).save(&foreign_dir).unwrap();
    let e = ReducedRadiosity::load(&foreign_dir).expect_err("refused").to_string();
    assert!(e.contains("galerkin 0.0.9") && e.contains(ENGINE) && e.contains("foreign"), "{e}");

    // `render --model DIR` without a scene draws the recorded scene's configuration.
    let picture = dir.path().join("reduced.png");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["radiosity", "render", "--model"])
        .arg(&model_dir)
        .args(["--size", "32x24", "--allow-untrusted", "--out"])
        .arg(&picture)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(picture.exists());
    assert!(String::from_utf8_lossy(&out.stdout).contains("estimated error"));

    // The scene edited: refused, naming the file and both hashes, by the library and the CLI.
    let text = std::fs::read_to_string(&scene_path).unwrap();
    std::fs::write(&scene_path, text.replace("window_sill = 0.9", "window_sill = 0.95")).unwrap();
    let now = AnyScene::load(&scene_path, None).unwrap().content_sha256(&scene_path).unwrap();
    assert_ne!(now, provenance.scene_sha256);
    let e = back.scene_file(None).unwrap_err().to_string();
    assert!(e.contains(&provenance.scene_sha256) && e.contains(&now) && e.contains("rooms.toml"), "{e}");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["radiosity", "compare", "--model"])
        .arg(&model_dir)
        .args(["--frames", "1,1", "--out"])
        .arg(dir.path().join("cmp"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("changed since the model was trained") && err.contains(&now), "{err}");
    assert!(!dir.path().join("cmp").join("compare.csv").exists(), "nothing compared");
}
