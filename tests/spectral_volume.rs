//! Volume rendering of solid meshes per pixel (`volume.frag`) against the f64 ray caster
//! (`spectral::volume_reference`): curved tetrahedra VTK wrote (orders 3 and 6), VTK's Lagrange
//! hexahedra (order 3) and the curved saddle hexahedra of orders 6 and 9
//! (scripts/vtk-iso-fixtures.py), through a transfer function with four opacity points (two
//! kinks inside the range). Per pixel, each colour channel (over black) and the transmittance
//! within 1/255 of the reference — the goal, and a 255-level picture's resolution;
//! pixels one side draws and the other not are allowed only where the other side's ray is
//! nearly empty (every channel and the opacity within 1/255 of none: silhouette rays grazing a
//! box). The reference is first shown converged: doubling its samples changes no channel by
//! more than 1/2040 (an eighth of the tolerance).

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::transfer::{Sheets, TransferFunction};
use galerkin::spectral::volume_reference::{compare_volume, volume_reference, VolumeColours};
use galerkin::spectral::{SpectralMesh, SpectralRenderer, SpectralView};

fn load(name: &str) -> SpectralMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
    galerkin::spectral::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Transparent at the bottom of the range, a peak at 30 %, nearly clear at 50 %, most opaque
/// at the top; a unit distance of a quarter of the mesh's diagonal.
fn transfer(mesh: &SpectralMesh) -> TransferFunction {
    let (lo, hi) = mesh.value_range(0, 0);
    let at = |s: f64| lo + s * (hi - lo);
    TransferFunction::new(vec![(lo, 0.0), (at(0.3), 0.6), (at(0.5), 0.05), (hi, 0.9)], 0.25 * mesh.diagonal())
        .expect("valid")
}

const TOLERANCE: f64 = 1.0 / 255.0;

#[test]
fn volumes_match_the_f64_ray_caster() {
    let gpu = common::gpu();
    let size = (64u32, 48u32);
    let target = RenderTarget::new(&gpu, "volume", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    let colormap = Colormap::viridis();
    for name in
        ["tet_cube_o3.vtu", "tet_cube_o6.vtu", "hex_ascii.vtu", "hex_saddle_o6.vtu", "hex_saddle_o9.vtu"]
    {
        let mesh = Arc::new(load(name));
        let tf = transfer(&mesh);
        let view = SpectralView { volume: Some(tf.clone()), ..SpectralView::default() };
        let camera = fit_camera(&mesh);
        let colours = VolumeColours { colormap: &colormap, range: mesh.value_range(0, 0), log: false };
        let started = std::time::Instant::now();
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &colormap).expect("renderer");
        let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let drawn = started.elapsed();
        let reference = volume_reference(&mesh, (0, 0), &camera, &tf, &Sheets::none(), &colours, size, 16);
        let agreement = compare_volume(&px, &reference, TOLERANCE);
        eprintln!(
            "{name}: {} pixels, worst {:.2e} ({:.2} of 1/255), mean {:.1e}, {} one-sided, {} mismatched; device {:.1} s, reference {:.1} s",
            agreement.shown,
            agreement.worst,
            agreement.worst / TOLERANCE,
            agreement.mean,
            agreement.missing,
            agreement.mismatched.len(),
            drawn.as_secs_f64(),
            started.elapsed().as_secs_f64() - drawn.as_secs_f64()
        );
        for m in agreement.mismatched.iter().take(6) {
            eprintln!("  pixel ({}, {}): {}", m.0 as u32 % size.0, m.0 as u32 / size.0, m.1);
        }
        assert!(agreement.shown > 300, "{name}: the volume covers {} pixels", agreement.shown);
        // Something is seen: the volume is neither clear nor black.
        let opaque = reference.iter().flatten().filter(|s| s.transmittance < 0.8).count();
        assert!(opaque * 4 > agreement.shown, "{name}: only {opaque} pixels absorb a fifth of the light");
        assert!(
            agreement.mismatched.is_empty(),
            "{name}: {:?}",
            &agreement.mismatched[..agreement.mismatched.len().min(4)]
        );
    }
}

