//! MFEM meshes and GridFunctions (and a GLVis stream: both in one file), and a mesh with a
//! GridFunction loaded together as the spectral renderer loads them.
#![no_main]
use galerkin_fuzz::{parts, scratch_file};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let [mesh, gf] = parts(data, 2)[..] else { return };
    let mesh_path = scratch_file("in.mesh", mesh);
    let gf_path = scratch_file("in.gf", gf);
    let _ = galerkin::spectral::mfem::read_mesh(&mesh_path);
    let _ = galerkin::spectral::mfem::read_grid_function(&gf_path);
    let _ = galerkin::spectral::mfem::read_solution(&mesh_path);
    let _ = galerkin::spectral::load(&mesh_path, &[gf_path]);
});
