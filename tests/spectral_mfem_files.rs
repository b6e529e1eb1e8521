//! Files written by MFEM itself (`scripts/mfem-fixtures.py`, PyMFEM 4.10): curved
//! quadrilateral and hexahedral meshes with GridFunctions in the H1 (Gauss–Lobatto), H1Pos
//! (Bernstein) and L2 (Gauss–Legendre) collections, and MFEM's own evaluation of geometry and
//! field at reference points of every element. Our reader must agree with MFEM at each.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::reference::check_pixels;
use galerkin::spectral::{SpectralRenderer, SpectralView, View2d};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mfem").join(name)
}

#[derive(serde::Deserialize)]
struct Evaluations {
    collection: String,
    records: Vec<common::evaluations::Record>,
}

#[test]
fn meshes_and_fields_mfem_wrote_evaluate_as_mfem_evaluates_them() {
    for name in ["quad_h1_p4", "quad_h1pos_p3", "quad_l2_p3", "hex_h1_p3"] {
        let mesh =
            galerkin::spectral::load(&fixture(&format!("{name}.mesh")), &[fixture(&format!("{name}.gf"))])
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        let json = std::fs::read_to_string(fixture(&format!("{name}.json"))).expect("evaluations");
        let evaluations: Evaluations = serde_json::from_str(&json).expect("JSON");
        let gf = std::fs::read_to_string(fixture(&format!("{name}.gf"))).expect("gf");
        assert!(gf.contains(&evaluations.collection), "{name}: {}", evaluations.collection);
        assert!(evaluations.records.len() >= 5 * mesh.elements(), "{name}");
        let (worst_x, worst_u) = common::evaluations::worst_differences(&mesh, 0, &evaluations.records);
        // 17 digits in the files; evaluation rounding of order-4 polynomials of size ~1:
        // 1e-12 is a thousand times the rounding, a misplaced DOF errs by ~1e-2.
        eprintln!("{name}: geometry {worst_x:e}, field {worst_u:e}");
        assert!(worst_x < 1e-12, "{name}: geometry off by {worst_x:e}");
        assert!(worst_u < 1e-12, "{name}: field off by {worst_u:e}");
    }
}

/// MFEM's curved quadrilaterals rendered per pixel: every covered pixel shows the field at its
/// centre (the f64 reference, which agrees with MFEM's own evaluation to 4e-16 above) within
/// the pixel's f32 bound, and no pixel inside an element is missing — for the H1, H1Pos and
/// discontinuous L2 fields.
#[test]
fn curved_quadrilaterals_mfem_wrote_render_pixel_exact() {
    let gpu = common::gpu();
    let (w, h) = (240, 160);
    for name in ["quad_h1_p4", "quad_h1pos_p3", "quad_l2_p3"] {
        let mesh = Arc::new(
            galerkin::spectral::load(&fixture(&format!("{name}.mesh")), &[fixture(&format!("{name}.gf"))])
                .unwrap_or_else(|e| panic!("{name}: {e}")),
        );
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let target = RenderTarget::new(&gpu, "mfem fixture", w, h, ColorFormat::Rgba32F).expect("target");
        let view = SpectralView { overdraw: false, ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let report = check_pixels(&mesh, 0, 0, &View2d::fit(&mesh, w, h), (w, h), &px);
        assert!(report.passed() && report.covered > 10_000, "{name}: {report:?}");
    }
}

/// MFEM's curved hexahedra (H1, order 3 on quadratic geometry) through cut planes — across the
/// middle, on the mesh's top face, through the curved faces between elements, and oblique: every
/// covered pixel shows the field at its point on the plane (the f64 reference, which agrees with
/// MFEM's own evaluation to 4e-16 above) within the pixel's f32 bound, none outside its
/// element, none inside an element missing.
#[test]
fn curved_hexahedra_mfem_wrote_render_pixel_exact_through_cut_planes() {
    use galerkin::spectral::reference::check_cut_pixels;
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let size = (240u32, 180u32);
    let mesh = Arc::new(
        galerkin::spectral::load(&fixture("hex_h1_p3.mesh"), &[fixture("hex_h1_p3.gf")])
            .expect("MFEM's hexahedra"),
    );
    let camera = fit_camera(&mesh);
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let target =
        RenderTarget::new(&gpu, "mfem hexahedra", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    for cut in [[0.0, 0.0, 1.0, 0.25], [0.0, 0.0, 1.0, 0.5], [1.0, 0.0, 0.0, 0.5], [1.0, 0.7, 2.0, 0.9]] {
        let view = SpectralView { overdraw: false, cuts: vec![cut], ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let report = check_cut_pixels(&mesh, 0, 0, &camera, &[cut], size, &px);
        eprintln!("plane {cut:?}: {report:?}");
        assert!(report.covered > 1500 && report.passed(), "plane {cut:?}: {report:?}");
    }
}
