//! The GLSL includes and their Rust twins agree: `colormap.glsl` with `render::colormap`
//! (`ramp_coordinate`, `ramp_texcoord`) and `polynomial.glsl` with `demo::polynomial`,
//! evaluated by a probe compute shader at the same inputs.

mod common;

use galerkin::demo::polynomial::BivariateCubic;
use galerkin::gpu::{shaders, vk, Buffer, MemoryKind};
use galerkin::render::{ramp_coordinate, ramp_texcoord};

#[test]
fn glsl_includes_match_their_rust_twins() {
    let gpu = common::gpu();
    // Ramp inputs: linear and log, inside, outside, at the ends, degenerate ranges, v <= 0 on log.
    let mut ramp_in: Vec<[f32; 4]> = Vec::new();
    for &(lo, hi, log) in &[(-1.5f32, 1.5f32, 0.0f32), (0.01, 100.0, 1.0), (2.0, 2.0, 0.0), (1.0, 0.5, 1.0)] {
        for k in -3..=23 {
            let v = lo + (hi - lo) * (k as f32 / 20.0);
            ramp_in.push([v, lo, hi, log]);
        }
        ramp_in.push([0.0, lo, hi, log]);
        ramp_in.push([-1.0, lo, hi, log]);
    }
    let n = ramp_in.len();
    let xy: Vec<[f32; 2]> =
        common::random_f32(2 * n, 9).chunks(2).map(|c| [c[0] * 1.3, c[1] * 1.3]).collect();
    let p = BivariateCubic { coefficients: [0.3, -1.2, 0.7, 0.25, 1.5, -0.8, 0.4, -0.6, 0.9, 0.35] };
    let coeffs: Vec<f32> = p.coefficients.iter().map(|&c| c as f32).collect();

    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let rb = Buffer::from_slice(&gpu, "ramp in", &ramp_in, usage).unwrap();
    let xb = Buffer::from_slice(&gpu, "xy", &xy, usage).unwrap();
    let cb = Buffer::from_slice(&gpu, "coefficients", &coeffs, usage).unwrap();
    let ob = Buffer::<[f32; 4]>::new(&gpu, "out", n as u64, usage, MemoryKind::GpuOnly).unwrap();
    let bindings = [rb.binding(), xb.binding(), cb.binding(), ob.binding()].map(|b| b.unwrap());
    let push = (n as u32).to_ne_bytes();
    common::run_probe(
        &gpu,
        "include probe",
        shaders::probe::INCLUDES,
        &bindings,
        &push,
        (n as u32).div_ceil(64),
    );
    let out = ob.download(&gpu).unwrap();

    for i in 0..n {
        let [v, lo, hi, log] = ramp_in[i].map(f64::from);
        let t = ramp_coordinate(v, lo, hi, log > 0.5);
        // f32 evaluation of (v − lo)/(hi − lo) or a ratio of logs: a few ulps relative to 1.
        assert!(
            (f64::from(out[i][0]) - t).abs() < 2e-6,
            "ramp_coordinate({v}, {lo}, {hi}, {log}): {} vs {t}",
            out[i][0]
        );
        // The texcoord step is affine in t: compare on the GPU's own t.
        let u = ramp_texcoord(f64::from(out[i][0]), 256.0);
        assert!((f64::from(out[i][1]) - u).abs() < 1e-6, "ramp_texcoord: {} vs {u}", out[i][1]);
        let (x, y) = (f64::from(xy[i][0]), f64::from(xy[i][1]));
        // The GLSL cubic sees f32 coefficients; the Rust twin evaluates those same values in
        // f64. Tolerance: a few ulps of Σ|c||x|^i|y|^j.
        let p32 = BivariateCubic {
            coefficients: coeffs.iter().map(|&c| f64::from(c)).collect::<Vec<_>>().try_into().unwrap(),
        };
        let want = p32.eval(x, y);
        let tol = 8.0 * f64::from(f32::EPSILON) * p32.abs_sum(x, y);
        assert!((f64::from(out[i][2]) - want).abs() <= tol, "cubic at ({x}, {y}): {} vs {want}", out[i][2]);
    }
}
