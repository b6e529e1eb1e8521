//! Spectral elements (seed 002) on lavapipe with validation on: the GLSL bases and element
//! maths against their Rust twins, per-pixel exactness against the CPU f64 reference for
//! straight and curved planar meshes of orders 1–10 on GLL and equispaced nodes (and Gauss and
//! Bernstein), edge overdraw on discontinuous data, and bad input.

mod common;

use std::sync::Arc;

use galerkin::gpu::{shaders, vk, Buffer, MemoryKind};
use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::generate::{annulus, quad_grid};
use galerkin::spectral::reference::check_pixels;
use galerkin::spectral::render::basis_specialization;
use galerkin::spectral::{
    Basis1d, Field, NodeSet, Shape, SpectralError, SpectralMesh, SpectralRenderer, SpectralView, View2d,
};

fn storage<T: bytemuck::Pod>(gpu: &galerkin::gpu::Gpu, name: &str, data: &[T]) -> Buffer<T> {
    Buffer::from_slice(gpu, name, data, vk::BufferUsageFlags::STORAGE_BUFFER).unwrap()
}

/// The GLSL bases, map, inverse map and value at random points against the Rust twins.
#[test]
fn glsl_element_maths_match_their_rust_twins() {
    let gpu = common::gpu();
    let cases = [
        annulus(2, 3, 4, 10, NodeSet::GaussLobatto).unwrap(),
        annulus(2, 3, 3, 7, NodeSet::Equispaced).unwrap(),
        annulus(2, 2, 2, 5, NodeSet::Gauss).unwrap(),
        quad_grid(3, 2, 0.2, 8, NodeSet::Bernstein).unwrap(),
        quad_grid(3, 2, 0.2, 1, NodeSet::GaussLobatto).unwrap(),
        // Isoparametric: one basis for field and geometry, coefficients as flat varyings
        // (order 3) and from the buffer (order 5).
        annulus(2, 3, 3, 3, NodeSet::GaussLobatto).unwrap(),
        annulus(2, 3, 5, 5, NodeSet::Equispaced).unwrap(),
        // Rational: VTK's rational Bézier quadrilaterals (homogeneous points and coefficients).
        galerkin::spectral::vtu::read(std::path::Path::new("tests/data/vtk/bezier_quad_rational.vtu"))
            .unwrap(),
    ];
    for mesh in &cases {
        let points = galerkin::spectral::render::geometry_points(mesh);
        let values = galerkin::spectral::render::padded_values(mesh, 0, 0);
        let r = common::random_f32(200, 11);
        let n = 100;
        let mut probes: Vec<[f32; 4]> = Vec::new();
        let mut expected = Vec::new();
        for k in 0..n {
            let e = (k * 7) % mesh.elements();
            let (xi, eta) = (0.5 + 0.5 * f64::from(r[2 * k]), 0.5 + 0.5 * f64::from(r[2 * k + 1]));
            let (xi, eta) = (f64::from(xi as f32), f64::from(eta as f32));
            let (x, _) = mesh.map(e, xi, eta);
            probes.push([e as f32, xi as f32, eta as f32, 0.0]);
            // Inverse-map the point from the element centre.
            probes.push([x[0] as f32, x[1] as f32, 0.5, 0.5]);
            expected.push((e, xi, eta, x));
        }
        let pb = storage(&gpu, "points", &points);
        let vb = storage(&gpu, "values", &values);
        let qb = storage(&gpu, "probes", &probes);
        let ob = Buffer::<[f32; 4]>::new(
            &gpu,
            "out",
            16 * n as u64,
            vk::BufferUsageFlags::STORAGE_BUFFER,
            MemoryKind::GpuToCpu,
        )
        .unwrap();
        let bindings =
            [pb.binding().unwrap(), vb.binding().unwrap(), qb.binding().unwrap(), ob.binding().unwrap()];
        common::run_probe_specialized(
            &gpu,
            "spectral probe",
            shaders::probe::SPECTRAL,
            &bindings,
            &common::CountPush { n: n as u32 },
            2,
            &basis_specialization(mesh),
        );
        let out = ob.download(&gpu).unwrap();
        let vmax = mesh.fields[0].steps[0].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        for (k, &(e, xi, eta, x)) in expected.iter().enumerate() {
            let o = &out[16 * k..16 * k + 16];
            let what = format!("{:?} order {} probe {k}", mesh.basis.set, mesh.basis.order);
            // Basis values: f32 products of ≤ 13 factors with weights up to ~1e6 (equispaced
            // order 10), each within ~30 ε₃₂ relative of the f64 value; derivatives likewise
            // against a scale of n².
            let (mut a, mut da, mut g, mut dg) = ([0.0; 16], [0.0; 16], [0.0; 16], [0.0; 16]);
            mesh.basis.eval(xi, &mut a, Some(&mut da));
            mesh.geometry.eval(xi, &mut g, Some(&mut dg));
            for j in 0..mesh.basis.len() {
                let n2 = (mesh.basis.order * mesh.basis.order) as f64;
                assert!(
                    (f64::from(o[3 + j][0]) - a[j]).abs() < 1e-5,
                    "{what}: l_{j} {} vs {}",
                    o[3 + j][0],
                    a[j]
                );
                assert!((f64::from(o[3 + j][1]) - da[j]).abs() < 1e-5 * n2, "{what}: l'_{j}");
            }
            for j in 0..mesh.geometry.len() {
                assert!((f64::from(o[3 + j][2]) - g[j]).abs() < 1e-5, "{what}: g_{j}");
                assert!((f64::from(o[3 + j][3]) - dg[j]).abs() < 1e-4, "{what}: g'_{j}");
            }
            // Map and value: sums of ≤ 121 f32 terms of size ≤ max|F| Λ.
            let (xr, [dx, dy]) = mesh.map(e, xi, eta);
            assert!(
                (f64::from(o[0][1]) - xr[0]).abs() < 1e-5 && (f64::from(o[0][2]) - xr[1]).abs() < 1e-5,
                "{what}: map"
            );
            for (gpu_d, d) in [(o[1][0], dx[0]), (o[1][1], dx[1]), (o[1][2], dy[0]), (o[1][3], dy[1])] {
                assert!(
                    (f64::from(gpu_d) - d).abs() < 1e-4 * (1.0 + d.abs()),
                    "{what}: jacobian {gpu_d} vs {d}"
                );
            }
            let value = mesh.value(0, 0, e, xi, eta);
            assert!((f64::from(o[0][0]) - value).abs() < 1e-4 * vmax, "{what}: value {} vs {value}", o[0][0]);
            // The fragment stage's value-with-map: the same sums, possibly in another order.
            assert!(
                (f64::from(o[0][3]) - value).abs() < 1e-4 * vmax,
                "{what}: combined {} vs {value}",
                o[0][3]
            );
            assert!(o[2][3] < 1e-5, "{what}: combined map strays by {}", o[2][3]);
            // Newton from the centre recovers (ξ, η) of the f32-rounded point to ~1e-5.
            assert_eq!(o[2][2], 1.0, "{what}: Newton converged");
            let _ = x;
            assert!(
                (f64::from(o[2][0]) - xi).abs() < 2e-5 && (f64::from(o[2][1]) - eta).abs() < 2e-5,
                "{what}: inverse map {:?} vs ({xi}, {eta})",
                o[2]
            );
        }
    }
}

