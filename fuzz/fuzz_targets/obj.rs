//! OBJ surfaces: an OBJ sequence of two frames (the fluid's animated boundaries) and a
//! radiosity OBJ scene (its TOML naming the OBJ file).
#![no_main]
use galerkin_fuzz::{parts, scratch_file};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let [first, second, scene] = parts(data, 3)[..] else { return };
    let a = scratch_file("a.obj", first);
    let b = scratch_file("b.obj", second);
    let _ = galerkin::mesh::animation::SurfaceAnimation::read_sequence(&[a.clone()]);
    let _ = galerkin::mesh::animation::SurfaceAnimation::read_sequence(&[a, b]);
    if !scene.is_empty() {
        let toml = scratch_file("scene.toml", scene);
        let _ = galerkin::radiosity::obj::ObjScene::load(&toml);
    }
});
