//! A user's scene from OBJ files with a named deformation target: loaded, blended, solved,
//! trained and evaluated reduced; bad files refused naming the file.

use std::path::{Path, PathBuf};

use galerkin::radiosity::obj::ObjScene;
use galerkin::radiosity::reduced::relative_error;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, DesignSpace, TrainOptions};
use galerkin::radiosity::{full_radiosity_of, FaceKind};

/// A closed unit box lit inwards, as three objects (floor, walls, window), its x scaled by `sx`.
fn box_obj(sx: f64) -> String {
    let mut out = String::new();
    // Sides as (object, corners counter-clockwise seen from inside).
    let sides: [(&str, [[f64; 3]; 4]); 6] = [
        ("floor", [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]]),
        ("walls", [[0., 0., 1.], [0., 1., 1.], [1., 1., 1.], [1., 0., 1.]]),
        ("walls", [[0., 1., 0.], [1., 1., 0.], [1., 1., 1.], [0., 1., 1.]]),
        ("walls", [[0., 0., 0.], [0., 1., 0.], [0., 1., 1.], [0., 0., 1.]]),
        ("walls", [[1., 0., 0.], [1., 0., 1.], [1., 1., 1.], [1., 1., 0.]]),
        ("window", [[0., 0., 0.], [0., 0., 1.], [1., 0., 1.], [1., 0., 0.]]),
    ];
    let mut v = 0;
    for name in ["floor", "walls", "window"] {
        out += &format!("o {name}\n");
        for (_, c) in sides.iter().filter(|(n, _)| *n == name) {
            for p in c {
                out += &format!("v {} {} {}\n", p[0] * sx, p[1], p[2]);
            }
            out += &format!("f {} {} {}\nf {} {} {}\n", v + 1, v + 2, v + 3, v + 1, v + 3, v + 4);
            v += 4;
        }
    }
    out
}

const SCENE: &str = r#"
base = "box.obj"
[[targets]]
name = "stretch"
file = "box_wide.obj"
range = [0.0, 1.0]
default = 0.0
[materials]
default = [0.7, 0.7, 0.7]
by_object = { floor = [0.4, 0.3, 0.2] }
[openings]
windows = ["window"]
[lights]
mode = "area"
window_exitance = [10.0, 10.0, 10.0]
sky_zenith = [4.0, 4.0, 4.0]
ground_albedo = 0.2
"#;

fn write_scene(dir: &Path, scene: &str, wide: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("box.obj"), box_obj(1.0)).unwrap();
    std::fs::write(dir.join("box_wide.obj"), wide).unwrap();
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    dir.join("scene.toml")
}

#[test]
fn an_obj_scene_with_a_deformation_target_trains_and_reduces() {
    let dir = std::env::temp_dir().join(format!("galerkin-obj-{}", std::process::id()));
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

    // Train on a few samples with spanning bases: training configurations come back.
    let params = sample_parameters(&scene.ranges(), &scene.defaults(), 6, 1);
    let options =
        TrainOptions { samples: 6, energy: 1.0, cap: 1000, radiosity_cap: 2000, ..TrainOptions::default() };
    let configurations = solve_configurations(&scene, &params, options.near, &|_| {}).unwrap();
    let (model, _) = train(&scene, &configurations, &options, &|_, _, _| {}).unwrap();
    for c in &configurations {
        let (b, _) = model.evaluate(&scene.mesh(&c.params).unwrap()).unwrap();
        let e = relative_error(&b, &c.radiosity, &c.geometry.areas);
        assert!(e < 2e-2, "configuration {:?}: {e}", c.params);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_obj_scenes_name_the_file() {
    let dir = std::env::temp_dir().join(format!("galerkin-obj-bad-{}", std::process::id()));
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
    std::fs::remove_dir_all(&dir).unwrap();
}
