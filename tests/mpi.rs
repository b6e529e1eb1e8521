//! The trainings over real MPI ranks (`make test-mpi`: the `mpi` feature, OpenMPI's `mpirun`):
//! `mpirun --oversubscribe -n 1/2/4 galerkin radiosity train` on the small radiosity scene and
//! `galerkin fluid train` on two small tunnel runs, each against the same command run without
//! MPI — reduced tensors to 1e-8 (radiosity) and 1e-10 (fluid) of their largest entry (the
//! threads-as-ranks tests, `tests/ranks.rs`, say why) — and a failing command stopping every
//! rank with its message. Every `mpirun` has a hard timeout.
#![cfg(feature = "mpi")]

mod common;

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use galerkin::fluid::reduced::ReducedFluidModel;
use galerkin::radiosity::reduced::ReducedRadiosity;

use common::models::compare_models;
use common::tunnel::tunnel_run;

const BIN: &str = env!("CARGO_BIN_EXE_galerkin");

/// Longest an `mpirun` may take before the test kills it and fails.
const TIMEOUT: Duration = Duration::from_secs(300);

/// Runs `galerkin ARGS` under `mpirun -n ranks` (or directly, `ranks == 0`), one rayon thread
/// per rank (the ranks share this machine's cores), killed after [`TIMEOUT`].
fn galerkin(ranks: usize, args: &[&str]) -> Output {
    let mut cmd = if ranks == 0 {
        Command::new(BIN)
    } else {
        let mut c = Command::new("mpirun");
        c.args(["--oversubscribe", "--mca", "btl_vader_single_copy_mechanism", "none"]);
        c.args(["-n", &ranks.to_string(), "-x", "RAYON_NUM_THREADS=1", BIN]);
        c
    };
    cmd.args(args)
        .env("OMPI_ALLOW_RUN_AS_ROOT", "1")
        .env("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("mpirun starts (make test-mpi installs OpenMPI)");
    let start = Instant::now();
    loop {
        if child.try_wait().expect("wait").is_some() {
            return child.wait_with_output().expect("output");
        }
        if start.elapsed() > TIMEOUT {
            let _ = child.kill();
            panic!("galerkin {args:?} on {ranks} ranks did not finish in {TIMEOUT:?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn ok(out: &Output, what: &str) -> String {
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{what}: {}\n{stdout}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn radiosity_training_over_mpi_ranks_matches_one_process() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let scene = scene.to_str().expect("utf-8 path");
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name).to_string_lossy().into_owned();
    let train = |ranks: usize, to: &str| {
        galerkin(ranks, &["radiosity", "train", scene, "--samples", "10", "--out", to])
    };
    ok(&train(0, &out("alone")), "one process");
    let alone = ReducedRadiosity::load(Path::new(&out("alone"))).unwrap();
    for ranks in [1, 2, 4] {
        let to = out(&format!("ranks-{ranks}"));
        let stdout = ok(&train(ranks, &to), &format!("{ranks} ranks"));
        // Results are printed by rank 0 only.
        assert_eq!(stdout.matches("radiosity train:").count(), 1, "{stdout}");
        let model = ReducedRadiosity::load(Path::new(&to)).unwrap();
        let worst = compare_models(model.model(), alone.model()).worst;
        assert!(worst < 1e-8, "{ranks} ranks: reduced tensors differ by {worst:e}");
    }
}

#[test]
fn fluid_training_over_mpi_ranks_matches_one_process() {
    let dir = tempfile::tempdir().unwrap();
    let runs = [tunnel_run(dir.path(), 0.6, 20), tunnel_run(dir.path(), 1.4, 20)];
    let runs: Vec<String> = runs.iter().map(|r| r.to_string_lossy().into_owned()).collect();
    let model_path = |name: &str| dir.path().join(format!("{name}.safetensors"));
    let train = |ranks: usize, to: &Path| {
        let to = to.to_string_lossy().into_owned();
        let mut args = vec!["fluid", "train"];
        args.extend(runs.iter().map(String::as_str));
        args.extend(["--out", to.as_str()]);
        galerkin(ranks, &args)
    };
    ok(&train(0, &model_path("alone")), "one process");
    let alone = ReducedFluidModel::load(&model_path("alone")).unwrap();
    for ranks in [2, 4] {
        let to = model_path(&format!("ranks-{ranks}"));
        ok(&train(ranks, &to), &format!("{ranks} ranks"));
        let model = ReducedFluidModel::load(&to).unwrap();
        let a = compare_models(&model.core, &alone.core);
        assert!(a.worst < 1e-10 && a.constraint < 1e-6, "{ranks} ranks: reduced tensors differ by {a:?}");
    }
}

#[test]
fn a_scene_trains_over_mpi_ranks_each_simulating_its_runs() {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/fluid/cavity_small.toml");
    let dir = tempfile::tempdir().unwrap();
    let work = dir.path().join("work");
    let path = |p: &Path| p.to_string_lossy().into_owned();
    let (scene, work_s) = (path(&scene), path(&work));
    let train = |ranks: usize, model: &Path| {
        let model = path(model);
        let args = [
            "fluid",
            "train-scene",
            &scene,
            "--runs",
            "0,3",
            "--frames",
            "6",
            "--work",
            &work_s,
            "--out",
            &model,
        ];
        galerkin(ranks, &args)
    };
    let stdout = ok(&train(2, &dir.path().join("ranks.safetensors")), "2 ranks");
    assert_eq!(stdout.matches("trained in").count(), 1, "rank 0 alone prints: {stdout}");
    assert!(work.join("run-00").is_dir() && work.join("run-03").is_dir());
    // One process on the same runs (read back from the work directory, not simulated again):
    // the bases and tensors again.
    std::fs::remove_file(work.join("bases.safetensors")).unwrap();
    ok(&train(0, &dir.path().join("one.safetensors")), "one process");
    let ranks = ReducedFluidModel::load(&dir.path().join("ranks.safetensors")).unwrap();
    let one = ReducedFluidModel::load(&dir.path().join("one.safetensors")).unwrap();
    let a = compare_models(&ranks.core, &one.core);
    assert!(a.worst < 1e-10 && a.constraint < 1e-6, "{a:?}");
}

#[test]
fn a_failing_command_stops_every_rank_with_its_message() {
    let out = galerkin(
        2,
        &["radiosity", "train", "/nonexistent/scene.toml", "--samples", "4", "--out", "/tmp/never"],
    );
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("/nonexistent/scene.toml"), "{stderr}");
    assert!(stderr.contains("stopping every rank"), "{stderr}");
    // Commands that do not run over ranks are refused under mpirun, before any work.
    let out = galerkin(2, &["info"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr)
        .contains("only `radiosity train`, `fluid train` and `fluid train-scene`"));
}
