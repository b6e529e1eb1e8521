//! Lagrange triangles drawn per pixel like the quadrilaterals (seed 002, issue "high-order
//! simplices"): `.vtu` files of `VTK_LAGRANGE_TRIANGLE` (69) that VTK 9.7 wrote
//! (`scripts/vtk-simplex-fixtures.py`: curved, orders 3, 6 and 10) read as a [`SpectralMesh`]
//! of [`Shape::Triangle`], whose evaluation (Silvester's basis in rows, the twin of
//! `spectral_simplex.glsl`) equals VTK's own and the plain node-by-node evaluation of
//! [`SimplexElements`]; rendered on the device, every covered pixel shows the f64 value at its
//! centre within that pixel's f32 rounding bound, and no pixel inside an element is missed;
//! lifted off the plane (a surface in 3D) or as a height field, they are tessellated on the
//! device within the half-pixel budget.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::reference::check_pixels;
use galerkin::spectral::simplex_mesh::SimplexElements;
use galerkin::spectral::{Shape, SpectralMesh, SpectralRenderer, SpectralView, View2d};

/// The VTK-written triangle files with their order and element count.
const FILES: [(&str, usize, usize); 3] =
    [("tri_curved", 3, 2), ("tri_curved_o6", 6, 8), ("tri_curved_o10", 10, 2)];

