//! `fluid::reduced::train_scene` (`galerkin fluid train-scene`): a scene to a reduced model in
//! one command that resumes — finished runs and bases are read back from the work directory,
//! an interrupted run is simulated again, and the resumed training gives the same model (every
//! basis, trajectory and tensor equal); a work directory of another scene is refused; stages report their time and peak
//! memory. On the small cavity, two of its training runs, a few frames.

use std::path::Path;

use galerkin::fluid::reduced::{
    run_driven, train_scene, BasisSizes, CompressionSchedule, ReducedFluid, ReducedFluidModel, SceneTraining,
    TrainingEvent,
};
use galerkin::fluid::snapshots::SnapshotMeta;

const SCENE: &str = "scenes/fluid/cavity_small.toml";

fn options(work: &Path) -> SceneTraining {
    SceneTraining {
        sizes: BasisSizes {
            energy: 0.9999,
            m_f: Some(8),
            m_u: Some(12),
            m_g: Some(4),
            m_h: Some(6),
            mid_step: false,
        },
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

#[test]
fn the_cavity_is_driven_by_any_compressions_exactly_as_its_full_deformation() {
    use galerkin::fluid::scene::{FluidScene, Motion};
    use galerkin::mesh::volume::enclosed_volume;
    let dir = tempfile::tempdir().expect("temp dir");
    let model_path = dir.path().join("cavity.safetensors");
    // Each small cavity compressed alone: the runs move all three and the centre, so B_g (kept
    // to 1 − 1e-12 of the energy) spans the map's five fields.
    let mut opts = options(&dir.path().join("work"));
    opts.runs = Some(vec![0, 1, 2]);
    opts.sizes = BasisSizes {
        energy: 1.0 - 1e-12,
        m_f: Some(6),
        m_u: Some(8),
        m_g: Some(5),
        m_h: Some(6),
        mid_step: false,
    };
    let model = train_scene(Path::new(SCENE), &model_path, &opts, &mut |_| {}).expect("training");
    let motion = model.cavity.clone().expect("a cavity model has its motion model");
    assert_eq!(model.dim_of("g"), 5, "B_g spans g₀, the three compressions and the inflation");
    assert_eq!(ReducedFluidModel::load(&model_path).unwrap().cavity, Some(motion.clone()));
    let scene = FluidScene::load(Path::new(SCENE)).unwrap();
    let Motion::Cavity { cavity, .. } = &scene.motion else { panic!("a cavity") };
    let b_g = model.basis("g").unwrap();
    // The volume cubic is the mesh's enclosed volume of the map's geometry.
    let fields = cavity.motion_fields();
    for c in [[1.0, 0.3, 0.0, 0.1, 0.02], [1.0, 0.0, 0.5, 0.2, 0.05], [0.7, -0.2, 0.1, 0.4, 0.3]] {
        let g: Vec<f64> = (0..fields[0].len()).map(|i| (0..5).map(|p| c[p] * fields[p][i]).sum()).collect();
        let want = enclosed_volume(&cavity.mesh, &cavity.topology, &g);
        let t = motion.volume.data();
        let got: f64 = (0..125).map(|n| t[n] * c[n / 25] * c[n / 5 % 5] * c[n % 5]).sum();
        assert!((got - want).abs() <= 1e-12 * want.abs(), "volume {got} vs {want}");
    }
    // Trained and untrained combinations — one cavity deep while another is half way, amounts
    // beyond the training's — against the full map with its own inflation.
    for a in [[0.3, 0.0, 0.0], [0.4, 0.0, 0.2], [0.2, 0.55, 0.1], [0.7, 0.7, 0.7]] {
        let lambda = motion.inflation(a).unwrap();
        let want_lambda = cavity.inflation_for(a);
        assert!((lambda - want_lambda).abs() < 1e-10, "{a:?}: λ {lambda} vs {want_lambda}");
        let g_full = cavity.mapped_for(a);
        let ghat = motion.geometry(a).unwrap();
        let projected = b_g.project(&g_full);
        let err = ghat.iter().zip(&projected).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        let scale = projected.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(err <= 1e-10 * scale, "{a:?}: ĝ off the projected full geometry by {err:e}");
        let lifted = b_g.lift(&ghat);
        let err = lifted.iter().zip(&g_full).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        assert!(err < 1e-9, "{a:?}: the lifted geometry is {err:e} off the full one");
        // … and the compressions are read back from ĝ (B_g resolves the four motions).
        let back = motion.compressions_of(&ghat).expect("m_g = 5 resolves the compressions");
        assert!((0..3).all(|i| (back[i] - a[i]).abs() < 1e-8), "{a:?} read back as {back:?}");
    }
    // What the model was trained on, read back from its trajectories: each run compresses
    // one cavity over the 6 frames of the training schedule.
    let mut want = [0.0f64; 3];
    for k in [0, 1, 2] {
        let amounts = galerkin::fluid::cavity::training_run(k).unwrap();
        for t in 0..=6 {
            let a = galerkin::fluid::cavity::Cavity::compression(amounts, t, 6);
            (0..3).for_each(|i| want[i] = want[i].max(a[i]));
        }
    }
    let trained = model.trained_compressions().expect("a cavity model");
    assert!((0..3).all(|i| (trained[i] - want[i]).abs() < 1e-8), "trained {trained:?}, runs made {want:?}");
    assert!(want.iter().all(|&x| x > 0.0) && model.warn_beyond_training(want).is_none());
    let beyond = [want[0] + 0.1, want[1], 0.0];
    let w = model.warn_beyond_training(beyond).expect("a warning beyond the training");
    assert!(w.contains("cavity 1") && !w.contains("cavity 2"), "{w}");
    // Driven at run time by a schedule no training run made (two cavities together, one
    // re-inflating while the other holds): each frame's ĝ is the motion model's, the boundary
    // constraint holds, the compression sets the fluid moving.
    let schedule: CompressionSchedule = "0=0/0/0,3=0.3/0/0.2,6=0/0/0.2".parse().unwrap();
    assert_eq!(schedule.at(0), [0.0; 3]);
    assert!((schedule.at(4)[0] - 0.2).abs() < 1e-15 && schedule.at(9) == [0.0, 0.0, 0.2]);
    let fluid = ReducedFluid::new(&model).unwrap();
    let run = run_driven(&model, &fluid, &schedule, 6, &mut |_| {}).expect("driven run");
    for (t, s) in run.states.iter().enumerate() {
        assert_eq!(s.g, motion.geometry(schedule.at(t)).unwrap(), "frame {t}");
    }
    // The boundary constraint holds as far as this small flux basis (6 modes) carries the new
    // motion's boundary flux: measured ≤ 1.3e-4 of ‖D̂_h ĥ‖ (exact for the replayed training
    // motions, tests/fluid_reduced.rs); 1e-3 allowed.
    for r in &run.reports {
        assert!(
            r.constraint_residual <= 1e-3 * r.constraint_target,
            "{} of {}",
            r.constraint_residual,
            r.constraint_target
        );
    }
    let last = run.states.last().unwrap();
    assert!(fluid.energy(&last.u, &last.g) > 0.0, "the compressions moved the fluid");
    for bad in ["0=0/0", "3=0/0/0,3=0.1/0/0", "0=0/1.5/0", "x=0/0/0"] {
        assert!(bad.parse::<CompressionSchedule>().is_err(), "{bad} accepted");
    }
    // Compressions a cavity cannot take are refused, naming it.
    for bad in [[1.0, 0.0, 0.0], [0.0, f64::NAN, 0.0], [0.0, 0.0, -0.1]] {
        let e = motion.geometry(bad).unwrap_err().to_string();
        assert!(e.contains("compression"), "{e}");
    }
}

#[test]
fn a_reduced_cavity_run_is_compared_with_the_full_run_of_the_same_motion() {
    use galerkin::fluid::reduced::compare::{compare, ComparedMotion};
    use galerkin::fluid::scene::FluidScene;
    let dir = tempfile::tempdir().expect("temp dir");
    let mut opts = options(&dir.path().join("work"));
    opts.runs = Some(vec![0, 1, 2]);
    opts.sizes = BasisSizes {
        energy: 1.0 - 1e-12,
        m_f: Some(12),
        m_u: Some(16),
        m_g: Some(5),
        m_h: Some(8),
        mid_step: false,
    };
    let model = train_scene(Path::new(SCENE), &dir.path().join("m.safetensors"), &opts, &mut |_| {}).unwrap();
    // The scene says 12 frames; the model's runs were trained with 6. Training run 0 is
    // simulated again at the pace it was trained at (its compressions peak at frame 3, not 6):
    // checked below against the run the training recorded.
    let scene = FluidScene::load(Path::new(SCENE)).unwrap();
    assert_eq!(scene.frames, 12);
    let replay = compare(&model, &scene, &ComparedMotion::Training(0), 6, 1, &mut |_| {}).unwrap();
    let driven = compare(
        &model,
        &scene,
        &ComparedMotion::Driven("0=0/0/0,6=0.2/0.2/0".parse().unwrap()),
        6,
        1,
        &mut |_| {},
    )
    .unwrap();
    for c in [&replay, &driven] {
        assert_eq!((c.energy_full.len(), c.energy_reduced.len(), c.error.len()), (7, 7, 7));
        assert_eq!(c.energy_full[0], 0.0, "both start at rest");
        assert!(c.energy_full[6] > 0.0 && c.energy_reduced[6] > 0.0, "the compression moved both");
        assert!(c.error.iter().all(|e| e.is_finite()));
        // The best fit in B_u (a Euclidean projection, measured in the V norm, so not
        // below the reduced run at every frame) is closer on average than the reduced run.
        assert!(c.projection_error.iter().all(|p| p.is_finite() && *p < 1.0));
        assert!(
            c.projection_summary().0 < c.error_summary().0,
            "{:?} {:?}",
            c.projection_summary(),
            c.error_summary()
        );
        assert_eq!(c.cell_error.len(), scene.mesh.cell_count());
        assert!(c.csv().lines().count() == 8 && c.csv().starts_with("frame,time,"));
        assert!(c.csv().lines().next().is_some_and(|h| h.ends_with("one_step_error,flux_projection_error")));
        // One step from each full frame, and the full flux's truncation in B_f: errors, finite.
        assert_eq!((c.one_step_error.len(), c.flux_projection_error.len()), (7, 7));
        assert_eq!(c.one_step_error[0], 0.0);
        assert!(c.one_step_error.iter().chain(&c.flux_projection_error).all(|e| e.is_finite() && *e >= 0.0));
        assert!(c.flux_projection_error.iter().all(|e| *e <= 1.0 + 1e-12));
    }
    // From rest, the replay's first step and the one-step error's first step are the same step
    // (both from û = f̂ = 0 at the projected frame-0 geometry, to the replayed ĝ₁ and ĥ₁ = B_hᵀh₁).
    assert!(replay.error[1] > 0.0, "the first frame moved");
    assert!(
        (replay.one_step_error[1] - replay.error[1]).abs() <= 1e-9,
        "{} vs {}",
        replay.one_step_error[1],
        replay.error[1]
    );
    // The training's own snapshots of run 0 read back instead of simulated again: the same
    // full run (the solver is deterministic; 1e-9 leaves room for summation order only) —
    // which holds only if the simulated run moved at the training's pace, 6 frames a pulse.
    let full = dir.path().join("work/run-00");
    let recorded =
        compare(&model, &scene, &ComparedMotion::Recorded { full: full.clone() }, 6, 1, &mut |_| {}).unwrap();
    for (a, b) in recorded.energy_full.iter().zip(&replay.energy_full) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1e-300), "{a} vs {b}");
    }
    for (a, b) in recorded.error.iter().zip(&replay.error) {
        assert!((a - b).abs() <= 1e-9, "{a} vs {b}");
    }
    // The one-step errors agree too: the induced flux read from the snapshots is the one the
    // solver computes for the simulated run.
    for (a, b) in recorded.one_step_error.iter().zip(&replay.one_step_error) {
        assert!((a - b).abs() <= 1e-9, "one step: {a} vs {b}");
    }
    assert!(recorded.seconds.0.is_nan(), "nothing was simulated on the full side");
    let e = compare(&model, &scene, &ComparedMotion::Recorded { full }, 7, 1, &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("7 frames"), "{e}");
    let missing = dir.path().join("work/run-07");
    let e =
        compare(&model, &scene, &ComparedMotion::Recorded { full: missing }, 6, 1, &mut |_| {}).unwrap_err();
    assert!(e.to_string().contains("run-07"), "{e}");
    // The full run with 4× its substeps: another full run (its time integration refined), the
    // same reduced one; a recorded run cannot be refined, nor a run by 0.
    let refined = compare(&model, &scene, &ComparedMotion::Training(0), 6, 4, &mut |_| {}).unwrap();
    assert_eq!(refined.energy_reduced, replay.energy_reduced);
    assert!(refined.energy_full[6] != replay.energy_full[6] && refined.error.iter().all(|e| e.is_finite()));
    let recorded_run = ComparedMotion::Recorded { full: dir.path().join("work/run-00") };
    assert!(compare(&model, &scene, &recorded_run, 6, 2, &mut |_| {})
        .unwrap_err()
        .to_string()
        .contains("refined"));
    assert!(compare(&model, &scene, &ComparedMotion::Training(0), 6, 0, &mut |_| {}).is_err());
    // A training run, its snapshots in the bases, is followed closer than a motion none made.
    let (replay_mean, _) = replay.error_summary();
    let (driven_mean, _) = driven.error_summary();
    eprintln!(
        "mean relative velocity error: training run {replay_mean:.3}, outside the training {driven_mean:.3}"
    );
    assert!(replay_mean < driven_mean, "{replay_mean} vs {driven_mean}");
}

