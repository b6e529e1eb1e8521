//! Lagrange tetrahedra drawn by cut planes like the hexahedra (seed 002's cut planes, issue
//! "high-order simplices"): `.vtu` files of `VTK_LAGRANGE_TETRAHEDRON` (71) that VTK 9.7 wrote
//! (`scripts/vtk-simplex-fixtures.py`: curved, order 3 on two cells and orders 3 and 6 on a
//! cube of six) read as a [`SpectralMesh`] of [`Shape::Tetrahedron`], whose evaluation
//! (Silvester's basis in four rows, the twin of `spectral_simplex.glsl`) equals VTK's own and
//! the plain node-by-node evaluation of [`SimplexElements`]; cut on the device, every covered
//! pixel shows the f64 value at its point on the plane within that pixel's f32 rounding bound,
//! and no pixel whose point lies inside an element is missed.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::reference::check_cut_pixels;
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::simplex::{SimplexShape, ToBernstein};
use galerkin::spectral::simplex_mesh::SimplexElements;
use galerkin::spectral::{Shape, SpectralRenderer, SpectralView};

/// The VTK-written tetrahedron files with their order and element count.
const FILES: [(&str, usize, usize); 3] = [("tet_curved", 3, 2), ("tet_cube_o3", 3, 6), ("tet_cube_o6", 6, 6)];

fn path(name: &str, ext: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(format!("{name}.{ext}"))
}

fn floats(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
}

