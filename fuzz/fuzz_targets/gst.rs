//! Spacetime `.gst` files (memory-mapped): the header, the materials, and every element record
//! checked as a slice would check them.
#![no_main]
use galerkin_fuzz::scratch_file;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = scratch_file("in.gst", data);
    if let Ok(mut d) = galerkin::spacetime::gst::open(&path) {
        let n = d.len();
        let _ = d.check(0..n);
        let _ = d.active_range(0.5);
    }
});