fn render_data(
    gpu: &galerkin::gpu::Gpu,
    mesh: &Arc<SpectralMesh>,
    view: &SpectralView,
    size: (u32, u32),
) -> Vec<f32> {
    let mut r = SpectralRenderer::new(gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let target = RenderTarget::new(gpu, "spectral data", size.0, size.1, ColorFormat::Rgba32F).unwrap();
    match r.render(&target, view).unwrap() {
        Pixels::Rgba32F(v) => v,
        Pixels::Rgba8(_) => unreachable!(),
    }
}

/// Every covered pixel shows its element's polynomial at the pixel centre's reference point
/// (f64 inverse map), within the pixel's own f32 rounding bound; every pixel inside an element
/// is covered. Straight (bilinear) and curved (isoparametric annulus) meshes, orders 1–10.
#[test]
fn pixels_show_the_polynomial_at_their_centre() {
    let gpu = common::gpu();
    let size = (160, 120);
    for set in [NodeSet::GaussLobatto, NodeSet::Equispaced] {
        for order in 1..=10 {
            let meshes = [
                quad_grid(4, 3, 0.25, order, set).unwrap(),
                annulus(2, 4, order.clamp(2, 6), order, set).unwrap(),
            ];
            for mesh in meshes {
                let curved = mesh.geometry.order > 1;
                let mesh = Arc::new(mesh);
                let view = SpectralView { overdraw: false, ..SpectralView::default() };
                let pixels = render_data(&gpu, &mesh, &view, size);
                let v2 = View2d::fit(&mesh, size.0, size.1);
                let report = check_pixels(&mesh, 0, 0, &v2, size, &pixels);
                eprintln!(
                    "{set:?} order {order} curved {curved}: {} px, max error {:.2e}, {:.3} of the bound",
                    report.covered, report.max_error, report.max_error_ratio
                );
                assert!(report.covered > 2000, "{set:?} order {order}: {} pixels covered", report.covered);
                assert!(report.passed(), "{set:?} order {order} curved {curved}: {report:?}");
            }
        }
    }
    // Gauss–Legendre and Bernstein coefficients, a later time step.
    for set in [NodeSet::Gauss, NodeSet::Bernstein] {
        let mesh = Arc::new(annulus(2, 4, 4, 6, set).unwrap());
        let view = SpectralView { step: 2, overdraw: false, ..SpectralView::default() };
        let pixels = render_data(&gpu, &mesh, &view, size);
        let v2 = View2d::fit(&mesh, size.0, size.1);
        let report = check_pixels(&mesh, 0, 2, &v2, size, &pixels);
        assert!(report.passed(), "{set:?}: {report:?}");
    }
}

/// With edge overdraw, no background pixel shows inside a mesh of discontinuous elements: a
/// pixel centre is "inside" when it lies inside some element's reference square.
#[test]
fn edge_overdraw_leaves_no_crack_in_discontinuous_data() {
    let gpu = common::gpu();
    let size = (200, 150);
    for mesh in [
        annulus(3, 6, 4, 5, NodeSet::GaussLobatto).unwrap(),
        quad_grid(5, 4, 0.3, 4, NodeSet::GaussLobatto).unwrap(),
    ] {
        let mesh = Arc::new(mesh);
        let cells = mesh.field_index(Some("cells")).unwrap();
        let v2 = View2d::fit(&mesh, size.0, size.1);
        let holes = |overdraw: bool| {
            let view = SpectralView { field: cells, overdraw, ..SpectralView::default() };
            let pixels = render_data(&gpu, &mesh, &view, size);
            let mut holes = 0;
            for py in 0..size.1 {
                for px in 0..size.0 {
                    let k = 4 * (py * size.0 + px) as usize;
                    if pixels[k + 3].is_nan()
                        && mesh.locate(v2.pixel_centre(px, py, size.0, size.1), 0.0).is_some()
                    {
                        holes += 1;
                    }
                }
            }
            holes
        };
        // Without overdraw the proxies leave only pixels whose centres lie on an edge that the
        // rasteriser's tie rule gives to no element (0 or 1 here); with it, none.
        eprintln!("holes without edge overdraw: {}", holes(false));
        let holes = holes(true);
        assert_eq!(holes, 0, "background pixels inside the mesh");
    }
}

/// Ownership at element edges: a pixel centre just inside one element (3e-6 of its width from
/// the edge, inside the neighbour's acceptance tolerance of 1e-5) is drawn by that element,
/// whichever of the two is drawn last — on a discontinuous field a stolen pixel shows the
/// neighbour's value.
#[test]
fn a_pixel_centre_near_an_edge_belongs_to_the_element_that_contains_it() {
    let gpu = common::gpu();
    let mesh = Arc::new(quad_grid(2, 1, 0.0, 3, NodeSet::GaussLobatto).unwrap());
    let cells = mesh.field_index(Some("cells")).unwrap();
    let bounds = |e: usize| {
        let p = mesh.element_points(e);
        let fold = |k: usize, f: fn(f64, f64) -> f64, init: f64| p.iter().map(|q| q[k]).fold(init, f);
        (
            fold(0, f64::min, f64::INFINITY),
            fold(0, f64::max, f64::NEG_INFINITY),
            fold(1, f64::min, f64::INFINITY),
            fold(1, f64::max, f64::NEG_INFINITY),
        )
    };
    let (left, right) = if bounds(0).0 < bounds(1).0 { (0, 1) } else { (1, 0) };
    let (x0, edge, y0, y1) = bounds(left);
    let width = edge - x0;
    let (w, h) = (64u32, 32u32);
    let pixel = width / 20.0;
    let delta = 3e-6 * width;
    for (owner, offset) in [(left, -delta), (right, delta)] {
        // Pixel column 32's centre is at centre.x + pixel / 2: put it at edge + offset.
        let centre = [edge + offset - 0.5 * pixel, 0.5 * (y0 + y1)];
        let view = SpectralView {
            field: cells,
            overdraw: false,
            view: Some(View2d { centre, pixel_size: pixel }),
            ..SpectralView::default()
        };
        let pixels = render_data(&gpu, &mesh, &view, (w, h));
        let mut checked = 0;
        for py in 0..h {
            let t = &pixels[4 * (py * w + 32) as usize..][..4];
            if t[3].is_nan() {
                continue;
            }
            checked += 1;
            assert_eq!(t[3] as usize, owner, "row {py}: the pixel at {:e} of the edge went to the neighbour ({t:?}, edge {edge}, width {width})", offset);
        }
        assert!(checked >= 10, "{checked} pixels of the column covered");
    }
}

/// The colour output maps the value through the colour ramp (and shows the background
/// outside), and the mesh lines darken the edge pixels.
#[test]
fn colour_output_and_mesh_lines() {
    let gpu = common::gpu();
    let mesh = Arc::new(quad_grid(4, 2, 0.0, 3, NodeSet::GaussLobatto).unwrap());
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let size = (128, 64);
    let target = RenderTarget::new(&gpu, "spectral colour", size.0, size.1, ColorFormat::Rgba8).unwrap();
    let view = SpectralView { range: Some((-1.5, 1.5)), ..SpectralView::default() };
    let Pixels::Rgba8(plain) = r.render(&target, &view).unwrap() else { unreachable!() };
    let Pixels::Rgba8(lined) = r.render(&target, &SpectralView { edges: true, ..view.clone() }).unwrap()
    else {
        unreachable!()
    };
    let v2 = View2d::fit(&mesh, size.0, size.1);
    let cmap = Colormap::viridis();
    let (mut checked, mut darker) = (0, 0);
    for py in 0..size.1 {
        for px in 0..size.0 {
            let p = v2.pixel_centre(px, py, size.0, size.1);
            let k = 4 * (py * size.0 + px) as usize;
            if let Some((e, ref_point)) = mesh.locate(p, -0.05) {
                let v = mesh.value(0, 0, e, ref_point[0], ref_point[1]);
                let c = cmap.sample(galerkin::render::ramp_coordinate(v, -1.5, 1.5, false));
                // 8-bit output of a linearly filtered 256-texel ramp: within 2/255 per channel.
                for ch in 0..3 {
                    assert!(
                        (f64::from(plain[k + ch]) / 255.0 - c[ch]).abs() <= 2.0 / 255.0,
                        "pixel ({px}, {py})"
                    );
                }
                checked += 1;
            }
            let sum = |img: &[u8]| u32::from(img[k]) + u32::from(img[k + 1]) + u32::from(img[k + 2]);
            if sum(&lined) + 30 < sum(&plain) {
                darker += 1;
            }
        }
    }
    assert!(checked > 3000, "{checked}");
    // Lines along 4 + 1 verticals and 2 + 1 horizontals of the 128 × 64 image, about 1 px wide.
    assert!(darker > 300, "{darker} pixels darkened by the mesh lines");
}

#[test]
fn bad_input_names_the_element_or_field() {
    let g = Basis1d::new(NodeSet::Equispaced, 1).unwrap();
    let b = Basis1d::new(NodeSet::GaussLobatto, 2).unwrap();
    let square = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    let field = |v: Vec<f64>| vec![Field { name: "f".into(), times: vec![0.0], steps: vec![v] }];
    // A NaN value names element and node.
    let mut v = vec![0.0; 9];
    v[4] = f64::NAN;
    let e =
        SpectralMesh::new(Shape::Quadrilateral, g.clone(), b.clone(), square.clone(), field(v)).unwrap_err();
    assert!(matches!(e, SpectralError::NotFinite { element: 0, .. }), "{e}");
    assert!(e.to_string().contains("value 4"), "{e}");
    // Wrong count.
    let e =
        SpectralMesh::new(Shape::Quadrilateral, g.clone(), b.clone(), square.clone(), field(vec![0.0; 8]))
            .unwrap_err();
    assert!(e.to_string().contains("8 entries, expected 9"), "{e}");
    // A folded element (corners crossed): the second element.
    let mut two = square.clone();
    two.extend([[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
    let e =
        SpectralMesh::new(Shape::Quadrilateral, g.clone(), b.clone(), two, field(vec![0.0; 18])).unwrap_err();
    assert!(matches!(e, SpectralError::Invalid { element: 1, .. }), "{e}");
    // Orders outside 1..=12.
    assert!(Basis1d::new(NodeSet::GaussLobatto, 13).is_err());
    // Unknown field and step.
    let mesh = SpectralMesh::new(Shape::Quadrilateral, g, b, square, field(vec![0.0; 9])).unwrap();
    assert!(mesh.field_index(Some("pressure")).unwrap_err().to_string().contains("\"f\""));
    let gpu = common::gpu();
    let mut r = SpectralRenderer::new(&gpu, Arc::new(mesh), &Colormap::viridis()).unwrap();
    let target = RenderTarget::new(&gpu, "t", 8, 8, ColorFormat::Rgba8).unwrap();
    let e = r.render(&target, &SpectralView { step: 3, ..SpectralView::default() }).err().unwrap();
    assert!(e.to_string().contains("step 3"), "{e}");
}

/// Surfaces in 3D: every covered pixel shows the polynomial at a reference point whose surface
/// point projects within the ½-pixel error budget of the pixel centre (the tessellation's
/// bound), with the value evaluated exactly there; a coarse budget visibly breaks the bound.
#[test]
fn surfaces_show_the_field_within_half_a_pixel() {
    use galerkin::spectral::generate::artery;
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let mesh = Arc::new(artery(22, 8, 3, 4, NodeSet::GaussLobatto).unwrap());
    // Isoparametric (field and geometry of order 3): the fragment stage shares the 1D bases
    // and takes the coefficients from flat varyings.
    let iso = Arc::new(artery(22, 8, 3, 3, NodeSet::GaussLobatto).unwrap());
    let size = (256u32, 192u32);
    let camera = fit_camera(&mesh);
    let farthest_on = |mesh: &Arc<galerkin::spectral::SpectralMesh>, budget: f64| {
        let view = SpectralView { overdraw: false, max_error_px: budget, ..SpectralView::default() };
        common::surfaces::surface_errors(
            mesh,
            &render_data(&gpu, mesh, &view, size),
            &camera,
            size,
            |e, r| glam::DVec3::from(mesh.map(e, r[0], r[1]).0),
        )
    };
    let farthest = |budget: f64| farthest_on(&mesh, budget);
    for (name, m) in [("order 4 on order-3 geometry", &mesh), ("isoparametric order 3", &iso)] {
        let (covered, worst, worst_value) = farthest_on(m, 0.5);
        eprintln!(
            "{name}, budget 0.5 px: {covered} pixels, farthest {worst:.3} px, value error {worst_value:.3} of its bound"
        );
        assert!(covered > 3000, "{covered}");
        // The bound, plus f32 slack: interpolated reference coordinates and the f32 view
        // matrix move the point by ~1e-6 of the scene (≈ 1e-3 px here).
        assert!(worst <= 0.5 + 0.01, "{name}: a pixel shows a surface point {worst} px away");
        assert!(worst_value <= 1.0, "{name}: value error {worst_value} of its bound");
    }
    // The device's levels agree with their CPU twin, and nothing was skipped.
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let target = RenderTarget::new(&gpu, "tess", size.0, size.1, ColorFormat::Rgba8).unwrap();
    let view = SpectralView::default();
    r.render(&target, &view).unwrap();
    let (written, skipped) = r.last_tessellation().unwrap().unwrap();
    let expected = r.expected_tessellation(&target, &view);
    eprintln!("tessellation: {written} vertices on the device, {expected} by the CPU twin");
    assert_eq!(skipped, 0);
    // Both in f32; a level may differ by one where ceil meets a rounding difference.
    assert!((f64::from(written) - expected as f64).abs() <= 0.02 * expected as f64);
    let (_, coarse, _) = farthest(16.0);
    eprintln!("budget 16 px: farthest {coarse:.3} px");
    assert!(coarse > 0.5, "a coarse tessellation should break the half-pixel bound ({coarse})");
}

/// Cut planes through curved hexahedra: every covered pixel shows its element's polynomial at
/// the reference point of the pixel's point on the plane (the camera ray through the pixel
/// centre met with the plane, pulled back in f64), within that pixel's f32 bound; with one
/// plane, every pixel whose plane point lies inside an element is covered.
#[test]
fn cut_planes_through_curved_hexahedra_are_pixel_exact() {
    use galerkin::spectral::generate::hex_shell;
    use galerkin::spectral::reference::check_cut_pixels;
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let size = (240u32, 180u32);
    for (set, order) in [(NodeSet::GaussLobatto, 4), (NodeSet::Equispaced, 6)] {
        let mesh = Arc::new(hex_shell(2, 3, 2, 3, order, set).unwrap());
        let camera = fit_camera(&mesh);
        let planes = [[0.0, 0.0, 1.0, 0.45], [1.0, 1.0, 0.0, 0.9]];
        for cuts in [vec![planes[0]], planes.to_vec()] {
            let view = SpectralView { overdraw: false, cuts: cuts.clone(), ..SpectralView::default() };
            let pixels = render_data(&gpu, &mesh, &view, size);
            let report = check_cut_pixels(&mesh, 0, 0, &camera, &cuts, size, &pixels);
            eprintln!("{set:?} order {order}, {} plane(s): {report:?}", cuts.len());
            assert!(report.covered > 2500 && report.passed(), "{report:?}");
        }
    }
}

/// A 2D field as a height field: every covered pixel shows the polynomial at a reference point
/// whose lifted point (x, y, scale · f) projects within ½ pixel of the pixel centre.
#[test]
fn height_fields_show_the_field_within_half_a_pixel() {
    let gpu = common::gpu();
    let mesh = Arc::new(annulus(2, 4, 3, 5, NodeSet::GaussLobatto).unwrap());
    let size = (256u32, 192u32);
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
    let view = SpectralView { overdraw: false, height: Some(0.2), ..SpectralView::default() };
    let target = RenderTarget::new(&gpu, "height", size.0, size.1, ColorFormat::Rgba32F).unwrap();
    let Pixels::Rgba32F(pixels) = r.render(&target, &view).unwrap() else { unreachable!() };
    // The camera the renderer fits to the lifted box.
    let (lo, hi) = r.range(&view);
    let (mut a, mut b) = ([f64::MAX; 3], [f64::MIN; 3]);
    for p in &mesh.points {
        for c in 0..2 {
            a[c] = a[c].min(p[c]);
            b[c] = b[c].max(p[c]);
        }
    }
    a[2] = 0.2 * lo;
    b[2] = 0.2 * hi;
    let camera = galerkin::spectral::render::camera_for_box(a, b);
    let (covered, worst, worst_value) =
        common::surfaces::surface_errors(&mesh, &pixels, &camera, size, |e, q| {
            let (x, _) = mesh.map(e, q[0], q[1]);
            glam::DVec3::new(x[0], x[1], 0.2 * mesh.value(0, 0, e, q[0], q[1]))
        });
    eprintln!(
        "height field: {covered} pixels, farthest {worst:.3} px, value error {worst_value:.3} of its bound"
    );
    assert!(covered > 2000, "{covered}");
    assert!(worst <= 0.5 + 0.01, "a pixel shows a point {worst} px away");
    assert!(worst_value <= 1.0);
}

/// Rational cells in 3D: a cylinder of radius 1 and height 1 from four rational quadratic
/// Bézier quadrilaterals (weights 1, √2/2, 1 around; the circle is exact, which no polynomial
/// quadrilateral is). The f64 map lies on the cylinder to rounding (closed form), and the
/// rendered surface keeps the half-pixel bound and each pixel's value bound as polynomial
/// surfaces do.
#[test]
fn rational_quadrilaterals_draw_an_exact_cylinder() {
    use galerkin::spectral::render::fit_camera;
    let basis = Basis1d::new(NodeSet::Bernstein, 2).unwrap();
    let (mut points, mut weights, mut values) = (Vec::new(), Vec::new(), Vec::new());
    for e in 0..4 {
        let a = f64::from(e) * std::f64::consts::FRAC_PI_2;
        let (c, s) = (a.cos(), a.sin());
        let around = [([c, s], 1.0), ([c - s, s + c], std::f64::consts::FRAC_1_SQRT_2), ([-s, c], 1.0)];
        for j in 0..3 {
            let z = 0.5 * f64::from(j);
            for (i, (p, w)) in around.iter().enumerate() {
                points.push([p[0], p[1], z]);
                weights.push(*w);
                values.push((f64::from(e) + i as f64 - z).sin());
            }
        }
    }
    let fields = vec![Field { name: "u".into(), times: vec![0.0], steps: vec![values] }];
    let mesh = SpectralMesh::new(Shape::Quadrilateral, basis.clone(), basis, points, fields)
        .unwrap()
        .with_weights(weights)
        .unwrap();
    let mut off_circle = 0.0f64;
    for e in 0..4 {
        for k in 0..=20 {
            let (x, _) = mesh.map(e, f64::from(k) / 20.0, 0.3);
            off_circle = off_circle.max((x[0].hypot(x[1]) - 1.0).abs());
        }
    }
    assert!(off_circle < 1e-15, "the rational map leaves the circle by {off_circle:e}");
    let mesh = Arc::new(mesh);
    let gpu = common::gpu();
    let size = (256u32, 192u32);
    let camera = fit_camera(&mesh);
    let view = SpectralView { overdraw: false, max_error_px: 0.5, ..SpectralView::default() };
    let (covered, farthest, worst_value) = common::surfaces::surface_errors(
        &mesh,
        &render_data(&gpu, &mesh, &view, size),
        &camera,
        size,
        |e, r| glam::DVec3::from(mesh.map(e, r[0], r[1]).0),
    );
    eprintln!("rational cylinder: {covered} pixels, farthest {farthest:.3} px, value error {worst_value:.3} of its bound");
    assert!(covered > 3000, "{covered}");
    // As for polynomial surfaces: the budget plus f32 slack (≈ 1e-3 px).
    assert!(farthest <= 0.5 + 0.01, "a pixel shows a surface point {farthest} px away");
    assert!(worst_value <= 1.0, "value error {worst_value} of its bound");
}
