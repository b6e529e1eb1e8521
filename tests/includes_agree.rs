//! The GLSL includes and their Rust twins agree: `colormap.glsl` with `render::colormap`
//! (`ramp_coordinate`, `ramp_texcoord`), `polynomial.glsl` with `demo::polynomial`, and
//! `simplex.glsl` with `mesh::geometry` and the particles' barycentric coordinates, evaluated
//! by probe compute shaders at the same inputs; `spectral_transfer.glsl` (the volume pass's
//! opacity ramp) with `spectral::transfer::TransferFunction`.

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
    let push = common::CountPush { n: n as u32 };
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

#[test]
fn simplex_glsl_matches_the_mesh_geometry() {
    use galerkin::fluid::particles::barycentric;
    use galerkin::mesh::geometry::{centroid, face_centroid, signed_volume};
    let gpu = common::gpu();
    let r = common::random_f32(64 * 16, 21);
    let n = 64;
    let mut corners: Vec<[f32; 4]> = Vec::new();
    let mut points: Vec<[f32; 4]> = Vec::new();
    for i in 0..n {
        let dim = if i % 2 == 0 { 2 } else { 3 };
        // A unit simplex, perturbed and positively oriented.
        let base = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for (k, b) in base.iter().enumerate() {
            let q = |j: usize| b[j] + 0.2 * r[16 * i + 3 * k + j];
            corners.push(if k <= dim {
                [q(0), q(1), if dim == 3 { q(2) } else { 0.0 }, 0.0]
            } else {
                [0.0; 4]
            });
        }
        points.push([
            0.3 + 0.5 * r[16 * i + 12],
            0.2 + 0.5 * r[16 * i + 13],
            if dim == 3 { 0.2 } else { 0.0 },
            dim as f32,
        ]);
    }
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let cb = Buffer::from_slice(&gpu, "corners", &corners, usage).unwrap();
    let pb = Buffer::from_slice(&gpu, "points", &points, usage).unwrap();
    let ob = Buffer::<[f32; 4]>::new(&gpu, "out", 4 * n as u64, usage, MemoryKind::GpuOnly).unwrap();
    let bindings = [cb.binding(), pb.binding(), ob.binding()].map(|b| b.unwrap());
    common::run_probe(
        &gpu,
        "simplex probe",
        shaders::probe::SIMPLEX,
        &bindings,
        &common::CountPush { n: n as u32 },
        1,
    );
    let out = ob.download(&gpu).unwrap();
    // f32 against f64 on O(1) coordinates: a few ulps of the O(1) terms.
    let close = |a: f32, b: f64, what: &str| assert!((f64::from(a) - b).abs() < 2e-6, "{what}: {a} vs {b}");
    for i in 0..n {
        let dim = points[i][3] as usize;
        let p: Vec<[f64; 3]> =
            (0..=dim).map(|k| [0, 1, 2].map(|j| f64::from(corners[4 * i + k][j]))).collect();
        let o = &out[4 * i..4 * i + 4];
        close(o[0][0], signed_volume(dim, &p), "volume");
        let c = centroid(&p);
        let fc = face_centroid(&p, 0);
        for j in 0..3 {
            close(o[1][j], c[j], "centroid");
            close(o[2][j], fc[j], "face centroid");
        }
        let x = [0, 1, 2].map(|j| f64::from(points[i][j]));
        let b = barycentric(dim, &p, x);
        for k in 0..=dim {
            // The weight divides by the volume (≥ 1/6 here): 1e-5.
            assert!((f64::from(o[3][k]) - b[k]).abs() < 1e-5, "barycentric {k}: {} vs {}", o[3][k], b[k]);
        }
    }
}

/// The volume pass's opacity ramp (`spectral_transfer.glsl`: `volume_alpha`, `volume_sigma`)
/// against `TransferFunction::alpha` and `sigma` from the same device words, at field values
/// below, between, on and beyond its points (a kink, a plateau, a drop and a fully opaque end).
/// Tolerances: α within 1e-6 (f32 interpolation of values of size 1); σ within
/// 8ε/(1 − α)/D + 1e-6 σ (−ln(1 − α) in f32 loses ε/(1 − α) of 1 − α's rounding; α is capped
/// at 1 − 2⁻²⁰, exact in f32, so the opaque end stays finite).
#[test]
fn transfer_glsl_matches_the_transfer_function() {
    use galerkin::spectral::transfer::{TransferFunction, MAX_OPACITY};
    let gpu = common::gpu();
    let tf =
        TransferFunction::new(vec![(-1.0, 0.0), (-0.25, 0.6), (0.5, 0.6), (0.75, 0.05), (2.0, 1.0)], 0.37)
            .expect("a transfer function");
    // The device sees the f32 points: the twin evaluates those same values in f64.
    let words = tf.device_words([0.0; 3], &galerkin::spectral::transfer::Sheets::none());
    let f32_of = |w: u32| f64::from(f32::from_bits(w));
    let count = words[0] as usize;
    let tf32 = TransferFunction::new(
        (0..count).map(|k| (f32_of(words[8 + 2 * k]), f32_of(words[9 + 2 * k]))).collect(),
        f32_of(words[1]),
    )
    .expect("the device's transfer function");
    let mut inputs: Vec<f32> = (-30..=70).map(|k| k as f32 * 0.04).collect();
    inputs.extend([-1.0f32, -0.25, 0.5, 0.75, 2.0, -7.5, 9.0]);
    let n = inputs.len();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let tb = Buffer::from_slice(&gpu, "transfer", &words, usage).unwrap();
    let ib = Buffer::from_slice(&gpu, "field values", &inputs, usage).unwrap();
    let ob = Buffer::<[f32; 2]>::new(&gpu, "out", n as u64, usage, MemoryKind::GpuToCpu).unwrap();
    let bindings = [tb.binding(), ib.binding(), ob.binding()].map(|b| b.unwrap());
    common::run_probe(
        &gpu,
        "transfer probe",
        shaders::probe::TRANSFER,
        &bindings,
        &common::CountPush { n: n as u32 },
        (n as u32).div_ceil(64),
    );
    let out = ob.download(&gpu).unwrap();
    let eps = f64::from(f32::EPSILON);
    for (k, &f) in inputs.iter().enumerate() {
        let f = f64::from(f);
        let (alpha, sigma) = (tf32.alpha(f), tf32.sigma(f));
        let (ga, gs) = (f64::from(out[k][0]), f64::from(out[k][1]));
        assert!((ga - alpha).abs() <= 1e-6, "α({f}): {ga} vs {alpha}");
        let tol = 8.0 * eps / (1.0 - alpha.min(MAX_OPACITY)) / tf32.unit_distance + 1e-6 * sigma;
        assert!((gs - sigma).abs() <= tol, "σ({f}): {gs} vs {sigma} (tolerance {tol:e})");
    }
    // The opaque end is capped, finite, on both sides.
    assert!(tf32.sigma(9.0).is_finite() && f64::from(out[n - 1][1]).is_finite());
}
