//! Drawing radiosity solutions (seed 000 §9): every pixel shows the face the ray through its
//! centre meets first (back faces culled), with that face's radiance (flat), the barycentric
//! interpolation of its vertices' radiance (smooth), and the tone-mapped colour of
//! `tonemap.glsl` equal to its Rust twin. References are computed per pixel in f64.

mod common;

use std::path::Path;

use galerkin::radiosity::form_factor::bvh_of;
use galerkin::radiosity::render::{
    camera_for, display_radiance, scene_vertices, Output, SceneRenderer, Shading, Viewpoint,
};
use galerkin::radiosity::{full_radiosity, SceneSpec};
use galerkin::render::{tone_map, ColorFormat, Pixels, RenderTarget, BACKGROUND};

const SMALL: &str = include_str!("../scenes/radiosity/two_rooms_small.toml");
const W: u32 = 160;
const H: u32 = 120;

#[test]
fn pixels_show_the_face_their_ray_meets_with_its_radiance() {
    let gpu = common::gpu();
    let spec = SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap();
    let s = full_radiosity(&spec, &spec.defaults()).unwrap();
    let radiance = display_radiance(&s.mesh, &s.geometry, &spec.lights, &s.radiosity);
    let bvh = bvh_of(&s.mesh);
    let raw = RenderTarget::new(&gpu, "raw", W, H, ColorFormat::Rgba32F).unwrap();
    let colour = RenderTarget::new(&gpu, "colour", W, H, ColorFormat::Rgba8).unwrap();
    let mut raw_pass = SceneRenderer::new(&gpu, raw.render_pass(), Output::Raw, s.mesh.len()).unwrap();
    let mut colour_pass =
        SceneRenderer::new(&gpu, colour.render_pass(), Output::Colour, s.mesh.len()).unwrap();
    let exposure = 2.0;
    for view in [Viewpoint::Living, Viewpoint::Bedroom, Viewpoint::Overview] {
        let camera = camera_for(&spec, view);
        for shading in [Shading::Flat, Shading::Smooth] {
            let vertices = scene_vertices(&s.mesh, &s.geometry, &radiance, shading);
            raw_pass.update(&vertices).expect("no draw in flight");
            colour_pass.update(&vertices).expect("no draw in flight");
            let Pixels::Rgba32F(out) = raw
                .render(&gpu, [0.0, 0.0, 0.0, -1.0], |rec| {
                    raw_pass.record(rec, raw.extent(), &camera, exposure)
                })
                .unwrap()
            else {
                panic!("float target")
            };
            let Pixels::Rgba8(rgb) = colour
                .render(&gpu, BACKGROUND, |rec| colour_pass.record(rec, colour.extent(), &camera, exposure))
                .unwrap()
            else {
                panic!("8-bit target")
            };
            let (mut interior, mut wrong_face, mut worst_value, mut worst_colour) = (0, 0, 0.0f64, 0i32);
            for py in 0..H {
                for px in 0..W {
                    let hit = |dx: f64, dy: f64| {
                        let (o, d) =
                            camera.ray_through(f64::from(px) + 0.5 + dx, f64::from(py) + 0.5 + dy, W, H);
                        bvh.closest_front_hit(o, d)
                    };
                    let Some((face, t)) = hit(0.0, 0.0) else { continue };
                    // Pixels whose whole neighbourhood (±0.75 px) sees the same face: no
                    // rasterisation rule or depth rounding can decide them otherwise.
                    let corners = [(-0.75, -0.75), (0.75, -0.75), (-0.75, 0.75), (0.75, 0.75)];
                    if !corners.iter().all(|&(dx, dy)| hit(dx, dy).map(|h| h.0) == Some(face)) {
                        continue;
                    }
                    interior += 1;
                    let k = ((py * W + px) * 4) as usize;
                    if out[k + 3] != face as f32 {
                        wrong_face += 1;
                        continue;
                    }
                    let expected = match shading {
                        Shading::Flat => radiance[face as usize],
                        Shading::Smooth => {
                            // Barycentric interpolation of the vertex values at the hit point.
                            let (o, d) = camera.ray_through(f64::from(px) + 0.5, f64::from(py) + 0.5, W, H);
                            let p = o + t * d;
                            let corner = s.mesh.corners(face as usize);
                            let n = (corner[1] - corner[0]).cross(corner[2] - corner[0]);
                            let lam = [1, 2, 0].map(|a| {
                                let (b, c) = (corner[a], corner[(a + 1) % 3]);
                                (c - b).cross(p - b).dot(n) / n.length_squared()
                            });
                            let base = 3 * face as usize;
                            let mut e = [0.0; 3];
                            for (v, l) in lam.iter().enumerate() {
                                for (acc, r) in e.iter_mut().zip(vertices[base + v].radiance) {
                                    *acc += l * f64::from(r);
                                }
                            }
                            e
                        }
                    };
                    for c in 0..3 {
                        worst_value = worst_value.max((f64::from(out[k + c]) - expected[c]).abs());
                    }
                    let display = tone_map(expected, exposure);
                    for c in 0..3 {
                        let want = (display[c] * 255.0).round() as i32;
                        worst_colour = worst_colour.max((i32::from(rgb[k + c]) - want).abs());
                    }
                }
            }
            let top = radiance.iter().flatten().fold(0.0f64, |m, v| m.max(*v));
            eprintln!(
                "{view:?} {shading:?}: {interior} interior pixels, {wrong_face} wrong faces, worst radiance error {:.2e} of max, worst colour {worst_colour}/255",
                worst_value / top
            );
            assert!(interior > (W * H / 8) as usize, "{view:?}: only {interior} interior pixels");
            assert_eq!(wrong_face, 0, "{view:?} {shading:?}");
            // Flat: the f32 copy of the face's value (relative 10⁻⁶; measured 2.5·10⁻⁷). Smooth:
            // f32 barycentric interpolation at the rasteriser's sample position, 10⁻⁵ of the
            // largest value (measured 4.8·10⁻⁷).
            let tol = if shading == Shading::Flat { 1e-6 } else { 1e-5 };
            assert!(worst_value <= tol * top, "{view:?} {shading:?}: radiance off by {worst_value}");
            // f32 exp/pow against f64 and the UNORM rounding: one step of 255.
            assert!(worst_colour <= 1, "{view:?} {shading:?}: colour off by {worst_colour}/255");
        }
    }
}