/// The reference's quadrature has converged: twice the samples change no channel by more than
/// an eighth of the tolerance (order 9, the most curved fixture; a small picture).
#[test]
fn the_volume_reference_is_converged() {
    let mesh = load("hex_saddle_o9.vtu");
    let tf = transfer(&mesh);
    let colormap = Colormap::viridis();
    let colours = VolumeColours { colormap: &colormap, range: mesh.value_range(0, 0), log: false };
    let camera = fit_camera(&mesh);
    let size = (24, 18);
    let a = volume_reference(&mesh, (0, 0), &camera, &tf, &Sheets::none(), &colours, size, 16);
    let b = volume_reference(&mesh, (0, 0), &camera, &tf, &Sheets::none(), &colours, size, 32);
    // No sheets: no ray grazes one.
    let (worst, _) = common::volumes::reference_difference(&a, &b);
    eprintln!("doubling the samples changes a channel by {worst:.2e}");
    assert!(worst <= TOLERANCE / 8.0, "{worst}");
}

/// A ray through more elements than a fragment holds at once (40 stacked hexahedra seen from
/// above, 16 slots a round) is composited over several rounds, in order: within 1/255 of the
/// reference everywhere, as through few elements.
#[test]
fn rays_through_many_elements_take_rounds_in_order() {
    use galerkin::render::Camera;
    use galerkin::spectral::{generate, NodeSet};
    let gpu = common::gpu();
    let mesh = Arc::new(generate::hex_shell(1, 1, 40, 1, 2, NodeSet::GaussLobatto).expect("mesh"));
    let (lo, hi) = mesh.value_range(0, 0);
    // Faint enough that light is left after all 40 (the ray would stop below 1/4096), with a
    // kink in the middle so that neighbouring layers differ.
    let tf = TransferFunction::new(vec![(lo, 0.05), (0.5 * (lo + hi), 0.4), (hi, 0.1)], 0.5).expect("valid");
    let camera = Camera {
        eye: [0.45, 0.45, 3.0],
        target: [0.45, 0.45, 0.5],
        up: [0.0, 1.0, 0.0],
        fov_y_degrees: 20.0,
        near: 0.01,
        far: 100.0,
    };
    let size = (32u32, 24u32);
    let colormap = Colormap::viridis();
    let target = RenderTarget::new(&gpu, "volume", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    let view = SpectralView { volume: Some(tf.clone()), camera: Some(camera), ..SpectralView::default() };
    let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &colormap).expect("renderer");
    let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else { panic!("bytes") };
    let colours = VolumeColours { colormap: &colormap, range: (lo, hi), log: false };
    let reference = volume_reference(&mesh, (0, 0), &camera, &tf, &Sheets::none(), &colours, size, 16);
    let agreement = compare_volume(&px, &reference, TOLERANCE);
    eprintln!(
        "40 layers: {} pixels, worst {:.2} of 1/255, {} mismatched",
        agreement.shown,
        agreement.worst / TOLERANCE,
        agreement.mismatched.len()
    );
    assert!(agreement.shown > 100, "{}", agreement.shown);
    // The middle pixel's ray crosses every layer's box (40 > the 16 slots of a round).
    let (_, d) = camera.pixel_ray(size.0 / 2, size.1 / 2, size.0, size.1);
    let boxes = galerkin::spectral::render::element_boxes(&mesh).expect("boxes");
    let crossed = boxes
        .chunks_exact(2)
        .filter(|b| {
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for a in 0..3 {
                let (p, q) = (
                    (f64::from(b[0][a]) - camera.eye[a]) / d[a],
                    (f64::from(b[1][a]) - camera.eye[a]) / d[a],
                );
                t0 = t0.max(p.min(q));
                t1 = t1.min(p.max(q));
            }
            t0 < t1
        })
        .count();
    assert_eq!(crossed, 40, "the middle ray crosses {crossed} boxes");
    assert!(reference[(size.1 / 2 * size.0 + size.0 / 2) as usize].is_some());
    assert!(
        agreement.mismatched.is_empty(),
        "{:?}",
        &agreement.mismatched[..agreement.mismatched.len().min(4)]
    );
}

