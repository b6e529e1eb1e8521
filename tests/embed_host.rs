//! The host-embedding example, run on lavapipe with the validation layer on (the host's own
//! messenger): galerkin records into the host's command buffer and image, the host checks
//! every covered pixel, and there must be no validation error, before or after galerkin drops.

#[path = "../examples/embed_host.rs"]
mod embed_host;

#[test]
fn a_plain_ash_host_embeds_galerkin() {
    let report = embed_host::run_host(true).expect("host runs");
    assert!(report.validated);
    assert_eq!(report.validation_errors, 0, "first: {}", report.first_error);
    assert!(report.pixels_checked > 5_000, "{report:?}");
    assert_eq!(report.pixel_failures, 0, "{report:?}");
    assert!(report.axpy_error_ratio <= 1.0, "{report:?}");
}
