//! A user's scene from OBJ files with a named deformation target: loaded, blended, solved,
//! trained and evaluated reduced; bad files refused naming the file.

mod common;

use galerkin::radiosity::obj::ObjScene;
use galerkin::radiosity::reduced::relative_error;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, DesignSpace, TrainOptions};
use galerkin::radiosity::{full_radiosity_of, FaceKind};

use common::obj_box::{box_obj, write_scene, SCENE};

#[test]
fn an_obj_scene_with_a_deformation_target_trains_and_reduces() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = ObjScene::load(&write_scene(&dir, SCENE, &box_obj(1.5))).unwrap();
    assert_eq!(scene.names(), ["stretch"]);
    let (m0, m1) = (scene.mesh(&[0.0]).unwrap(), scene.mesh(&[1.0]).unwrap());
    assert_eq!(m0.faces, m1.faces, "one topology");
    assert_eq!(m0.len(), 12);
    assert_eq!(m0.kind.iter().filter(|k| **k == FaceKind::Window).count(), 2);
    let xmax = m1.vertices.iter().fold(0.0f64, |m, v| m.max(v.x));
    assert!((xmax - 1.5).abs() < 1e-12, "the target stretches x to 1.5, got {xmax}");
    let half = scene.mesh(&[0.5]).unwrap();
    assert!((half.vertices.iter().fold(0.0f64, |m, v| m.max(v.x)) - 1.25).abs() < 1e-12, "blend is linear");
    let s = full_radiosity_of(m0, DesignSpace::lights(&scene)).unwrap();
    assert!(s.radiosity.iter().filter(|b| b[0] > 0.0).count() == 12);

    // Train on a few samples with spanning bases: training configurations come back, exactly
    // but for rounding and the training solves' Jacobi tolerance with the operator correction
    // (the reduced operator is the exact projection there).
    let params = sample_parameters(&scene.ranges(), &scene.defaults(), 6, 1);
    let options = TrainOptions {
        samples: 6,
        energy: 1.0,
        radiosity_energy: None,
        cap: 1000,
        radiosity_cap: 2000,
        ..TrainOptions::default()
    };
    let configurations = solve_configurations(&scene, &params, &options, &|_| {}).unwrap();
    let (model, _) = train(&scene, &configurations, &options, &|_, _, _| {}).unwrap();
    for c in &configurations {
        let (b, _) = model.evaluate(&scene.mesh(&c.params).unwrap()).unwrap();
        let e = relative_error(&b, &c.radiosity, &c.geometry.areas);
        assert!(e < 1e-8, "configuration {:?}: {e}", c.params);
    }
}

#[test]
fn bad_obj_scenes_name_the_file() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    // A target with another topology.
    let short: String = box_obj(1.5).lines().take(20).map(|l| format!("{l}\n")).collect();
    let e = ObjScene::load(&write_scene(&dir, SCENE, &short)).unwrap_err().to_string();
    assert!(e.contains("box_wide.obj") && e.contains("vertices and faces"), "{e}");
    // An object the base does not have.
    let bad = SCENE.replace("by_object = { floor", "by_object = { ceiling");
    let e = ObjScene::load(&write_scene(&dir, &bad, &box_obj(1.5))).unwrap_err().to_string();
    assert!(e.contains("scene.toml:") && e.contains("ceiling"), "{e}");
    // A weight outside its range names the target.
    let scene = ObjScene::load(&write_scene(&dir, SCENE, &box_obj(1.5))).unwrap();
    assert!(scene.mesh(&[2.0]).unwrap_err().to_string().contains("stretch"));
    // A missing OBJ names its path.
    std::fs::remove_file(dir.join("box.obj")).unwrap();
    let e = ObjScene::load(&dir.join("scene.toml")).unwrap_err().to_string();
    assert!(e.contains("box.obj"), "{e}");
}

/// An OBJ scene is one of the scene kinds the CLI and the viewer take: its parameters by name,
/// and in the viewer chosen by number and moved by brackets (the two rooms' letter keys do
/// nothing there).
#[cfg(feature = "viewer")]
#[test]
fn the_viewer_moves_an_obj_scenes_parameter_by_number_and_brackets() {
    use galerkin::radiosity::any_scene::AnyScene;
    use galerkin::radiosity::render::{Shading, Viewpoint};
    use galerkin::radiosity::viewer::{RadiosityContent, ViewSettings};
    use galerkin::render::viewer::ViewerContent;
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = AnyScene::load(&write_scene(&dir, SCENE, &box_obj(1.5)), None).unwrap();
    assert_eq!(scene.names(), ["stretch"]);
    let e = scene.parameters_from(&[("width".into(), 1.0)]).unwrap_err().to_string();
    assert!(e.contains("width") && e.contains("stretch"), "{e}");
    assert!(scene.parameters_from(&[("stretch".into(), 2.0)]).is_err(), "outside its range [0, 1]");
    let params = scene.parameters_from(&[("stretch".into(), 0.5)]).unwrap();
    let settings = ViewSettings {
        params,
        view: Viewpoint::Living,
        shading: Shading::Flat,
        exposure: 1.0,
        size: (64, 64),
        playing: false,
    };
    let mut content = RadiosityContent::new(scene, None, settings).unwrap();
    assert!(content.title().contains("[stretch 0.50]"), "{}", content.title());
    assert!(content.key("]"));
    assert!(content.title().contains("[stretch 0.55]"), "{}", content.title());
    assert!(!content.key("W"), "the two rooms' window key moves nothing here");
    assert!(content.key("2"), "a key the viewer takes");
    assert!(content.title().contains("[stretch"), "no second parameter to choose");
    for _ in 0..12 {
        content.key("[");
    }
    assert!(content.title().contains("[stretch 0.00]"), "{}", content.title());
    assert!(!content.key("["), "clamped at the range's end");
}