/// `write_picture` with a reduced model reports the model's estimate and operator margin at the
/// drawn parameters (what `evaluate_estimated` and `operator_margin` give; the margin positive
/// for a sane model), none for the full solve, and refuses to draw where the estimate is above
/// the threshold asked.
#[test]
fn a_picture_from_a_model_reports_its_estimate_and_refuses_when_untrusted() {
    use galerkin::radiosity::any_scene::AnyScene;
    use galerkin::radiosity::picture::{write_picture, PictureRequest};
    use galerkin::radiosity::train::{
        sample_parameters, solve_configurations, train, DesignSpace, TrainOptions,
    };
    let gpu = common::gpu();
    let spec = SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap();
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), 6, 5);
    let options =
        TrainOptions { samples: 6, energy: 0.99, cap: 4, radiosity_cap: 8, ..TrainOptions::default() };
    let configurations = solve_configurations(&spec, &params, &options, &|_| {}).unwrap();
    let (model, _) = train(&spec, &configurations, &options, &|_, _, _| {}).unwrap();
    let scene = AnyScene::Rooms(Box::new(spec.clone()));
    let dir = tempfile::Builder::new().prefix("galerkin-picture-").tempdir().unwrap();
    let request = PictureRequest {
        params: spec.defaults().to_vec(),
        viewpoint: Viewpoint::Living,
        orbit: None,
        overlay: Default::default(),
        shading: Shading::Flat,
        exposure: None,
        size: (W, H),
        faces: None,
        form_factors: galerkin::radiosity::near_field::FormFactorMethod::Centroid,
        trust_threshold: None,
        legend: true,
    };
    let reduced =
        write_picture(&gpu, &scene, Some(&model), &request, &dir.path().join("reduced.png")).unwrap();
    let mesh = DesignSpace::mesh(&spec, &spec.defaults()).unwrap();
    let want = model.operator_margin(&mesh).unwrap();
    let estimate = reduced.estimate.expect("a reduced picture carries its estimate");
    assert_eq!(estimate, model.evaluate_estimated(&mesh).unwrap().2);
    assert!(
        (estimate.margin - want).abs() <= 1e-12 * want.abs().max(1.0),
        "{} against {want}",
        estimate.margin
    );
    assert!(want > 0.0, "a sane model's margin: {want}");
    assert!(estimate.error.is_finite() && estimate.error > 0.0, "an estimate: {estimate:?}");
    let full = write_picture(&gpu, &scene, None, &request, &dir.path().join("full.png")).unwrap();
    assert_eq!(full.estimate, None);
    // Below the estimate, the picture is refused as untrusted, naming why, and nothing is
    // written.
    let strict = PictureRequest { trust_threshold: Some(0.5 * estimate.error), ..request };
    let refused = dir.path().join("refused.png");
    let err = write_picture(&gpu, &scene, Some(&model), &strict, &refused).unwrap_err().to_string();
    assert!(err.contains("not to be trusted") && err.contains("estimated error"), "{err}");
    assert!(!refused.exists(), "an untrusted picture was written");
}
