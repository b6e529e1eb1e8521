//! The first graphics pass against its CPU f64 reference, every covered pixel: the value at a
//! pixel centre must be the cubic evaluated at the plane point seen through that centre, and
//! the colour must be that value through the colour map.

mod common;

use galerkin::demo::field::{
    reference_colour, reference_coverage, Coverage, FieldOutput, FieldPass, Ramp,
};
use galerkin::demo::polynomial::BivariateCubic;
use galerkin::render::{Camera, ColorFormat, Colormap, Pixels, RenderTarget};

const W: u32 = 160;
const H: u32 = 120;
/// Pixels whose centre lies within this many pixels of the square's outline are left to the
/// rasteriser's tie-breaking rules (lavapipe snaps vertices to 1/256 px); all others are checked.
const MARGIN_PX: f64 = 0.05;

fn scene() -> (Camera, BivariateCubic, Ramp) {
    let camera = Camera {
        eye: [0.4, -2.6, 1.9],
        target: [0.0, 0.05, 0.0],
        fov_y_degrees: 42.0,
        ..Camera::default()
    };
    let p = BivariateCubic {
        coefficients: [0.1, 0.8, -0.3, -0.6, 1.2, 0.4, 0.5, -0.7, 0.3, -0.45],
    };
    (
        camera,
        p,
        Ramp {
            lo: -1.5,
            hi: 1.5,
            log: false,
        },
    )
}

#[test]
fn field_values_match_the_cpu_reference_at_every_covered_pixel() {
    let gpu = common::gpu();
    let (camera, p, ramp) = scene();
    let target = RenderTarget::new(&gpu, "field values", W, H, ColorFormat::Rgba32F).unwrap();
    let pass = FieldPass::new(
        &gpu,
        target.render_pass(),
        &p,
        8,
        &Colormap::viridis(),
        ramp,
        FieldOutput::Value,
    )
    .unwrap();
    let Pixels::Rgba32F(px) = target
        .render(&gpu, [0.0, 0.0, 0.0, 0.0], |cmd| {
            pass.record(cmd, target.extent(), &camera)
        })
        .unwrap()
    else {
        panic!("float target reads back floats")
    };
    let coverage = reference_coverage(&camera, W, H, MARGIN_PX);
    let (mut inside, mut edge, mut worst) = (0, 0, 0.0f64);
    for (i, c) in coverage.iter().enumerate() {
        let got = &px[4 * i..4 * i + 4];
        match *c {
            Coverage::Inside { point } => {
                inside += 1;
                assert_eq!(got[3], 1.0, "pixel {} must be covered", i);
                let reference = p.eval(point.x, point.y);
                // Tolerance: the interpolated position is f32 (relative error ~1e-6 over a
                // domain of size 1, so |Δx| ≤ 4e-6 with margin) and moves p by |∇p|·|Δx|;
                // the f32 Horner evaluation adds a few ulps of Σ|c_ij||x|^i|y|^j.
                let tol = 4e-6 * p.gradient_norm(point.x, point.y)
                    + 8.0 * f64::from(f32::EPSILON) * p.abs_sum(point.x, point.y);
                let err = (f64::from(got[0]) - reference).abs();
                worst = worst.max(err / tol);
                assert!(
                    err <= tol,
                    "pixel ({}, {}): gpu {} vs reference {reference} (tol {tol})",
                    i as u32 % W,
                    i as u32 / W,
                    got[0]
                );
            }
            Coverage::Outside => assert_eq!(got, [0.0; 4], "pixel {} must be background", i),
            Coverage::Edge => edge += 1,
        }
    }
    // The view must actually show the field, and the unchecked outline must be thin.
    assert!(
        inside > (W * H / 4) as usize,
        "only {inside} covered pixels"
    );
    assert!(edge < 2 * (W + H) as usize, "{edge} pixels on the outline");
    eprintln!("field values: {inside} pixels checked, {edge} on the outline, worst error {worst:.3} of tolerance");
}

#[test]
fn field_colours_match_the_cpu_reference_at_every_covered_pixel() {
    let gpu = common::gpu();
    let (camera, p, ramp) = scene();
    for colormap in [Colormap::viridis(), Colormap::cool_warm()] {
        let target = RenderTarget::new(&gpu, "field colours", W, H, ColorFormat::Rgba8).unwrap();
        let pass = FieldPass::new(
            &gpu,
            target.render_pass(),
            &p,
            8,
            &colormap,
            ramp,
            FieldOutput::Colour,
        )
        .unwrap();
        let clear = [0.25, 0.25, 0.25, 1.0];
        let Pixels::Rgba8(px) = target
            .render(&gpu, clear, |cmd| {
                pass.record(cmd, target.extent(), &camera)
            })
            .unwrap()
        else {
            panic!("RGBA8 target reads back bytes")
        };
        let coverage = reference_coverage(&camera, W, H, MARGIN_PX);
        for (i, c) in coverage.iter().enumerate() {
            let got = &px[4 * i..4 * i + 4];
            match *c {
                Coverage::Inside { point } => {
                    let v = p.eval(point.x, point.y);
                    // Tolerance: the value's own error (as above, ≤ 1e-4 here) moves the ramp
                    // coordinate by ≤ 1e-4/3; the ramp's steepest step between adjacent texels
                    // is a few levels, the sampler's 8-bit subtexel weights and the final 8-bit
                    // rounding add up to 1.5 levels. Bound it by the colours of v ± 1e-4.
                    let lo = reference_colour(&colormap, ramp, v - 1e-4);
                    let hi = reference_colour(&colormap, ramp, v + 1e-4);
                    for ch in 0..3 {
                        let g = f64::from(got[ch]) / 255.0;
                        let (a, b) = (lo[ch].min(hi[ch]), lo[ch].max(hi[ch]));
                        let slack = 1.5 / 255.0;
                        assert!(
                            g >= a - slack && g <= b + slack,
                            "{}: pixel ({}, {}) channel {ch}: {} not in [{a}, {b}] ± 1.5/255",
                            colormap.name(),
                            i as u32 % W,
                            i as u32 / W,
                            got[ch]
                        );
                    }
                    assert_eq!(got[3], 255);
                }
                Coverage::Outside => {
                    assert_eq!(got, [64, 64, 64, 255], "pixel {i} must be background")
                }
                Coverage::Edge => {}
            }
        }
    }
}
