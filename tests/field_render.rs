//! The first graphics pass against its CPU f64 reference, every covered pixel: the value at a
//! pixel centre must be the cubic evaluated at the plane point seen through that centre
//! (tolerance: `value_tolerance`), and the colour must be that value through the colour map
//! (tolerance: `check_colours`). Background pixels must be untouched; only pixels within
//! 0.05 px of the square's outline are left to the rasteriser's tie-breaking.

mod common;

use galerkin::demo::field::{check_colours, check_values, FieldOutput, FieldPass, Ramp};
use galerkin::demo::polynomial::BivariateCubic;
use galerkin::render::{Camera, ColorFormat, Colormap, Pixels, RenderTarget};

const W: u32 = 160;
const H: u32 = 120;

fn scene() -> (Camera, BivariateCubic, Ramp) {
    let camera =
        Camera { eye: [0.4, -2.6, 1.9], target: [0.0, 0.05, 0.0], fov_y_degrees: 42.0, ..Camera::default() };
    let p = BivariateCubic { coefficients: [0.1, 0.8, -0.3, -0.6, 1.2, 0.4, 0.5, -0.7, 0.3, -0.45] };
    (camera, p, Ramp { lo: -3.0, hi: 3.0, log: false })
}

/// Renders the value image of `p` (RGBA32F, cleared to zero).
fn render_values(gpu: &galerkin::gpu::Gpu, camera: &Camera, p: &BivariateCubic, ramp: Ramp) -> Vec<f32> {
    let target = RenderTarget::new(gpu, "field values", W, H, ColorFormat::Rgba32F).unwrap();
    let pass =
        FieldPass::new(gpu, target.render_pass(), p, 8, &Colormap::grey(), ramp, FieldOutput::Value).unwrap();
    match target.render(gpu, [0.0; 4], |rec| pass.record(rec, target.extent(), camera)).unwrap() {
        Pixels::Rgba32F(px) => px,
        Pixels::Rgba8(_) => panic!("a float target reads back floats"),
    }
}

#[test]
fn field_values_match_the_cpu_reference_at_every_covered_pixel() {
    let gpu = common::gpu();
    let (camera, p, ramp) = scene();
    let px = render_values(&gpu, &camera, &p, ramp);
    let check = check_values(&camera, &p, W, H, &px);
    assert!(check.passed(), "{} failures, first: {:?}", check.failures, check.first_failure);
    // The view must actually show the field and background, and the unchecked outline be thin.
    assert!(check.checked > (W * H / 4) as usize, "only {} covered pixels", check.checked);
    assert!(check.background > (W * H / 10) as usize, "only {} background pixels", check.background);
    assert!(check.outline < 2 * (W + H) as usize, "{} pixels on the outline", check.outline);
}

#[test]
fn a_wrong_polynomial_fails_the_value_check() {
    // The comparison must be able to fail: perturb one coefficient by 1e-3 in the reference.
    let gpu = common::gpu();
    let (camera, p, ramp) = scene();
    let px = render_values(&gpu, &camera, &p, ramp);
    let mut wrong = p;
    wrong.coefficients[4] += 1e-3;
    let check = check_values(&camera, &wrong, W, H, &px);
    assert!(check.failures > check.checked / 2, "only {} of {} pixels failed", check.failures, check.checked);
}

#[test]
fn field_colours_match_the_cpu_reference_at_every_covered_pixel() {
    let gpu = common::gpu();
    let (camera, p, ramp) = scene();
    let log_ramp = Ramp { lo: 0.05, hi: 4.0, log: true };
    for (colormap, ramp) in
        [(Colormap::viridis(), ramp), (Colormap::cool_warm(), ramp), (Colormap::grey(), log_ramp)]
    {
        let target = RenderTarget::new(&gpu, "field colours", W, H, ColorFormat::Rgba8).unwrap();
        let pass =
            FieldPass::new(&gpu, target.render_pass(), &p, 8, &colormap, ramp, FieldOutput::Colour).unwrap();
        let clear = [0.25, 0.25, 0.25, 1.0];
        let Pixels::Rgba8(px) =
            target.render(&gpu, clear, |rec| pass.record(rec, target.extent(), &camera)).unwrap()
        else {
            panic!("an RGBA8 target reads back bytes")
        };
        let check = check_colours(&camera, &p, &colormap, ramp, W, H, &px, [64, 64, 64, 255]);
        assert!(
            check.passed(),
            "{}: {} failures, first: {:?}",
            colormap.name(),
            check.failures,
            check.first_failure
        );
        assert!(check.checked > (W * H / 4) as usize);
    }
}
