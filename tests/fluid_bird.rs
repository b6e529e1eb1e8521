//! The flying bird of seed 000 §7.2 (src/fluid/bird.rs, src/fluid/embedded.rs): a box of
//! fluid around an animated closed surface, its mesh following the animation frame by frame.

use std::path::Path;

use galerkin::fluid::scene::FluidScene;
use galerkin::fluid::FluidSolver;
use galerkin::mesh::bvh::Bvh;
use galerkin::mesh::volume::enclosed_volume;

/// The small bird, coarser still (about 20,000 cells), over `frames` animation frames.
fn scene_text(frames: usize, steps: usize) -> String {
    format!(
        "[bird]\nframes = {frames}\n[box]\nlo = [-1.4, -1.8, -1.3]\nhi = [1.4, 1.8, 1.3]\nspacing = 0.25\n\
         [flow]\ninitial_velocity = [0.0, 0.0, 0.0]\nviscosity = 1e-3\nframe_time = 0.02\nframes = {steps}\n"
    )
}

fn load(text: &str) -> FluidScene {
    FluidScene::parse(text, Path::new("bird_test.toml")).expect("scene")
}

#[test]
fn every_frame_of_the_bird_keeps_the_volume_and_the_surface_vertices_on_the_bird() {
    let mut scene = load(&scene_text(266, 10));
    let base = scene.base.clone();
    let topo = scene.topology.clone();
    let rest = enclosed_volume(&base, &topo, base.g());
    let animation = scene.animation().expect("a bird").clone();
    // Frame 0 is the base pose: the mesh is the stuffed one, to rounding.
    let g0 = scene.geometry(0).expect("frame 0");
    let worst0 = g0.iter().zip(base.g()).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst0 < 1e-12, "frame 0 moved the base mesh by {worst0}");
    // The mesh vertices on the bird: those within the stuffing's bisection tolerance of it.
    let near = |frame: usize| {
        let tris = (0..animation.triangles.len())
            .map(|t| animation.triangle_at(frame, t).map(glam::DVec3::from_array))
            .collect();
        Bvh::new(tris)
    };
    let bvh0 = near(0);
    let on_bird: Vec<usize> = (0..base.vertex_count())
        .filter(|&v| {
            let p = base.point(v);
            bvh0.nearest(glam::DVec3::new(p[0], p[1], p[2])).is_some_and(|(d, _)| d < 1e-9)
        })
        .collect();
    assert!(on_bird.len() > 50, "{} vertices on the bird", on_bird.len());
    let (mut worst_volume, mut worst_surface) = (0.0f64, 0.0f64);
    for frame in 0..animation.frame_count() {
        // Refused (an error naming the frame and cell) if any cell inverts.
        let g = scene.geometry(frame).unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        let volume = enclosed_volume(&base, &topo, &g);
        worst_volume = worst_volume.max((volume - rest).abs() / rest);
        let cells: f64 = base.volumes_at(&g).iter().sum();
        assert!((cells - rest).abs() < 1e-10 * rest, "frame {frame}: cells hold {cells}, not {rest}");
        if frame % 19 == 0 {
            let bvh = near(frame);
            for &v in &on_bird {
                let p = glam::DVec3::new(g[3 * v], g[3 * v + 1], g[3 * v + 2]);
                worst_surface = worst_surface.max(bvh.nearest(p).map_or(f64::INFINITY, |(d, _)| d));
            }
        }
    }
    // Volume: the lid's δ is exact up to rounding of sums over ~5,000 boundary faces.
    assert!(worst_volume < 1e-12, "volume drift {worst_volume:e}");
    // Surface: barycentric on the moved triangle plus the bisection offset (≤ 1e-9).
    assert!(worst_surface < 1e-9, "a bird vertex left the bird by {worst_surface:e}");
}

