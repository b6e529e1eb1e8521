//! A small OBJ radiosity scene for tests: a closed unit box with a window, and a scene file
//! with one deformation target stretching it along x.

use std::path::{Path, PathBuf};

/// A closed unit box lit inwards, as three objects (floor, walls, window), its x scaled by `sx`.
pub fn box_obj(sx: f64) -> String {
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

pub const SCENE: &str = r#"
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

pub fn write_scene(dir: &Path, scene: &str, wide: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("box.obj"), box_obj(1.0)).unwrap();
    std::fs::write(dir.join("box_wide.obj"), wide).unwrap();
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    dir.join("scene.toml")
}
