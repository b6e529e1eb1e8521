//! The host-embedding example, run on lavapipe with the validation layer and synchronization
//! validation on (the host's own messenger): a six-frame host loop, two frames in flight, in
//! which galerkin records particles, a spacetime slice and three draws into the host's command
//! buffers and images between the host's own passes; the host checks every frame's pixels and
//! the particles, and there must be no validation error, before or after galerkin drops.

#[path = "../examples/embed_host.rs"]
mod embed_host;

#[test]
fn a_plain_ash_host_embeds_galerkin() {
    let report = embed_host::run_host(true).expect("host runs");
    assert!(report.validated);
    assert_eq!(report.validation_errors, 0, "first: {}", report.first_error);
    assert_eq!(report.frames, 6, "{report:?}");
    assert!(report.pixels_checked > 6 * 3_000, "{report:?}");
    assert_eq!(report.pixel_failures, 0, "{report:?}");
    // The spectral and spacetime regions equal galerkin's own offscreen renders (each tested
    // pixel-exact against the CPU f64 reference elsewhere) bit for bit: same pipelines, same
    // device, a NEAREST blit of the same size.
    assert!(report.pixels_covered > 6 * 5_000, "{report:?}");
    assert_eq!(report.pixels_differing, 0, "{report:?}");
    // Uniform flow: the closed form U·t; device positions in f32 near 2.0 round at ~1.2e-7 per
    // substep over 60 substeps.
    assert!(report.particle_error < 1e-4, "{report:?}");
}
