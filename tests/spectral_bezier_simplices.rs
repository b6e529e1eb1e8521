//! Bézier triangles and tetrahedra (`VTK_BEZIER_TRIANGLE` = 76, `VTK_BEZIER_TETRAHEDRON` =
//! 78) as VTK 9.7 writes them (`scripts/vtk-simplex-fixtures.py bezier`: curved, order 5 on
//! eight triangles and order 4 on a cube of six tetrahedra, the points and point data Bernstein
//! coefficients). They load as Lagrange simplices of the same order — the same polynomial,
//! its values at the equispaced nodes (`simplex::FromBernstein`) — whose evaluation equals
//! VTK's own (`EvaluateLocation`) and the plain Bernstein evaluation of [`SimplexElements`];
//! drawn on the device they pass the per-pixel f64 checks the Lagrange files pass. Rational
//! ones (weights other than 1) are refused by name.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::reference::{check_cut_pixels, check_pixels};
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::simplex::{FromBernstein, SimplexShape, ToBernstein};
use galerkin::spectral::simplex_mesh::SimplexElements;
use galerkin::spectral::{Shape, SpectralRenderer, SpectralView, View2d};

fn path(name: &str, ext: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(format!("{name}.{ext}"))
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

/// The Bézier files with their shape, order and element count.
const FILES: [(&str, Shape, usize, usize); 2] =
    [("bezier_tri_o5", Shape::Triangle, 5, 8), ("bezier_tet_o4", Shape::Tetrahedron, 4, 6)];

/// Read through `spectral::load`, each Bézier file is a simplex mesh of its order whose map and
/// field equal VTK's `EvaluateLocation` and Bernstein-interpolated field at VTK's samples
/// (1e-11: the conversion to nodal values is a product with a matrix of entries ≤ 1 summed
/// over ≤ 35 terms, then the Lagrange sums, whose order-5 basis values stay below 10); and on
/// a lattice of every element they equal the plain evaluation that sums each control point's
/// Bernstein polynomial (`SimplexElements`, no conversion), value and Jacobian (1e-9: the
/// derivatives reach ~10²), and so does VTK's at its samples.
#[test]
fn vtk_bezier_simplices_evaluate_as_vtk_does() {
    for (name, shape, order, elements) in FILES {
        let mesh =
            galerkin::spectral::load(&path(name, "vtu"), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((mesh.shape, mesh.geometry.order, mesh.elements()), (shape, order, elements), "{name}");
        let plain = SimplexElements::read(&path(name, "vtu")).expect("plain reader");
        assert_eq!((plain.order, plain.len()), (order, elements));
        let text = std::fs::read_to_string(path(name, "json")).expect("VTK's samples");
        let data: serde_json::Value = serde_json::from_str(&text).expect("json");
        let samples = data["samples"].as_array().expect("samples");
        assert_eq!(samples.len(), 3 * elements);
        for s in samples {
            let e = s["element"].as_u64().expect("element") as usize;
            let r = floats(&s["r"]);
            let r = [r[0], r[1], r.get(2).copied().unwrap_or(0.0)];
            let x = if shape == Shape::Triangle { mesh.map(e, r[0], r[1]).0 } else { mesh.map_hex(e, r).0 };
            let want = floats(&s["x"]);
            let (y, _) = plain.map(e, &r);
            for c in 0..3 {
                assert!((x[c] - want[c]).abs() < 1e-11, "{name} element {e} at {r:?}: {x:?} vs VTK {want:?}");
                assert!(
                    (y[c] - want[c]).abs() < 1e-12,
                    "{name} element {e} at {r:?}: plain {y:?} vs VTK {want:?}"
                );
            }
            let u = if shape == Shape::Triangle {
                mesh.value(0, 0, e, r[0], r[1])
            } else {
                mesh.value_hex(0, 0, e, r)
            };
            let want_u = s["u"].as_f64().expect("u");
            assert!((u - want_u).abs() < 1e-11, "{name} element {e} at {r:?}: u {u} vs VTK {want_u}");
            assert!((plain.value(e, 0, &r) - want_u).abs() < 1e-12, "{name} element {e}: plain u");
        }
        let s = 6;
        let depth = if shape == Shape::Triangle { 0 } else { s };
        for e in 0..elements {
            for k in 0..=depth {
                for j in 0..=s - k {
                    for i in 0..=s - k - j {
                        let r = [i, j, k].map(|c| c as f64 / s as f64);
                        let (y, want) = plain.map(e, &r);
                        let (x, jac): ([f64; 3], Vec<[f64; 3]>) = if shape == Shape::Triangle {
                            let (x, jac) = mesh.map(e, r[0], r[1]);
                            (x, jac.to_vec())
                        } else {
                            let (x, jac) = mesh.map_hex(e, r);
                            (x, jac.to_vec())
                        };
                        for c in 0..3 {
                            assert!((x[c] - y[c]).abs() < 1e-11, "{name} {e} {r:?}: {x:?} vs {y:?}");
                            for (a, column) in jac.iter().enumerate() {
                                assert!((column[c] - want[a][c]).abs() < 1e-9, "{name} {e} {r:?} ∂/∂r{a}");
                            }
                        }
                        let u = if shape == Shape::Triangle {
                            mesh.value(0, 0, e, r[0], r[1])
                        } else {
                            mesh.value_hex(0, 0, e, r)
                        };
                        let v = plain.value(e, 0, &r);
                        assert!((u - v).abs() < 1e-11, "{name} {e} {r:?}: {u} vs {v}");
                    }
                }
            }
        }
    }
}

/// The conversion to nodal values and the one back to Bernstein coefficients are inverse to
/// each other for every shape and order 1–10 (1e-9 of coefficients of size 1: the
/// collocation matrix of order 10's condition number is ~10⁴).
#[test]
fn from_bernstein_and_to_bernstein_are_inverse() {
    for shape in [SimplexShape::Triangle, SimplexShape::Tetrahedron] {
        for n in 1..=10 {
            let (from, to) = (FromBernstein::new(shape, n), ToBernstein::new(shape, n).expect("invertible"));
            let control: Vec<f64> =
                (0..shape.node_count(n)).map(|k| ((k * 7919) % 101) as f64 / 50.0 - 1.0).collect();
            let back = to.control_values(&from.nodal_values(&control));
            for (a, b) in control.iter().zip(&back) {
                assert!((a - b).abs() < 1e-9, "{shape:?} order {n}: {a} vs {b}");
            }
        }
    }
}

/// Drawn on the device, the Bézier triangles pass the per-pixel check of the Lagrange ones
/// (each covered pixel the f64 value at its centre within its f32 bound, no pixel inside an
/// element missed) and the tetrahedra the cut-plane check, under an axis plane and an
/// oblique one.
#[test]
fn vtk_bezier_simplices_render_pixel_exact() {
    let gpu = common::gpu();
    let mesh = Arc::new(galerkin::spectral::load(&path("bezier_tri_o5", "vtu"), &[]).expect("read"));
    let (w, h) = (192u32, 192u32);
    let target = RenderTarget::new(&gpu, "bezier", w, h, ColorFormat::Rgba32F).expect("target");
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let Pixels::Rgba32F(px) = r.render(&target, &SpectralView::default()).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    let report = check_pixels(&mesh, 0, 0, &View2d::fit(&mesh, w, h), (w, h), &px);
    eprintln!("bezier_tri_o5: {report:?}");
    // The bent unit square fills most of the fitted 192 × 192 picture.
    assert!(report.passed() && report.covered > 15_000, "bezier_tri_o5: {report:?}");
    drop(r);
    let mesh = Arc::new(galerkin::spectral::load(&path("bezier_tet_o4", "vtu"), &[]).expect("read"));
    let camera = fit_camera(&mesh);
    let (lo, hi) = mesh.bounds();
    let mid: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    for cut in
        [[0.0, 0.0, 1.0, 0.3 * lo[2] + 0.7 * mid[2]], [0.3, 0.2, 1.0, 0.3 * mid[0] + 0.2 * mid[1] + mid[2]]]
    {
        let view = SpectralView { overdraw: false, cuts: vec![cut], ..SpectralView::default() };
        let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let report = check_cut_pixels(&mesh, 0, 0, &camera, &[cut], (w, h), &px);
        eprintln!("bezier_tet_o4 plane {cut:?}: {report:?}");
        assert!(report.covered > 500 && report.passed(), "bezier_tet_o4 plane {cut:?}: {report:?}");
    }
}

/// A rational Bézier triangle (RationalWeights other than 1, as VTK wrote it) is refused
/// naming the file, the element and the array, by the loader and the plain reader; the same
/// cell with weights all 1 is polynomial and loads.
#[test]
fn rational_bezier_simplices_are_refused_by_name() {
    let file = path("bezier_tri_rational", "vtu");
    let err = galerkin::spectral::load(&file, &[]).expect_err("rational simplex").to_string();
    assert!(
        err.contains("bezier_tri_rational.vtu")
            && err.contains("element 0")
            && err.contains("RationalWeights"),
        "{err}"
    );
    let err = SimplexElements::read(&file).expect_err("rational simplex").to_string();
    assert!(err.contains("bezier_tri_rational.vtu") && err.contains("RationalWeights"), "{err}");
    let text = std::fs::read_to_string(&file).expect("fixture");
    let start = text.find("Name=\"RationalWeights\"").expect("weights array");
    let line_start = start + text[start..].find('\n').expect("values line") + 1;
    let line_end = line_start + text[line_start..].find('\n').expect("end of values");
    let ones = format!(
        "{text_before}          1 1 1 1 1 1{rest}",
        text_before = &text[..line_start],
        rest = &text[line_end..]
    );
    let dir = tempfile::tempdir().expect("temp dir");
    let polynomial = dir.path().join("ones.vtu");
    std::fs::write(&polynomial, ones).expect("written");
    let mesh = galerkin::spectral::load(&polynomial, &[]).expect("weights of 1 are polynomial");
    assert_eq!((mesh.shape, mesh.geometry.order, mesh.elements()), (Shape::Triangle, 2, 1));
}
