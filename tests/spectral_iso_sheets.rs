//! Transparent isosurfaces, and isosurfaces inside a volume, drawn by the volume pass as sheets
//! (`volume.frag`) against the f64 ray caster (`spectral::volume_reference` with
//! [`Sheets`]): every crossing of every value along each pixel's ray composited front to back
//! with its opacity, lit with the exact normal. On VTK's curved tetrahedra (orders 3 and 6, two
//! values) and the curved saddle hexahedra of orders 6 and 9 (scripts/vtk-iso-fixtures.py:
//! u = 0 a double cone whose sheets touch, 0.04 and 0.12 nested around it, −0.04 beyond).
//!
//! Tolerance: each colour channel (over black) and the transmittance within 1/255 of the
//! reference — a 255-level picture's resolution; the sheet colours themselves differ only by
//! the f32 normal, the compositing is exact. Pixels whose reference ray grazes a sheet (two
//! roots of one value within two of the device's sample intervals in one element, or three
//! samples approaching a value without crossing it — `VolumeSample::grazing`) may differ by a
//! whole sheet (the device's coarser samples see a different number of crossings there); they
//! are counted and must stay rare (at most 3 % of the pixels shown); every other pixel must
//! agree.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::picture::check_view;
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::transfer::{Sheets, TransferFunction};
use galerkin::spectral::volume_reference::{compare_volume, volume_reference, VolumeColours};
use galerkin::spectral::{SpectralMesh, SpectralRenderer, SpectralView};

fn load(name: &str) -> SpectralMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
    galerkin::spectral::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

const TOLERANCE: f64 = 1.0 / 255.0;

/// Draws `view` and compares it with the reference of `tf` and `sheets`; returns how many
/// reference pixels let at most `behind` of the light through.
fn check(
    gpu: &galerkin::gpu::Gpu,
    name: &str,
    mesh: &Arc<SpectralMesh>,
    view: &SpectralView,
    tf: &TransferFunction,
    size: (u32, u32),
    behind: f64,
) -> usize {
    let colormap = Colormap::viridis();
    let target = RenderTarget::new(gpu, "sheets", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    let started = std::time::Instant::now();
    let mut renderer = SpectralRenderer::new(gpu, mesh.clone(), &colormap).expect("renderer");
    let Pixels::Rgba32F(px) = renderer.render(&target, view).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    let drawn = started.elapsed();
    let colours = VolumeColours { colormap: &colormap, range: mesh.value_range(0, 0), log: false };
    let sheets = view.sheets();
    assert_eq!(sheets.values, view.iso, "{name}: the volume pass draws the isosurfaces");
    let reference = volume_reference(mesh, (0, 0), &fit_camera(mesh), tf, &sheets, &colours, size, 16);
    let agreement = compare_volume(&px, &reference, TOLERANCE);
    eprintln!(
        "{name} (opacity {}): {} pixels, worst {:.2} of 1/255, mean {:.1e}, {} grazing ({} of them beyond 1/255), {} one-sided, {} mismatched; device {:.1} s",
        view.iso_opacity,
        agreement.shown,
        agreement.worst / TOLERANCE,
        agreement.mean,
        agreement.grazing,
        agreement.grazing_mismatched,
        agreement.missing,
        agreement.mismatched.len(),
        drawn.as_secs_f64(),
    );
    for m in agreement.mismatched.iter().take(6) {
        eprintln!("  pixel ({}, {}): {}", m.0 as u32 % size.0, m.0 as u32 / size.0, m.1);
    }
    assert!(agreement.shown > 300, "{name}: the mesh covers {} pixels", agreement.shown);
    assert!(
        agreement.mismatched.is_empty(),
        "{name}: {:?}",
        &agreement.mismatched[..agreement.mismatched.len().min(4)]
    );
    assert!(agreement.grazing * 100 <= 3 * agreement.shown, "{name}: {} grazing pixels", agreement.grazing);
    reference.iter().flatten().filter(|s| s.transmittance <= behind).count()
}

/// Transparent isosurfaces (opacity ½, a clear medium): several sheets per ray, composited in
/// ray order. A ray that crosses two sheets lets at most ¼ of the light through; enough rays do
/// that for the order of compositing to be tested.
#[test]
fn transparent_isosurfaces_match_the_f64_ray_caster() {
    let gpu = common::gpu();
    let saddle: &[f64] = &[0.0, 0.04, 0.12, -0.04];
    for (name, values) in [
        ("tet_cube_o3.vtu", None),
        ("tet_cube_o6.vtu", None),
        ("hex_saddle_o6.vtu", Some(saddle)),
        ("hex_saddle_o9.vtu", Some(saddle)),
    ] {
        let mesh = Arc::new(load(name));
        let (lo, hi) = mesh.value_range(0, 0);
        let values = values.map_or(vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)], |v| v.to_vec());
        let view = SpectralView { iso: values, iso_opacity: 0.5, overdraw: false, ..SpectralView::default() };
        assert!(view.uses_volume_pass());
        let layered = check(&gpu, name, &mesh, &view, &TransferFunction::clear(), (64, 48), 0.25 + 1e-9);
        assert!(layered > 100, "{name}: only {layered} rays cross two sheets or more");
    }
}

