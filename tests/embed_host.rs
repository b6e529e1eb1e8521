//! The host-embedding example, run on lavapipe with the validation layer and synchronization
//! validation on (the host's own messenger): a six-frame host loop, two frames in flight, in
//! which galerkin records particles, a spacetime slice, radiosity form factors and Jacobi sweeps,
//! the spectral prepass, a field drawn by
//! its own pass into a host image, and spectral and spacetime draws inside the host's own
//! render pass in viewports the host chose; the host checks every frame's pixels and the
//! particles, and there must be no validation error, before or after galerkin drops.

#[path = "../examples/embed_host/main.rs"]
mod embed_host;

#[test]
fn a_plain_ash_host_embeds_galerkin() {
    let report = embed_host::run_host(true).expect("host runs");
    assert!(report.validated);
    assert_eq!(report.validation_errors, 0, "first: {}", report.first_error);
    assert_eq!(report.frames, 6, "{report:?}");
    assert!(report.pixels_checked > 6 * 3_000, "{report:?}");
    assert_eq!(report.pixel_failures, 0, "{report:?}");
    // The spectral viewport equals galerkin's own offscreen render (tested pixel-exact against
    // the CPU f64 reference elsewhere) bit for bit: its fragments take their world point from
    // the pixel centre relative to the viewport's corner (exact in f32), whatever the viewport.
    // Pixels neither render covers show the host's clear colour.
    assert!(report.pixels_covered[0] > 6 * 5_000, "{report:?}");
    assert_eq!(report.pixels_differing[0], 0, "{report:?}");
    // The spacetime slice is drawn from interpolated vertex attributes: moved by the viewport
    // offset, the rasteriser computes their barycentric weights from other framebuffer
    // coordinates, which round differently in the last bit; a few pixels then land one 8-bit
    // step away from the offscreen render (measured: 2 of about 130,000), never more.
    assert!(report.pixels_covered[1] > 6 * 5_000, "{report:?}");
    assert!(report.largest_difference[1] <= 1, "{report:?}");
    assert!(report.pixels_differing[1] * 1000 < report.pixels_covered[1], "{report:?}");
    // Uniform flow: the closed form U·t; device positions in f32 near 2.0 round at ~1.2e-7 per
    // substep over 60 substeps.
    assert!(report.particle_error < 1e-4, "{report:?}");
    // Form factors recorded in the host's frames: f32 against the CPU's f64 within 5·10⁻⁵ of
    // max(|F|, 10⁻³ max F), at most 0.1 % of visible pairs flipped by a grazing segment or the
    // facing threshold (the bounds of tests/radiosity_gpu.rs, where they are explained).
    assert!(report.form_factor_error < 5e-5, "{report:?}");
    assert!(report.form_factor_flips.0 * 1000 <= report.form_factor_flips.1, "{report:?}");
    // 48 Jacobi sweeps over six frames, against the same sweeps in f64 on the device's F:
    // each sweep's f32 sums of ~500 terms round at ~10⁻⁷ relative; 10⁻⁵ of the largest value.
    assert_eq!(report.sweeps, 48);
    assert!(report.radiosity_error <= 1e-5, "{report:?}");
}