#[test]
fn a_training_motion_is_replayed_faster_or_slower() {
    use galerkin::fluid::reduced::{run_paced, run_reduced, ReducedMotion};
    let dir = tempfile::tempdir().expect("temp dir");
    let (model, _, _) = train(&dir.path().join("work"), &dir.path().join("m.safetensors"));
    let fluid = ReducedFluid::new(&model).unwrap();
    let traj = &model.trajectories[0];
    let mg = traj.g.shape()[1];
    let g = |k: usize| traj.g.data()[k * mg..(k + 1) * mg].to_vec();
    // At its own pace the paced run is the computed-flux replay, bit for bit.
    let same = run_paced(&model, &fluid, 0, 1.0, 6, &mut |_| {}).unwrap();
    let computed = run_reduced(&model, &fluid, ReducedMotion::Computed(0), 6, &mut |_| {}).unwrap();
    assert_eq!(same.states, computed.states);
    // Half speed: every other frame is a training frame, the ones between are midpoints.
    let slow = run_paced(&model, &fluid, 0, 0.5, 12, &mut |_| {}).unwrap();
    for t in 0..=12 {
        let want: Vec<f64> = if t % 2 == 0 {
            g(t / 2)
        } else {
            g(t / 2).iter().zip(g(t / 2 + 1)).map(|(a, b)| 0.5 * a + 0.5 * b).collect()
        };
        let err = slow.states[t].g.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err <= 1e-15 * want.iter().fold(1.0f64, |m, x| m.max(x.abs())), "frame {t}: {err:e}");
    }
    // Twice the speed: frame t is training frame 2t; the fluid moves faster, so more energy.
    let fast = run_paced(&model, &fluid, 0, 2.0, 3, &mut |_| {}).unwrap();
    for t in 0..=3 {
        assert_eq!(fast.states[t].g, g(2 * t), "frame {t}");
    }
    let energy =
        |r: &galerkin::fluid::reduced::ReducedRun, t: usize| fluid.energy(&r.states[t].u, &r.states[t].g);
    assert!(energy(&fast, 3) > energy(&same, 6), "{} vs {}", energy(&fast, 3), energy(&same, 6));
    // Past the run's last frame, or a pace out of range, is refused.
    let e = run_paced(&model, &fluid, 0, 2.0, 4, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("at most 3 frames"), "{e}");
    for bad in [0.0, -1.0, f64::NAN, 1e3] {
        assert!(run_paced(&model, &fluid, 0, bad, 1, &mut |_| {}).is_err(), "pace {bad} accepted");
    }
    assert!(run_paced(&model, &fluid, 5, 1.0, 1, &mut |_| {}).unwrap_err().to_string().contains("run 5"));
}

