//! Gmsh MSH 4.1 files (ASCII and binary) as the fluid reads its meshes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = galerkin::mesh::gmsh::parse_msh(data, std::path::Path::new("in.msh"));
});
