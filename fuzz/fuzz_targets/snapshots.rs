//! Fluid snapshot directories: the header, the mesh and one file of frames (given to every
//! quantity), read as `fluid export`, `fluid train` and `fluid render` read them.
#![no_main]
use galerkin_fuzz::{parts, scratch_dir, scratch_file};
use libfuzzer_sys::{fuzz_mutator, fuzz_target};

fuzz_target!(|data: &[u8]| {
    let [header, mesh, frames] = parts(data, 3)[..] else { return };
    scratch_file("snapshots.json", header);
    scratch_file("mesh.json", mesh);
    for q in galerkin::fluid::snapshots::QUANTITIES {
        scratch_file(&format!("{q}.f64"), frames);
    }
    let Ok(reader) = galerkin::fluid::snapshots::SnapshotReader::open(&scratch_dir()) else { return };
    for k in 0..reader.meta().frames.min(3) {
        let _ = reader.mesh_at(k);
        for q in galerkin::fluid::snapshots::QUANTITIES {
            let _ = reader.frame(q, k);
        }
    }
});

// Value mutations (NaN, ±inf, 1e308, negative sizes) beside libFuzzer's byte mutations.
fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    galerkin_fuzz::value_mutation(data, size, max_size, seed)
});