/// A model trained from a scene names it (absolute path and content hash): `fluid compare`
/// needs no --scene, from any working directory, and refuses the scene once it changed,
/// naming both hashes.
#[test]
fn compare_finds_the_model_s_scene_from_any_directory_and_refuses_a_changed_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("cavity.toml");
    std::fs::copy(SCENE, &scene).expect("scene copied");
    let model_path = dir.path().join("m.safetensors");
    let model =
        train_scene(&scene, &model_path, &options(&dir.path().join("work")), &mut |_| {}).expect("training");
    let source = model.provenance.source.as_ref().expect("the model names its scene");
    assert_eq!(Path::new(&source.scene), std::path::absolute(&scene).unwrap());
    assert_eq!(model.scene_file(None).expect("the scene, unchanged"), Path::new(&source.scene));
    let elsewhere = tempfile::tempdir().expect("another working directory");
    let compare = || {
        std::process::Command::new(env!("CARGO_BIN_EXE_galerkin"))
            .args(["fluid", "compare"])
            .arg(&model_path)
            .args(["--run", "0", "--frames", "2", "--out"])
            .arg(dir.path().join("compare"))
            .current_dir(elsewhere.path())
            .output()
            .expect("ran")
    };
    let out = compare();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The scene edited since: refused, naming the file and both hashes.
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, format!("{text}\n# edited\n")).unwrap();
    let out = compare();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("changed since the model was trained") && err.contains(&source.scene_sha256),
        "{err}"
    );
}
