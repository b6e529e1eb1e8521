//! Scene files: the radiosity, fluid and demo scenes' TOML.
//!
//! Fluid scenes build their mesh while parsing; a valid scene at a fine spacing is a
//! legitimate minutes-long meshing job (a 2.2·10⁶-cell bird takes 10 s natively, over 90 s
//! under AddressSanitizer), not a finding. The fuzzer therefore builds within a budget of
//! 20,000 cells (about a second under AddressSanitizer), which exercises the same estimate
//! and refusal code that the machine's budget does.
#![no_main]
use galerkin::mesh::budget::CellBudget;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

/// The most cells a fuzzed fluid scene may mesh.
const FUZZ_CELLS: f64 = 20_000.0;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = Path::new("in.toml");
    let _ = galerkin::radiosity::scene::SceneSpec::parse(text, path);
    let _ = galerkin::fluid::scene::FluidScene::parse_within(text, path, &CellBudget::cells(FUZZ_CELLS));
    let _ = galerkin::demo::scene::DemoScene::parse(text, path);
});
