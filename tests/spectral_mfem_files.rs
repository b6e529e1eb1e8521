//! Files written by MFEM itself (`scripts/mfem-fixtures.py`, PyMFEM 4.10): curved
//! quadrilateral, hexahedral, triangular and tetrahedral meshes with GridFunctions in the H1
//! (Gauss–Lobatto), H1Pos (Bernstein) and L2 (Gauss–Legendre) collections, and MFEM's own
//! evaluation of geometry and field at reference points of every element, read back as MFEM
//! reads the files. Our reader must agree with MFEM at each.

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
    for name in [
        "quad_h1_p4",
        "quad_h1pos_p3",
        "quad_l2_p3",
        "hex_h1_p3",
        "tri_h1_p4",
        "tri_l2_p3",
        "tri_h1pos_p3",
        "tet_h1_p5",
        "tet_l2_p2",
        "tet_h1pos_p4",
    ] {
        let mesh =
            galerkin::spectral::load(&fixture(&format!("{name}.mesh")), &[fixture(&format!("{name}.gf"))])
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        let json = std::fs::read_to_string(fixture(&format!("{name}.json"))).expect("evaluations");
        let evaluations: Evaluations = serde_json::from_str(&json).expect("JSON");
        let gf = std::fs::read_to_string(fixture(&format!("{name}.gf"))).expect("gf");
        assert!(gf.contains(&evaluations.collection), "{name}: {}", evaluations.collection);
        assert!(evaluations.records.len() >= 5 * mesh.elements(), "{name}");
        let (worst_x, worst_u) = common::evaluations::worst_differences(&mesh, 0, &evaluations.records);
        // 17 digits in the files; evaluation rounding of order-5 polynomials of size ~1, and
        // for simplices the interpolation from MFEM's nodes to ours (a matrix of entries
        // below ~10): 1e-12 is a hundred times the rounding, a misplaced DOF errs by ~1e-2
        // (and a face DOF of the tetrahedra permuted wrongly by ~1e-3).
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

/// MFEM's local DOFs of its nodal simplex elements (`mfem_simplex::local_dofs` and
/// `dof_point`) sit where MFEM 4.10 puts them (`FiniteElement::GetNodes`), for H1 on
/// Gauss–Lobatto and equispaced points and L2 on Gauss–Legendre, Gauss–Lobatto and equispaced
/// points, triangles and tetrahedra of orders 1–6 (1e-14: 1D points from two computations of
/// the same roots, divided by sums near 1).
#[test]
fn mfem_simplex_dofs_sit_where_mfem_puts_them() {
    use galerkin::spectral::basis::Basis1d;
    use galerkin::spectral::mfem::parse_collection;
    use galerkin::spectral::mfem_simplex::{dof_point, local_dofs};
    use galerkin::spectral::simplex::SimplexShape;
    let json = std::fs::read_to_string(fixture("simplex_nodes.json")).expect("nodes");
    let data: serde_json::Value = serde_json::from_str(&json).expect("JSON");
    let elements = data["elements"].as_array().expect("elements");
    assert_eq!(elements.len(), 60);
    for element in elements {
        let name = element["collection"].as_str().expect("name");
        let c = parse_collection(name).unwrap_or_else(|| panic!("{name}"));
        let shape = if c.dim == 2 { SimplexShape::Triangle } else { SimplexShape::Tetrahedron };
        let x = Basis1d::new(c.set, c.order).expect("points").nodes;
        let dofs = local_dofs(shape, c.order, c.continuous);
        let want = element["points"].as_array().expect("points");
        assert_eq!(dofs.len(), want.len(), "{name}");
        for (k, (w, p)) in dofs.iter().zip(want).enumerate() {
            let r = dof_point(shape, w, &x);
            for (a, v) in p.as_array().expect("point").iter().enumerate() {
                let v = v.as_f64().expect("coordinate");
                assert!((r[a] - v).abs() < 1e-14, "{name} DOF {k}: {r:?} vs MFEM {p:?}");
            }
        }
    }
}

/// MFEM's curved triangles (H1 order 4, H1Pos order 3 and L2 order 3 on cubic geometry)
/// rendered per pixel, and its curved tetrahedra (H1 order 5 on quartic geometry) through an
/// axis plane and an oblique one: every covered pixel shows the field at its point (the f64
/// reference, which agrees with MFEM's own evaluation to 1e-12 above) within the pixel's f32
/// bound, and no pixel inside an element is missing.
#[test]
fn curved_simplices_mfem_wrote_render_pixel_exact() {
    use galerkin::spectral::reference::check_cut_pixels;
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let (w, h) = (240u32, 160u32);
    let target = RenderTarget::new(&gpu, "mfem simplices", w, h, ColorFormat::Rgba32F).expect("target");
    for name in ["tri_h1_p4", "tri_h1pos_p3", "tri_l2_p3"] {
        let mesh = Arc::new(
            galerkin::spectral::load(&fixture(&format!("{name}.mesh")), &[fixture(&format!("{name}.gf"))])
                .unwrap_or_else(|e| panic!("{name}: {e}")),
        );
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let view = SpectralView { overdraw: false, ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let report = check_pixels(&mesh, 0, 0, &View2d::fit(&mesh, w, h), (w, h), &px);
        eprintln!("{name}: {report:?}");
        assert!(report.passed() && report.covered > 10_000, "{name}: {report:?}");
    }
    let mesh = Arc::new(
        galerkin::spectral::load(&fixture("tet_h1_p5.mesh"), &[fixture("tet_h1_p5.gf")])
            .expect("MFEM's tetrahedra"),
    );
    let camera = fit_camera(&mesh);
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    for cut in [[0.0, 0.0, 1.0, 0.3], [1.0, 0.7, 2.0, 0.9]] {
        let view = SpectralView { overdraw: false, cuts: vec![cut], ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let report = check_cut_pixels(&mesh, 0, 0, &camera, &[cut], (w, h), &px);
        eprintln!("tet_h1_p5 plane {cut:?}: {report:?}");
        assert!(report.covered > 1500 && report.passed(), "tet_h1_p5 plane {cut:?}: {report:?}");
    }
}

/// A mesh that mixes triangles and quadrilaterals, and a tetrahedral mesh whose GridFunction
/// claims more DOFs than its space has, are refused naming the file and the line, element or
/// field.
#[test]
fn mixed_or_mismatched_simplex_meshes_are_refused_by_name() {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = std::fs::read_to_string(fixture("tri_h1_p4.mesh")).expect("mesh");
    let first = text.lines().position(|l| l.trim() == "elements").expect("elements") + 2;
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let element = lines[first + 1].clone();
    let fields: Vec<&str> = element.split_whitespace().collect();
    // Element 1 as a quadrilateral of its three vertices and the first one again.
    lines[first + 1] = format!("{} 3 {} {} {} {}", fields[0], fields[2], fields[3], fields[4], 999);
    let mixed = dir.path().join("mixed.mesh");
    std::fs::write(&mixed, lines.join("\n")).expect("written");
    let err = galerkin::spectral::load(&mixed, &[fixture("tri_h1_p4.gf")]).expect_err("mixed").to_string();
    assert!(
        err.contains("mixed.mesh")
            && err.contains("element 1")
            && err.contains("one element geometry per mesh"),
        "{err}"
    );
    let gf = std::fs::read_to_string(fixture("tet_h1_p5.gf")).expect("gf");
    let longer = dir.path().join("longer.gf");
    std::fs::write(&longer, format!("{}\n0.5\n", gf.trim_end())).expect("written");
    let err = galerkin::spectral::load(&fixture("tet_h1_p5.mesh"), &[longer]).expect_err("long").to_string();
    assert!(err.contains("longer.gf") && err.contains("values for") && err.contains("H1_3D_P5"), "{err}");
}