fn path(name: &str, ext: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(format!("{name}.{ext}"))
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

/// Read through `spectral::load`, each file is a triangle mesh of its order whose map and
/// field equal VTK's `EvaluateLocation` and interpolated field at VTK's samples (1e-11: the
/// same sums in another order, of order-10 basis values up to ~10³ in size), and equal the
/// plain evaluation (every node's basis function in VTK's order, `SimplexElements`) on a
/// lattice of points of every element (the same 1e-11). Geometry orders above 10 are no
/// triangle's, so they are refused.
#[test]
fn vtk_triangles_load_as_spectral_meshes_that_evaluate_as_vtk_does() {
    for (name, order, elements) in FILES {
        let mesh =
            galerkin::spectral::load(&path(name, "vtu"), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            (mesh.shape, mesh.geometry.order, mesh.basis.order),
            (Shape::Triangle, order, order),
            "{name}"
        );
        assert_eq!(mesh.elements(), elements, "{name}");
        assert!(mesh.is_planar());
        let text = std::fs::read_to_string(path(name, "json")).expect("VTK's samples");
        let data: serde_json::Value = serde_json::from_str(&text).expect("json");
        for s in data["samples"].as_array().expect("samples") {
            let e = s["element"].as_u64().expect("element") as usize;
            let r = floats(&s["r"]);
            let (x, _) = mesh.map(e, r[0], r[1]);
            let want = floats(&s["x"]);
            for c in 0..3 {
                assert!((x[c] - want[c]).abs() < 1e-11, "{name} element {e} at {r:?}: {x:?} vs VTK {want:?}");
            }
            let u = mesh.value(0, 0, e, r[0], r[1]);
            let want_u = s["u"].as_f64().expect("u");
            assert!((u - want_u).abs() < 1e-11, "{name} element {e} at {r:?}: u {u} vs VTK {want_u}");
        }
        let plain = SimplexElements::read(&path(name, "vtu")).expect("plain reader");
        for e in 0..elements {
            for j in 0..=7 {
                for i in 0..=7 - j {
                    let r = [i as f64 / 7.0, j as f64 / 7.0];
                    let (x, [dx, dy]) = mesh.map(e, r[0], r[1]);
                    let (y, jac) = plain.map(e, &[r[0], r[1], 0.0]);
                    for c in 0..3 {
                        assert!((x[c] - y[c]).abs() < 1e-11, "{name} {e} {r:?}: x {x:?} vs {y:?}");
                        assert!(
                            (dx[c] - jac[0][c]).abs() < 1e-9,
                            "{name} {e} {r:?}: ∂x/∂ξ {dx:?} vs {:?}",
                            jac[0]
                        );
                        assert!(
                            (dy[c] - jac[1][c]).abs() < 1e-9,
                            "{name} {e} {r:?}: ∂x/∂η {dy:?} vs {:?}",
                            jac[1]
                        );
                    }
                    let (u, v) = (mesh.value(0, 0, e, r[0], r[1]), plain.value(e, 0, &[r[0], r[1], 0.0]));
                    assert!((u - v).abs() < 1e-11, "{name} {e} {r:?}: {u} vs {v}");
                    // The gradient (derived fields' `grad`) against a central difference.
                    let (g, [gx, gy]) = mesh.value_gradient(0, 0, e, r[0], r[1]);
                    assert!((g - u).abs() < 1e-12);
                    let h = 1e-6;
                    let fd = (mesh.value(0, 0, e, r[0] + h, r[1]) - mesh.value(0, 0, e, r[0] - h, r[1]))
                        / (2.0 * h);
                    let fe = (mesh.value(0, 0, e, r[0], r[1] + h) - mesh.value(0, 0, e, r[0], r[1] - h))
                        / (2.0 * h);
                    assert!(
                        (gx - fd).abs() < 1e-5 && (gy - fe).abs() < 1e-5,
                        "{name} {e} {r:?}: ∇ ({gx}, {gy}) vs ({fd}, {fe})"
                    );
                }
            }
        }
    }
}

/// Written back by our `.vtu` writer (VTK's node order for type 69, each node evaluated
/// through the map and field) and read again, a triangle mesh has the same nodes and values
/// to 1e-14 (the evaluation's rounding at a node: a node out of place would be ~0.1 off).
#[test]
fn triangles_round_trip_through_our_vtu_writer() {
    let mesh = galerkin::spectral::load(&path("tri_curved_o6", "vtu"), &[]).expect("read");
    let dir = tempfile::tempdir().expect("scratch");
    let out = dir.path().join("back.vtu");
    galerkin::spectral::vtu::write(&out, &mesh).expect("written");
    let back = galerkin::spectral::load(&out, &[]).expect("read back");
    assert_eq!((back.shape, back.elements()), (Shape::Triangle, mesh.elements()));
    for (a, b) in back.points.iter().zip(&mesh.points) {
        assert!((0..3).all(|c| (a[c] - b[c]).abs() < 1e-14), "{a:?} vs {b:?}");
    }
    for (a, b) in back.fields[0].steps[0].iter().zip(&mesh.fields[0].steps[0]) {
        assert!((a - b).abs() < 1e-14, "{a} vs {b}");
    }
}

fn render(
    gpu: &galerkin::gpu::Gpu,
    mesh: &Arc<SpectralMesh>,
    view: &SpectralView,
    size: (u32, u32),
) -> Vec<f32> {
    let mut r = SpectralRenderer::new(gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let target = RenderTarget::new(gpu, "triangles", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    let Pixels::Rgba32F(px) = r.render(&target, view).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    px
}

/// Every VTK-written triangle mesh drawn per pixel passes the f64 per-pixel check: each
/// covered pixel shows the element's polynomial at the reference point the f64 inverse map
/// finds for its centre, within that pixel's f32 rounding bound (`rounding_bound`'s
/// triangle branch), in the element that contains the centre, and no pixel whose centre lies
/// inside an element (by 10⁻³ of the reference triangle) is left uncovered — so the curved
/// edges are exact and the shared ones have no crack. With edge overdraw and a zoomed view
/// onto a corner where four curved triangles meet, the same holds.
#[test]
fn vtk_written_triangles_render_pixel_exact() {
    let gpu = common::gpu();
    let (w, h) = (256, 256);
    for (name, _, elements) in FILES {
        let mesh = Arc::new(galerkin::spectral::load(&path(name, "vtu"), &[]).expect("read"));
        let px = render(&gpu, &mesh, &SpectralView::default(), (w, h));
        let report = check_pixels(&mesh, 0, 0, &View2d::fit(&mesh, w, h), (w, h), &px);
        eprintln!("{name}: {report:?}");
        assert!(report.passed(), "{name}: {report:?}");
        // The unit square, bent, fills most of the fitted picture.
        assert!(report.covered > 30_000, "{name}: {report:?}");
        let drawn: std::collections::BTreeSet<i64> =
            px.chunks_exact(4).filter(|t| t[3] >= 0.0).map(|t| t[3] as i64).collect();
        assert_eq!(drawn.len(), elements, "{name}: every element draws");
    }
    let mesh = Arc::new(galerkin::spectral::load(&path("tri_curved_o6", "vtu"), &[]).expect("read"));
    // Around (0.5, 0.5) bent (the script's bend: x + 0.08 sin 2y, y + 0.06 sin 1.7x): the
    // grid's centre, where six curved triangles meet, 0.05 wide.
    let view =
        View2d { centre: [0.5 + 0.08 * 1f64.sin(), 0.5 + 0.06 * 0.85f64.sin()], pixel_size: 0.05 / 256.0 };
    let shown = SpectralView { view: Some(view), overdraw: true, ..SpectralView::default() };
    let px = render(&gpu, &mesh, &shown, (w, h));
    let report = check_pixels(&mesh, 0, 0, &view, (w, h), &px);
    eprintln!("zoomed: {report:?}");
    assert!(report.passed() && report.covered > 60_000, "zoomed: {report:?}");
}

/// Curved triangles forming a surface in 3D (`tri_surface_o4.vtu`, order 4, VTK-written,
/// z = 0.3 sin(2.2x + 0.4) cos(1.3y) at the nodes) and the height field of the planar order-6
/// triangles: tessellated on the device like quadrilateral surfaces, every covered pixel shows
/// the polynomial at a reference point whose surface point projects within the ½-pixel budget
/// of the pixel centre (plus 0.01 px of f32 slack, as for quadrilaterals), the value there
/// within its pixel's f32 bound; the device writes as many vertices as the CPU twin of the
/// levels says (3 L² per triangle; 2 % for levels where ceil meets rounding), none skipped; and
/// a coarse budget visibly breaks the bound (so the check can fail).
#[test]
fn triangle_surfaces_and_height_fields_show_the_field_within_half_a_pixel() {
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let size = (256u32, 192u32);
    let mesh = Arc::new(galerkin::spectral::load(&path("tri_surface_o4", "vtu"), &[]).expect("read"));
    assert!(!mesh.is_planar());
    let camera = fit_camera(&mesh);
    let target =
        RenderTarget::new(&gpu, "triangle surface", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let mut farthest = |budget: f64| {
        let view = SpectralView { overdraw: false, max_error_px: budget, ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let (written, skipped) = r.last_tessellation().expect("counts").expect("a surface frame");
        let expected = r.expected_tessellation(&target, &view);
        let report = common::surfaces::surface_errors(&mesh, &px, &camera, size, |e, q| {
            glam::DVec3::from(mesh.map(e, q[0], q[1]).0)
        });
        (report, written, skipped, expected)
    };
    let ((covered, worst, worst_value), written, skipped, expected) = farthest(0.5);
    eprintln!("triangle surface: {covered} pixels, farthest {worst:.3} px, value error {worst_value:.3} of its bound; {written} vertices (CPU twin {expected})");
    // The lifted unit square, seen from the fitted camera's oblique view, covers ~5,000 pixels.
    assert!(covered > 4_000, "{covered}");
    assert!(worst <= 0.5 + 0.01, "a pixel shows a surface point {worst} px away");
    assert!(worst_value <= 1.0, "value error {worst_value} of its bound");
    assert_eq!(skipped, 0);
    assert!(
        (f64::from(written) - expected as f64).abs() <= 0.02 * expected as f64,
        "{written} vs {expected}"
    );
    let ((_, coarse, _), ..) = farthest(16.0);
    eprintln!("budget 16 px: farthest {coarse:.3} px");
    assert!(coarse > 0.5, "a coarse tessellation should break the half-pixel bound ({coarse})");

    let flat = Arc::new(galerkin::spectral::load(&path("tri_curved_o6", "vtu"), &[]).expect("read"));
    let mut r = SpectralRenderer::new(&gpu, flat.clone(), &Colormap::viridis()).expect("renderer");
    let scale = 0.2;
    let view = SpectralView { overdraw: false, height: Some(scale), ..SpectralView::default() };
    let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    // The camera the renderer fits to the lifted box.
    let (lo, hi) = r.range(&view);
    let (mut a, mut b) = flat.bounds();
    a[2] = scale * lo;
    b[2] = scale * hi;
    let camera = galerkin::spectral::render::camera_for_box(a, b);
    let (covered, worst, worst_value) =
        common::surfaces::surface_errors(&flat, &px, &camera, size, |e, q| {
            let (x, _) = flat.map(e, q[0], q[1]);
            glam::DVec3::new(x[0], x[1], scale * flat.value(0, 0, e, q[0], q[1]))
        });
    eprintln!("triangle height field: {covered} pixels, farthest {worst:.3} px, value error {worst_value:.3} of its bound");
    // The lifted square from the fitted camera covers ~7,600 pixels.
    assert!(covered > 5_000, "{covered}");
    assert!(worst <= 0.5 + 0.01, "a pixel shows a point {worst} px away");
    assert!(worst_value <= 1.0, "value error {worst_value} of its bound");
}