#[test]
fn the_bird_written_as_an_obj_sequence_loads_back_as_the_same_domain() {
    let frames = 12;
    let mut bird = load(&scene_text(frames, 3));
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    bird.animation().expect("a bird").write_sequence(&dir, "bird").expect("written");
    let text =
        scene_text(frames, 3).replace("[bird]\nframes = 12\n", "[surface]\nobj_sequence = \"bird_*.obj\"\n");
    assert!(text.contains("[surface]"));
    let mut user = FluidScene::parse(&text, &dir.join("scene.toml")).expect("the OBJ sequence scene");
    assert_eq!(user.base.cells(), bird.base.cells());
    for frame in [0, 5, 11] {
        let (a, b) = (bird.geometry(frame).expect("bird"), user.geometry(frame).expect("user"));
        let worst = a.iter().zip(&b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
        // 17 significant digits in the files: the same doubles, the same stuffing.
        assert!(worst < 1e-13, "frame {frame}: {worst:e}");
    }
}

#[test]
fn the_flapping_bird_stirs_still_air_without_divergence() {
    let mut scene = load(&scene_text(266, 3));
    let (mesh, topo) = (scene.mesh.clone(), scene.topology.clone());
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(mesh.g().to_vec(), &scene.initial_velocity).expect("state");
    assert_eq!(solver.energy(&state), 0.0);
    for frame in 1..=3 {
        let g = scene.geometry(frame).expect("geometry");
        let (next, report) = solver.step(&state, &g, frame).expect("step");
        // The closed box keeps its volume: the induced fluxes through the walls sum to zero.
        let net: f64 = topo.boundary_faces().iter().map(|&f| report.h[f as usize]).sum();
        let scale: f64 = topo.boundary_faces().iter().map(|&f| report.h[f as usize].abs()).sum();
        assert!(net.abs() < 1e-9 * scale, "frame {frame}: net wall flux {net} of {scale}");
        assert!(report.projection.relative_divergence < 1e-9, "frame {frame}");
        state = next;
    }
    // The wings moved the air: energy went from zero to a finite positive amount.
    let e = solver.energy(&state);
    assert!(e.is_finite() && e > 1e-6, "energy {e}");
}

#[test]
fn bad_bird_scenes_are_refused_naming_the_key() {
    let too_many = scene_text(10, 10);
    let err =
        FluidScene::parse(&too_many, Path::new("b.toml")).expect_err("10 steps of 10 frames").to_string();
    assert!(err.contains("frames") && err.contains("at most 9"), "{err}");
    let small_box = scene_text(10, 3).replace("hi = [1.4, 1.8, 1.3]", "hi = [1.4, 1.0, 1.3]");
    let err = FluidScene::parse(&small_box, Path::new("b.toml")).expect_err("wing outside").to_string();
    assert!(err.contains("frame 0") && err.contains("box"), "{err}");
    let no_box = "[bird]\n[flow]\ninitial_velocity = [0.0, 0.0, 0.0]\nviscosity = 0.0\nframe_time = 0.02\nframes = 1\n";
    let err = FluidScene::parse(no_box, Path::new("b.toml")).expect_err("no box").to_string();
    assert!(err.contains("[box]"), "{err}");
    let missing =
        scene_text(10, 3).replace("[bird]\nframes = 10\n", "[surface]\nobj_sequence = \"nothing_*.obj\"\n");
    let err =
        FluidScene::parse(&missing, Path::new("/nonexistent/b.toml")).expect_err("no files").to_string();
    // The error points at the `obj_sequence` line (line 2) and says what is missing.
    assert!(err.contains("b.toml:2") && err.contains("No such file"), "{err}");
}

#[test]
fn the_cli_writes_a_scene_s_surface_animation_as_an_obj_sequence() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = dir.join("bird.toml");
    std::fs::write(&scene, scene_text(6, 2)).expect("scene");
    let out_dir = dir.join("obj");
    let run = |args: &[&std::ffi::OsStr]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("run")
    };
    let out = run(&[
        "fluid".as_ref(),
        "surface".as_ref(),
        scene.as_os_str(),
        "--out".as_ref(),
        out_dir.as_os_str(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let files = galerkin::mesh::animation::SurfaceAnimation::sequence_files(&out_dir.join("frame_*.obj"))
        .expect("listed");
    assert_eq!(files.len(), 6);
    let back = galerkin::mesh::animation::SurfaceAnimation::read_sequence(&files).expect("read");
    let bird = galerkin::fluid::bird::BirdSpec { frames: 6, ..Default::default() }.animation();
    for k in 0..6 {
        for t in 0..bird.triangles.len() {
            assert_eq!(back.triangle_at(k, t), bird.triangle_at(k, t), "frame {k} triangle {t}");
        }
    }
    // A scene without a surface animation is refused with a message, not a panic.
    let tunnel = Path::new("scenes/fluid/tunnel_small.toml");
    let out = run(&[
        "fluid".as_ref(),
        "surface".as_ref(),
        tunnel.as_os_str(),
        "--out".as_ref(),
        out_dir.as_os_str(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("only [bird] and [surface] scenes"), "{stderr}");
}

/// The bird trains although a small geometry basis folds cells of the projected mesh (the
/// wings' shells rotate; seed 000 §6.1 keeps m_g = 7 for its eagle), the folded cells
/// reported; a reduced geometry whose volume matrix V̂(ĝ) is not positive definite is refused
/// naming its run and frame.
#[test]
fn a_bird_trains_with_its_folded_cells_reported_and_an_indefinite_volume_matrix_refused() {
    use galerkin::fluid::reduced::{train_scene, BasisSizes, ReducedFluid, SceneTraining};
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = dir.path().join("bird.toml");
    // 24 animation frames: six steps are a whole wingbeat.
    std::fs::write(&scene, scene_text(24, 6)).expect("scene written");
    let options = SceneTraining {
        sizes: BasisSizes {
            energy: 0.9999,
            m_f: Some(5),
            m_u: Some(6),
            m_g: Some(2),
            m_h: Some(4),
            mid_step: false,
        },
        frames: Some(6),
        runs: None,
        work: dir.path().join("work"),
    };
    let mut model = train_scene(&scene, &dir.path().join("bird.safetensors"), &options, &mut |_| {})
        .expect("the bird trains");
    let g = model.provenance.bases.iter().find(|b| b.name == "g").expect("basis g");
    assert_eq!(g.columns, 2);
    assert!(g.note.contains("folds cells in"), "{}", g.note);
    // The model runs: every training frame's V̂(ĝ) was factorised.
    let fluid = ReducedFluid::new(&model).expect("a reduced fluid");
    let mg = model.trajectories[0].g.shape()[1];
    let g3 = model.trajectories[0].g.data()[3 * mg..4 * mg].to_vec();
    fluid.check_geometry(&g3, "frame 3").expect("positive definite");
    // Table 1's rows measure a bird model by replaying its training run beside the full step
    // of the same scene; a model measured on another scene's mesh is refused.
    use galerkin::bench::fluid_reduced::{trained_model, BenchMotion};
    let b = trained_model(&model, &scene, BenchMotion::Replay(0), (6, 2), 300, None, &mut |_| {})
        .expect("the bird's rows");
    assert_eq!(b.dims, (6, 5, 2, model.dim_of("h")));
    assert!(b.full.iter().all(|&t| t > 0.0) && b.reduced > 0.0 && b.particles.0 > 0.0, "{b:?}");
    assert!(b.particles.1.is_none());
    let e = trained_model(
        &model,
        Path::new("scenes/fluid/cavity_small.toml"),
        BenchMotion::Replay(0),
        (6, 2),
        10,
        None,
        &mut |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("mesh"), "{e}");
    let e = trained_model(&model, &scene, BenchMotion::Replay(0), (7, 2), 10, None, &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("training run 0 has 6"), "{e}");
    // ĝ → −ĝ turns every volume (cubic in g) negative: V̂ is negative definite, refused.
    for x in &mut model.trajectories[0].g.data_mut()[3 * mg..4 * mg] {
        *x = -*x;
    }
    let e = model.check_trajectories().unwrap_err().to_string();
    assert!(
        e.contains("training run 0") && e.contains("frame 3") && e.contains("not positive definite"),
        "{e}"
    );
}