/// Read through `spectral::load`, each file is a tetrahedral mesh of its order whose map and
/// field equal VTK's `EvaluateLocation` and interpolated field at VTK's samples (1e-11: the
/// same sums in another order), and the plain evaluation (`SimplexElements`, every node's basis
/// function in VTK's order) on a lattice of points of every element, Jacobian included (1e-9:
/// derivatives of order-6 bases reach ~10²); the field's gradient agrees with central
/// differences (1e-5: the differences' own truncation at h = 10⁻⁶).
#[test]
fn vtk_tetrahedra_load_as_spectral_meshes_that_evaluate_as_vtk_does() {
    for (name, order, elements) in FILES {
        let mesh =
            galerkin::spectral::load(&path(name, "vtu"), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((mesh.shape, mesh.geometry.order, mesh.elements()), (Shape::Tetrahedron, order, elements));
        let text = std::fs::read_to_string(path(name, "json")).expect("VTK's samples");
        let data: serde_json::Value = serde_json::from_str(&text).expect("json");
        for s in data["samples"].as_array().expect("samples") {
            let e = s["element"].as_u64().expect("element") as usize;
            let r = floats(&s["r"]);
            let r = [r[0], r[1], r[2]];
            let (x, _) = mesh.map_hex(e, r);
            let want = floats(&s["x"]);
            for c in 0..3 {
                assert!((x[c] - want[c]).abs() < 1e-11, "{name} element {e} at {r:?}: {x:?} vs VTK {want:?}");
            }
            let u = mesh.value_hex(0, 0, e, r);
            let want_u = s["u"].as_f64().expect("u");
            assert!((u - want_u).abs() < 1e-11, "{name} element {e} at {r:?}: u {u} vs VTK {want_u}");
            let back = mesh.inverse_map_hex(e, x, [0.25; 3]).expect("Newton converges");
            assert!((0..3).all(|a| (back[a] - r[a]).abs() < 1e-10), "{name} {e}: {back:?} vs {r:?}");
        }
        let plain = SimplexElements::read(&path(name, "vtu")).expect("plain reader");
        let s = 5;
        for e in 0..elements {
            for k in 0..=s {
                for j in 0..=s - k {
                    for i in 0..=s - k - j {
                        let r = [i, j, k].map(|c| c as f64 / s as f64);
                        let (x, jac) = mesh.map_hex(e, r);
                        let (y, want) = plain.map(e, &r);
                        for c in 0..3 {
                            assert!((x[c] - y[c]).abs() < 1e-11, "{name} {e} {r:?}: {x:?} vs {y:?}");
                            for a in 0..3 {
                                assert!((jac[a][c] - want[a][c]).abs() < 1e-9, "{name} {e} {r:?} ∂/∂r{a}");
                            }
                        }
                        let (u, v) = (mesh.value_hex(0, 0, e, r), plain.value(e, 0, &r));
                        assert!((u - v).abs() < 1e-11, "{name} {e} {r:?}: {u} vs {v}");
                        let (g, grad) = mesh.value_gradient_at(0, 0, e, r);
                        assert!((g - u).abs() < 1e-12);
                        for a in 0..3 {
                            let h = 1e-6;
                            let (mut p, mut m) = (r, r);
                            p[a] += h;
                            m[a] -= h;
                            let fd = (mesh.value_hex(0, 0, e, p) - mesh.value_hex(0, 0, e, m)) / (2.0 * h);
                            assert!(
                                (grad[a] - fd).abs() < 1e-5,
                                "{name} {e} {r:?}: ∂f/∂r{a} {} vs {fd}",
                                grad[a]
                            );
                        }
                    }
                }
            }
        }
    }
}

/// The Bernstein control points the cut pass tests planes against reproduce the element
/// (their Bernstein sum at the Lagrange nodes is the node, 1e-12), and their convex hull holds
/// every sampled point of the curved element: each sample lies within the control points' box
/// (a necessary condition of the hull, which is what a plane test relies on).
#[test]
fn bernstein_control_points_of_curved_tetrahedra_contain_them() {
    let mesh = galerkin::spectral::load(&path("tet_cube_o6", "vtu"), &[]).expect("read");
    let convert = ToBernstein::new(SimplexShape::Tetrahedron, 6).expect("invertible");
    for e in 0..mesh.elements() {
        let control = convert.control_points(mesh.element_points(e));
        let (lo, hi) = galerkin::spectral::mesh::bounds_of(&control);
        let s = 8;
        for k in 0..=s {
            for j in 0..=s - k {
                for i in 0..=s - k - j {
                    let (x, _) = mesh.map_hex(e, [i, j, k].map(|c| c as f64 / s as f64));
                    assert!((0..3).all(|c| x[c] >= lo[c] - 1e-12 && x[c] <= hi[c] + 1e-12), "{e}: {x:?}");
                }
            }
        }
        // Bernstein at the vertices equals the vertex (interpolation at corners).
        let pts = mesh.element_points(e);
        assert!((0..3).all(|c| (control[0][c] - pts[0][c]).abs() < 1e-12));
    }
}

/// Every VTK-written tetrahedral mesh cut by an axis plane and an oblique one passes the f64
/// per-pixel check (`check_cut_pixels`): each covered pixel shows its element's polynomial at
/// the reference point of the pixel's point on the plane, within that pixel's f32 bound, in
/// the element that contains it, and no pixel whose point lies inside an element (by 10⁻³ of
/// the reference tetrahedron) is missing — the cube's six curved tetrahedra meet along curved
/// faces the planes cross.
#[test]
fn vtk_written_tetrahedra_render_pixel_exact_through_cut_planes() {
    let gpu = common::gpu();
    let size = (240u32, 180u32);
    let target = RenderTarget::new(&gpu, "tetrahedra", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    for (name, _, elements) in FILES {
        let mesh = Arc::new(galerkin::spectral::load(&path(name, "vtu"), &[]).expect("read"));
        let camera = fit_camera(&mesh);
        let (lo, hi) = mesh.bounds();
        let mid: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let mut seen = std::collections::BTreeSet::new();
        for cut in [
            [0.0, 0.0, 1.0, 0.3 * lo[2] + 0.7 * mid[2]],
            [0.3, 0.2, 1.0, 0.3 * mid[0] + 0.2 * mid[1] + mid[2]],
        ] {
            let view = SpectralView { overdraw: false, cuts: vec![cut], ..SpectralView::default() };
            let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
                panic!("a float target returned bytes")
            };
            let report = check_cut_pixels(&mesh, 0, 0, &camera, &[cut], size, &px);
            eprintln!("{name} plane {cut:?}: {report:?}");
            // Two small tetrahedra under an oblique plane cover ~900 pixels of 240 × 180.
            assert!(report.covered > 500 && report.passed(), "{name} plane {cut:?}: {report:?}");
            seen.extend(px.chunks_exact(4).filter(|t| t[3] >= 0.0).map(|t| t[3] as i64));
        }
        assert!(seen.len() >= elements.min(4), "{name}: elements drawn {seen:?}");
    }
}

/// The device's tetrahedron functions (`spectral_simplex.glsl` through `spectral_map_hex`,
/// `spectral_value_hex`, `spectral_slot_value_gradient_hex` and `spectral_inverse_map_hex`,
/// run by the `spectral_solid` probe) against their Rust twins at 60 reference points of the
/// order-3 and order-6 cubes: the map within 1e-5 (f32 sums of ≤ 84 terms of size ≤ 10³
/// basis values times coordinates ≤ 1.1), the value within 1e-5 · max|F| · 10, the Jacobian
/// and the gradient within 1e-3 of their scale (derivatives of order-6 bases reach ~10²), and
/// the pull-back of each mapped point back at its reference point within 1e-4.
#[test]
fn device_tetrahedra_evaluate_as_their_rust_twins() {
    use galerkin::gpu::vk;
    use galerkin::gpu::{Buffer, MemoryKind};
    use galerkin::spectral::render::{basis_specialization, geometry_points, padded_values};
    let gpu = common::gpu();
    let storage = |name: &str, data: &[[f32; 4]]| {
        Buffer::from_slice(&gpu, name, data, vk::BufferUsageFlags::STORAGE_BUFFER).expect("buffer")
    };
    for name in ["tet_cube_o3", "tet_cube_o6"] {
        let mesh = galerkin::spectral::load(&path(name, "vtu"), &[]).expect("read");
        let values: Vec<[f32; 4]> =
            padded_values(&mesh, 0, 0).chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        let random = common::random_f32(180, 5);
        let n = 60;
        let (mut probes, mut expected) = (Vec::new(), Vec::new());
        for k in 0..n {
            let e = k % mesh.elements();
            // A point of the reference tetrahedron: |random| coordinates scaled into Σ ≤ 1.
            let raw: [f64; 3] = std::array::from_fn(|a| f64::from(random[3 * k + a].abs()));
            let sum = raw.iter().sum::<f64>().max(1.0);
            let r = raw.map(|c| f64::from((c / sum * 0.98) as f32));
            let (x, _) = mesh.map_hex(e, r);
            probes.push([e as f32, r[0] as f32, r[1] as f32, r[2] as f32]);
            probes.push([x[0] as f32, x[1] as f32, x[2] as f32, 0.0]);
            expected.push((e, r, x));
        }
        let pb = storage("points", &geometry_points(&mesh));
        let vb = storage("values", &values);
        let qb = storage("probes", &probes);
        let ob = Buffer::<[f32; 4]>::new(
            &gpu,
            "out",
            6 * n as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuToCpu,
        )
        .expect("out");
        let bindings =
            [pb.binding().unwrap(), vb.binding().unwrap(), qb.binding().unwrap(), ob.binding().unwrap()];
        common::run_probe_specialized(
            &gpu,
            "spectral solid probe",
            galerkin::gpu::shaders::probe::SPECTRAL_SOLID,
            &bindings,
            &common::CountPush { n: n as u32 },
            1,
            &basis_specialization(&mesh),
        );
        let out = ob.download(&gpu).expect("downloaded");
        let vmax = mesh.fields[0].steps[0].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (k, &(e, r, x)) in expected.iter().enumerate() {
            let o = &out[6 * k..6 * k + 6];
            let what = format!("{name} probe {k} (element {e}, r {r:?})");
            for c in 0..3 {
                assert!((f64::from(o[0][c]) - x[c]).abs() < 1e-5, "{what}: x {:?} vs {x:?}", o[0]);
            }
            let u = mesh.value_hex(0, 0, e, r);
            assert!((f64::from(o[0][3]) - u).abs() < 1e-4 * vmax, "{what}: u {} vs {u}", o[0][3]);
            let (_, jac) = mesh.map_hex(e, r);
            for a in 0..3 {
                for c in 0..3 {
                    assert!(
                        (f64::from(o[1 + a][c]) - jac[a][c]).abs() < 1e-3,
                        "{what}: J[{a}][{c}] {} vs {}",
                        o[1 + a][c],
                        jac[a][c]
                    );
                }
            }
            let (_, grad) = mesh.value_gradient_at(0, 0, e, r);
            for a in 0..3 {
                assert!(
                    (f64::from(o[4][1 + a]) - grad[a]).abs() < 1e-3 * vmax.max(1.0),
                    "{what}: ∂f/∂r{a} {} vs {}",
                    o[4][1 + a],
                    grad[a]
                );
            }
            assert!(o[5][3] == 1.0, "{what}: the pull-back did not converge: {:?}", o[5]);
            for a in 0..3 {
                assert!((f64::from(o[5][a]) - r[a]).abs() < 1e-4, "{what}: pulled back to {:?}", o[5]);
            }
        }
    }
}