/// Bad volume views are refused by name: a quadrilateral mesh, a volume together with cut
/// planes; bad transfer functions (empty, inverted) are refused when made.
#[test]
fn volume_views_that_cannot_be_drawn_are_refused() {
    use galerkin::spectral::picture::check_view;
    let gpu = common::gpu();
    let tf = TransferFunction::new(vec![(0.0, 0.0), (1.0, 0.5)], 1.0).expect("valid");
    let quads = Arc::new(load("quad_default.vtu"));
    let view = SpectralView { volume: Some(tf.clone()), ..SpectralView::default() };
    let err = check_view(&quads, &view).expect_err("refused").to_string();
    assert!(err.contains("hexahedral and tetrahedral meshes"), "{err}");
    let target = RenderTarget::new(&gpu, "volume", 32, 24, ColorFormat::Rgba32F).expect("target");
    let mut q = SpectralRenderer::new(&gpu, quads, &Colormap::viridis()).expect("renderer");
    let err = q.render(&target, &view).expect_err("refused").to_string();
    assert!(err.contains("hexahedral and tetrahedral meshes"), "{err}");
    let tets = Arc::new(load("tet_cube_o3.vtu"));
    let mut r = SpectralRenderer::new(&gpu, tets.clone(), &Colormap::viridis()).expect("renderer");
    let view = SpectralView {
        volume: Some(tf.clone()),
        cuts: vec![[0.0, 0.0, 1.0, 0.5]],
        ..SpectralView::default()
    };
    let err = check_view(&tets, &view).expect_err("refused").to_string();
    assert!(err.contains("cannot be combined"), "{err}");
    let err = r.render(&target, &view).expect_err("refused").to_string();
    assert!(err.contains("not drawn yet"), "{err}");
    for (points, what) in [
        (vec![], "empty"),
        (vec![(0.0, 0.0), (1.0, 0.0)], "empty"),
        (vec![(1.0, 0.2), (0.0, 0.5)], "inverted"),
    ] {
        let err = TransferFunction::new(points, 1.0).expect_err("refused");
        assert!(err.contains(what), "{err}");
    }
}

/// A picture whose tile lists outgrow one buffer is drawn in bands of tile rows: with the
/// budget cut to a few rows' worth, the same pixels as drawn whole, bit for bit (each pixel's
/// ray is cast by the same code over the same elements).
#[test]
fn a_picture_over_the_tile_budget_is_drawn_in_bands() {
    let gpu = common::gpu();
    let mesh = Arc::new(load("tet_cube_o3.vtu"));
    let tf = transfer(&mesh);
    let view = SpectralView { volume: Some(tf), ..SpectralView::default() };
    let target = RenderTarget::new(&gpu, "volume", 64, 48, ColorFormat::Rgba32F).expect("target");
    let mut renderer = SpectralRenderer::new(&gpu, mesh, &Colormap::viridis()).expect("renderer");
    let Pixels::Rgba32F(whole) = renderer.render(&target, &view).expect("rendered") else { panic!("bytes") };
    // 4 × 3 tiles of 16 pixels, each listing at most the 6 tetrahedra: 8 + 2·4 + 24 words a row
    // at most; 50 words hold one row, so three bands.
    renderer.set_volume_tile_budget(50);
    let Pixels::Rgba32F(banded) = renderer.render(&target, &view).expect("rendered") else { panic!("bytes") };
    let same = whole.iter().zip(&banded).all(|(a, b)| a.to_bits() == b.to_bits());
    assert!(same, "banded and whole pictures differ");
    assert!(whole.chunks_exact(4).filter(|p| !p[3].is_nan()).count() > 300);
    renderer.set_volume_tile_budget(10);
    let err = renderer.render(&target, &view).expect_err("refused").to_string();
    assert!(err.contains("one row of 4 screen tiles"), "{err}");
}
