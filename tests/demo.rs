//! `galerkin demo`'s parts run as a test (with validation): every part's check against its
//! CPU f64 reference passes (a part whose check fails is an error), in order, and each part
//! wrote its files — the same library function the command line prints.

mod common;

use std::path::Path;

use galerkin::demo::scene::DemoScene;

#[test]
fn every_demo_part_passes_its_reference_check_and_writes_its_files() {
    let gpu = common::gpu();
    let scene_path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/demo.toml");
    let scene = DemoScene::load(Path::new(scene_path)).expect("the demo scene loads");
    let out = tempfile::Builder::new().prefix("galerkin-demo-").tempdir().expect("scratch");
    let mut reported = Vec::new();
    let parts = galerkin::demo::run::run(&gpu, &scene, out.path(), &mut |p| reported.push(p.name))
        .unwrap_or_else(|e| panic!("a demo part failed its check: {e:#}"));
    let names: Vec<&str> = parts.iter().map(|p| p.name).collect();
    assert_eq!(
        names,
        [
            "axpy",
            "field values",
            "field colours",
            "spacetime",
            "spectral",
            "spectral",
            "radiosity",
            "fluid",
            "fluid reduced"
        ]
    );
    assert_eq!(reported, names, "each part is reported as it finishes");
    for part in &parts {
        for file in &part.files {
            let bytes = std::fs::read(file).unwrap_or_else(|e| panic!("{part}: {}: {e}", file.display()));
            let png = bytes.starts_with(b"\x89PNG\r\n\x1a\n");
            let exr = bytes.starts_with(&[0x76, 0x2f, 0x31, 0x01]);
            assert!(png || exr, "{part}: {} is neither PNG nor EXR", file.display());
            assert!(file.starts_with(out.path()), "{part}: wrote outside --out: {}", file.display());
        }
    }
    let written: usize = parts.iter().map(|p| p.files.len()).sum();
    assert_eq!(written, 10, "{parts:#?}");
}
