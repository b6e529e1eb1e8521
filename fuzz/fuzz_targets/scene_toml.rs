//! Scene files: the radiosity, fluid and demo scenes' TOML.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = Path::new("in.toml");
    let _ = galerkin::radiosity::scene::SceneSpec::parse(text, path);
    let _ = galerkin::fluid::scene::FluidScene::parse(text, path);
    let _ = galerkin::demo::scene::DemoScene::parse(text, path);
});
