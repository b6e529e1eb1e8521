//! Reduced models (safetensors with our header): the core model, the fluid's and the
//! radiosity's (its directory: the model and the visibility file).
#![no_main]
use galerkin_fuzz::{parts, scratch_dir, scratch_file};
use libfuzzer_sys::{fuzz_mutator, fuzz_target};

fuzz_target!(|data: &[u8]| {
    let [model, visibility] = parts(data, 2)[..] else { return };
    let path = scratch_file("model.safetensors", model);
    let _ = galerkin::reduce::ReducedModel::load(&path);
    let _ = galerkin::fluid::reduced::ReducedFluidModel::load(&path);
    scratch_file("visibility.safetensors", visibility);
    let _ = galerkin::radiosity::reduced::ReducedRadiosity::load(&scratch_dir());
});

// Value mutations (NaN, ±inf, 1e308, negative sizes) beside libFuzzer's byte mutations.
fuzz_mutator!(|data: &mut [u8], size: usize, max_size: usize, seed: u32| {
    galerkin_fuzz::value_mutation(data, size, max_size, seed)
});
