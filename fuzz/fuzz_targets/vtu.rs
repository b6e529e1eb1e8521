//! VTK XML unstructured grids (`.vtu`: every encoding and compressor) as the spectral and the
//! spacetime readers read them, and ParaView collections (`.pvd`) naming them.
#![no_main]
use galerkin_fuzz::{parts, scratch_file};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let [vtu, pvd] = parts(data, 2)[..] else { return };
    let path = scratch_file("in.vtu", vtu);
    let _ = galerkin::spectral::vtu::read(&path);
    let _ = galerkin::spacetime::vtu::read(&path);
    if !pvd.is_empty() {
        let collection = scratch_file("in.pvd", pvd);
        let _ = galerkin::spectral::collection::read_collection(&collection);
    }
});