/// Isosurfaces inside a volume: an opaque sheet (opacity 1, what is behind it hidden) and a
/// half-transparent one in the volume's fog, with the volume integrated on both sides of each.
#[test]
fn isosurfaces_inside_a_volume_match_the_f64_ray_caster() {
    let gpu = common::gpu();
    for (name, opacity) in [("tet_cube_o3.vtu", 1.0), ("hex_saddle_o6.vtu", 0.5)] {
        let mesh = Arc::new(load(name));
        let (lo, hi) = mesh.value_range(0, 0);
        let at = |s: f64| lo + s * (hi - lo);
        let tf = TransferFunction::new(vec![(lo, 0.0), (at(0.5), 0.3), (hi, 0.1)], 0.25 * mesh.diagonal())
            .expect("valid");
        let view = SpectralView {
            volume: Some(tf.clone()),
            iso: vec![at(0.7)],
            iso_opacity: opacity,
            overdraw: false,
            ..SpectralView::default()
        };
        check(&gpu, name, &mesh, &view, &tf, (64, 48), 1.0);
    }
}

/// The reference with sheets has converged: twice the samples change no channel by more than
/// an eighth of the tolerance away from grazing rays (the saddle of order 9, four nested and
/// touching values).
#[test]
fn the_sheet_reference_is_converged() {
    let mesh = load("hex_saddle_o9.vtu");
    let colormap = Colormap::viridis();
    let colours = VolumeColours { colormap: &colormap, range: mesh.value_range(0, 0), log: false };
    let sheets = Sheets::new(vec![0.0, 0.04, 0.12, -0.04], 0.5).expect("sheets");
    let camera = fit_camera(&mesh);
    let tf = TransferFunction::clear();
    let size = (24, 18);
    let a = volume_reference(&mesh, (0, 0), &camera, &tf, &sheets, &colours, size, 16);
    let b = volume_reference(&mesh, (0, 0), &camera, &tf, &sheets, &colours, size, 32);
    let (worst, grazing) = common::volumes::reference_difference(&a, &b);
    eprintln!("doubling the samples changes a channel by {worst:.2e} ({grazing} grazing rays left out)");
    assert!(worst <= TOLERANCE / 8.0, "{worst}");
    assert!(grazing * 20 <= a.len(), "{grazing} grazing rays of {}", a.len());
}

/// What transparent isosurfaces cannot be is refused by name: an opacity outside (0, 1], and
/// element edges or a colouring field (opaque isosurfaces only) — by the view check and by the
/// renderer; sheets are checked when made. Isosurfaces in a volume are accepted.
#[test]
fn transparent_isosurface_views_that_cannot_be_drawn_are_refused() {
    let gpu = common::gpu();
    let tets = Arc::new(load("tet_cube_o3.vtu"));
    let iso = SpectralView { iso: vec![0.5], iso_opacity: 0.5, ..SpectralView::default() };
    for bad in [0.0, 1.5, f64::NAN] {
        let err = check_view(&tets, &SpectralView { iso_opacity: bad, ..iso.clone() }).expect_err("refused");
        assert!(err.to_string().contains("--iso-opacity"), "{err}");
    }
    // Isosurfaces in a volume are a view, not a conflict.
    let tf = TransferFunction::new(vec![(0.0, 0.0), (1.0, 0.5)], 1.0).expect("valid");
    check_view(&tets, &SpectralView { volume: Some(tf), iso: vec![0.5], ..SpectralView::default() })
        .expect("isosurfaces in a volume");
    let target = RenderTarget::new(&gpu, "sheets", 32, 24, ColorFormat::Rgba32F).expect("target");
    let mut r = SpectralRenderer::new(&gpu, tets.clone(), &Colormap::viridis()).expect("renderer");
    for view in
        [SpectralView { edges: true, ..iso.clone() }, SpectralView { colour_by: Some(0), ..iso.clone() }]
    {
        let err = check_view(&tets, &view).expect_err("refused").to_string();
        assert!(err.contains("opaque isosurfaces"), "{err}");
        let err = r.render(&target, &view).expect_err("refused").to_string();
        assert!(err.contains("--colour-by and --edges go with opaque isosurfaces"), "{err}");
    }
    assert!(Sheets::new(vec![0.5; 9], 0.5).expect_err("refused").contains("at most 8"));
    assert!(Sheets::new(vec![0.5], 0.0).expect_err("refused").contains("not in (0, 1]"));
    assert!(Sheets::new(vec![f64::INFINITY], 0.5).expect_err("refused").contains("not a finite number"));
}
