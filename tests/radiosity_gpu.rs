//! Full radiosity on the device against the CPU f64 path: the form factors of every pair
//! (facing test, BVH walk, Eq. 15) and Jacobi sweeps of Eq. 14, on the small two-room scene.

mod common;

use std::path::Path;

use galerkin::radiosity::form_factor::{form_factors, NearField};
use galerkin::radiosity::gpu::GpuRadiosity;
use galerkin::radiosity::{full_radiosity, SceneSpec};

const SMALL: &str = include_str!("../scenes/radiosity/two_rooms_small.toml");

#[test]
fn device_form_factors_and_solve_match_the_cpu() {
    let gpu = common::gpu();
    let spec = SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap();
    let mut p = spec.defaults();
    p[3] = 15.0; // a tilted ceiling: nothing axis-aligned to lean on
    let s = full_radiosity(&spec, &p).unwrap();
    let device = GpuRadiosity::new(&gpu).unwrap();
    for near in [NearField::Regularised, NearField::Eq15] {
        let cpu = form_factors(&s.mesh, near);
        let f = device.form_factors(&gpu, &s.mesh, near).unwrap();
        let gpu_f = f.download(&gpu).unwrap();
        let top = cpu.values.iter().fold(0.0f64, |m, v| m.max(*v));
        let (mut vis_flips, mut worst, mut visible) = (0, 0.0f64, 0);
        for (a, b) in cpu.values.iter().zip(&gpu_f.values) {
            visible += usize::from(*a > 0.0);
            if (*a > 0.0) != (*b > 0.0) {
                vis_flips += 1;
            } else {
                worst = worst.max((a - b).abs() / a.abs().max(1e-3 * top));
            }
        }
        eprintln!("{near:?}: {visible} visible pairs, {vis_flips} visibility flips, worst relative error {worst:.2e}");
        // f32 against f64: centroids, normals and the quotient each round at ~6·10⁻⁸; the
        // value relative to max(|F|, 10⁻³ max F) within 5·10⁻⁵ (measured 9·10⁻⁶).
        assert!(worst < 5e-5, "{near:?}: worst {worst}");
        // A pair whose segment grazes a blocker's edge within f32 rounding, or whose cosine is
        // between the CPU's and the device's facing thresholds, may flip: at most 0.1 %.
        assert!(vis_flips * 1000 <= visible, "{near:?}: {vis_flips} of {visible} visible pairs flipped");
        if near == NearField::Regularised {
            let (b, sweeps) = device.solve(&gpu, &f, &s.mesh.albedo, &s.emission, 1e-6, 2000).unwrap();
            let top = s.radiosity.iter().flatten().fold(0.0f64, |m, v| m.max(*v));
            let off = |reference: &[[f64; 3]]| {
                b.iter()
                    .zip(reference)
                    .flat_map(|(x, y)| (0..3).map(move |c| (x[c] - y[c]).abs()))
                    .fold(0.0f64, f64::max)
            };
            // The solver: against an f64 direct solve of the device's own form factors, f32
            // sums of ~500 terms and the stopping rule at 10⁻⁶ give 10⁻⁵ of the largest value.
            let same_factors =
                galerkin::radiosity::solve::solve_direct(&gpu_f, &s.mesh.albedo, &s.emission).unwrap();
            let solver = off(&same_factors);
            // Against the CPU's whole solve: the visibility flips above (grazing pairs, some of
            // them neighbours with large F where a floor meets the furniture) move a few faces'
            // radiosity by up to 10⁻³ of the largest value (measured 2.1·10⁻⁴).
            let whole = off(&s.radiosity);
            eprintln!(
                "solve: {sweeps} sweeps on the device ({} on the CPU); {:.2e} of max from the same factors' f64 solve, {:.2e} from the CPU's",
                s.sweeps,
                solver / top,
                whole / top
            );
            assert!(solver <= 1e-5 * top, "the device's solve is off by {solver} (max {top})");
            assert!(whole <= 1e-3 * top, "radiosity off by {whole} (max {top})");
        }
    }
}
