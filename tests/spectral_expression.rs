//! Derived fields (`--expr`): expressions over the solution evaluated per pixel by a fragment
//! shader compiled at run time (shaderc), on lavapipe with validation on — every covered pixel
//! against the f64 interpreter at the pixel centre's reference point within its propagated
//! rounding bound, a closed-form gradient, surfaces, and what is refused. The command-line
//! refusals run in every build; the GPU tests need the `runtime-shaderc` feature
//! (`make test-shaderc`).

mod common;

use std::process::Command;

fn galerkin(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran galerkin")
}

/// A type error is reported with its column before any GPU work, in every build.
#[test]
fn cli_reports_expression_errors_with_their_column() {
    let out = galerkin(&["spectral", "render", "--expr", "grad(u) + 1", "--out", "/nonexistent/x.png"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("column 9") && err.contains("cannot add a vector and a scalar"), "{err}");
    let out = galerkin(&["spectral", "render", "--expr", "u * wavs", "--out", "/nonexistent/x.png"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("column 5") && err.contains("\"waves\""), "{err}");
    // The spacetime renderer's names: grad takes a field, U is a variable.
    let out = galerkin(&["spacetime", "render", "--expr", "length(grad(U))", "--out", "/nonexistent/x.png"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("column 13") && err.contains("not a field"), "{err}");
}

/// The viewer's keys with a derived field, without a window: `v` (per vertex) and `h` (height
/// field) are not taken — a derived field is drawn per pixel and flat — and `.` cycles only
/// through the steps every field it reads has (`cells` has one).
#[test]
fn the_viewer_keeps_a_derived_field_drawable() {
    use galerkin::render::viewer::ViewerContent;
    use galerkin::spectral::{generate, NodeSet, SpectralView};
    let mesh = std::sync::Arc::new(generate::by_name("annulus", 3, 3, NodeSet::GaussLobatto).unwrap());
    let d = galerkin::expression::spectral::DerivedField::new(&mesh, "u * cells").unwrap();
    let view = SpectralView { expression: Some(std::sync::Arc::new(d)), ..SpectralView::default() };
    let mut content =
        galerkin::spectral::viewer::SpectralContent::new(mesh, view, "viridis", (320, 200), false);
    assert!(!content.key("v") && !content.key("h"));
    assert!(content.key("."));
    let title = content.title();
    assert!(title.contains("u * cells step 0/1"), "{title}");
}

#[cfg(feature = "runtime-shaderc")]
mod device {
    use std::sync::Arc;

    use super::common;
    use galerkin::expression::spectral::DerivedField;
    use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
    use galerkin::spectral::generate::{annulus, artery, quad_grid};
    use galerkin::spectral::reference::check_derived_pixels;
    use galerkin::spectral::{Field, NodeSet, SpectralMesh, SpectralRenderer, SpectralView, View2d};

    /// The linked compiler turns a fragment shader into SPIR-V (magic number first), resolves
    /// the project's includes, and reports a syntax error as an error, not a panic.
    #[test]
    fn runtime_compiler_compiles_and_reports_errors() {
        use galerkin::gpu::shaders::compile_glsl;
        let ok = compile_glsl(
            "#version 450\n#include \"colormap.glsl\"\nlayout(location=0) out vec4 c;\nvoid main(){ c = vec4(sqrt(2.0)); }\n",
            "probe.frag",
            shaderc::ShaderKind::Fragment,
        )
        .expect("a valid shader compiles");
        assert_eq!(ok[0], 0x0723_0203);
        let bad = compile_glsl(
            "#version 450\nvoid main(){ float a = ; }\n",
            "bad.frag",
            shaderc::ShaderKind::Fragment,
        );
        assert!(bad.is_err_and(|e| e.contains("bad.frag")));
        let missing = compile_glsl(
            "#version 450\n#include \"nope.glsl\"\nvoid main(){}\n",
            "m.frag",
            shaderc::ShaderKind::Fragment,
        );
        assert!(missing.is_err_and(|e| e.contains("nope.glsl")));
    }

    fn render(
        gpu: &galerkin::gpu::Gpu,
        renderer: &mut SpectralRenderer,
        view: &SpectralView,
        size: (u32, u32),
    ) -> Vec<f32> {
        let target = RenderTarget::new(gpu, "derived data", size.0, size.1, ColorFormat::Rgba32F).unwrap();
        match renderer.render(&target, view).unwrap() {
            Pixels::Rgba32F(v) => v,
            Pixels::Rgba8(_) => unreachable!(),
        }
    }

    /// Every covered pixel of a derived field shows the expression, evaluated in f64 from the
    /// element's exact polynomials at the pixel centre's reference point, within the bound
    /// propagated from the f32 sums through the expression (DerivedField::rounding_bound);
    /// every pixel inside an element is covered. Curved and straight meshes, gradients,
    /// a second field, coordinates, the time, and every built-in function. One renderer per
    /// mesh draws all expressions (pipelines kept per expression).
    #[test]
    fn derived_pixels_match_the_f64_reference() {
        let gpu = common::gpu();
        let size = (160, 120);
        let expressions = [
            "length(grad(u))",
            "u * cells - 0.5 * grad(u).x",
            "sqrt(abs(u)) + x * y - z",
            "dot(grad(u), grad(cells)) / (1 + u * u)",
            "exp(-t) * clamp(u, -0.5, 0.5) + pow(abs(u) + 1, 1.5)",
            "sin(u) - cos(grad(u).y / 4) + log(abs(u) + 0.1) + min(u, 0) * max(u, 0)",
            "-grad(u).y / (length(grad(u)) + 1)",
        ];
        let meshes = [
            ("curved annulus, order 5", annulus(2, 4, 3, 5, NodeSet::GaussLobatto).unwrap()),
            ("straight grid, order 7", quad_grid(4, 3, 0.25, 7, NodeSet::GaussLobatto).unwrap()),
        ];
        for (name, mesh) in meshes {
            let mesh = Arc::new(mesh);
            let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
            let v2 = View2d::fit(&mesh, size.0, size.1);
            for (k, text) in expressions.iter().enumerate() {
                let d = Arc::new(DerivedField::new(&mesh, text).unwrap());
                // Step 2 for the time-dependent one (t ≠ 0); `cells` has one step.
                let step = if d.expression.uses("t") { 2 } else { 0 };
                let view = SpectralView {
                    step,
                    overdraw: false,
                    expression: Some(d.clone()),
                    ..SpectralView::default()
                };
                let pixels = render(&gpu, &mut renderer, &view, size);
                let report = check_derived_pixels(&mesh, &d, (0, step), &v2, size, &pixels);
                eprintln!(
                    "{name}, {text:?}: {} px, max error {:.2e}, {:.3} of the bound, {} not comparable",
                    report.covered, report.max_error, report.max_error_ratio, report.uncomparable
                );
                assert!(report.covered > 2000, "{name} {text}: {report:?}");
                assert!(report.uncomparable * 100 <= report.covered, "{name} {text}: {report:?}");
                assert!(report.passed(), "{name}, expression {k} {text:?}: {report:?}");
            }
            // The plain field after derived ones: the coefficient buffer goes back to one field.
            let view = SpectralView { overdraw: false, ..SpectralView::default() };
            let pixels = render(&gpu, &mut renderer, &view, size);
            let report = galerkin::spectral::reference::check_pixels(&mesh, 0, 0, &v2, size, &pixels);
            assert!(report.passed(), "{name}, the field after derived fields: {report:?}");
        }
    }

    /// A closed form: on parallelogram elements u = x² + 3xy is exactly an order-2 polynomial
    /// of the reference coordinates, so length(grad(u)) must be |(2x + 3y, 3x)| at the point
    /// each pixel shows (its reported reference point mapped in f64), within the bound.
    #[test]
    fn gradient_matches_its_closed_form() {
        let gpu = common::gpu();
        let size = (160, 120);
        let mut mesh = quad_grid(4, 3, 0.0, 2, NodeSet::GaussLobatto).unwrap();
        let nodes = mesh.basis.nodes.clone();
        let m = nodes.len();
        let mut values = Vec::new();
        for e in 0..mesh.elements() {
            for j in 0..m {
                for i in 0..m {
                    let (x, _) = mesh.map(e, nodes[i], nodes[j]);
                    values.push(x[0] * x[0] + 3.0 * x[0] * x[1]);
                }
            }
        }
        mesh.fields = vec![Field { name: "u".into(), times: vec![0.0], steps: vec![values] }];
        let mesh = Arc::new(mesh);
        let d = Arc::new(DerivedField::new(&mesh, "length(grad(u))").unwrap());
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let view = SpectralView { overdraw: false, expression: Some(d.clone()), ..SpectralView::default() };
        let pixels = render(&gpu, &mut renderer, &view, size);
        let (mut covered, mut worst, mut caught) = (0, 0.0f64, 0);
        for t in pixels.chunks_exact(4).filter(|t| !t[3].is_nan()) {
            let (e, r) = (t[3] as usize, [f64::from(t[1]), f64::from(t[2])]);
            let (x, [dxi, deta]) = mesh.map(e, r[0], r[1]);
            let exact = (2.0 * x[0] + 3.0 * x[1]).hypot(3.0 * x[0]);
            let bound = d.rounding_bound(&mesh, 0, 0, e, r);
            worst = worst.max((f64::from(t[0]) - exact).abs() / bound);
            covered += 1;
            // The bound is tight enough to catch a plausible mistake: the Jacobian applied
            // transposed (J d instead of J⁻ᵀ d) on these skew-free cells.
            let (_, d_ref) = mesh.value_gradient(0, 0, e, r[0], r[1]);
            let wrong =
                (dxi[0] * d_ref[0] + deta[0] * d_ref[1]).hypot(dxi[1] * d_ref[0] + deta[1] * d_ref[1]);
            if (f64::from(t[0]) - wrong).abs() > bound {
                caught += 1;
            }
        }
        eprintln!("closed form: {covered} px, worst error {worst:.3} of the bound; a transposed Jacobian fails {caught}");
        assert!(covered > 5000);
        assert!(worst <= 1.0, "{worst}");
        assert!(caught * 100 >= covered * 99, "{caught} of {covered}");
    }

    /// Surfaces: the tangential gradient on the artery, at the reference point each pixel
    /// reports, against the f64 interpreter there within the bound.
    #[test]
    fn surfaces_show_the_tangential_gradient() {
        let gpu = common::gpu();
        let size = (200, 150);
        let mesh = Arc::new(artery(8, 6, 3, 4, NodeSet::GaussLobatto).unwrap());
        let d = Arc::new(DerivedField::new(&mesh, "length(grad(u)) + 0.1 * u").unwrap());
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let view = SpectralView { expression: Some(d.clone()), ..SpectralView::default() };
        let pixels = render(&gpu, &mut renderer, &view, size);
        let (mut covered, mut worst) = (0, 0.0f64);
        for t in pixels.chunks_exact(4).filter(|t| !t[3].is_nan() && t[3] >= 0.0) {
            let (e, r) = (t[3] as usize, [f64::from(t[1]), f64::from(t[2])]);
            let reference = d.value_at(&mesh, 0, 0, e, r);
            worst = worst.max((f64::from(t[0]) - reference).abs() / d.rounding_bound(&mesh, 0, 0, e, r));
            covered += 1;
        }
        eprintln!("artery: {covered} px, worst error {worst:.3} of the bound");
        assert!(covered > 1500, "{covered}");
        assert!(worst <= 1.0, "{worst}");
    }

    /// Cut planes through curved hexahedra: every covered pixel shows the expression of the
    /// 3D gradient (J⁻ᵀ ∇_r f) and the values at the pixel's point on its plane (pulled back in
    /// f64) within the propagated bound; with one plane, no pixel inside an element is missed.
    #[test]
    fn cut_planes_show_derived_fields() {
        use galerkin::spectral::generate::hex_shell;
        use galerkin::spectral::reference::check_derived_cut_pixels;
        use galerkin::spectral::render::fit_camera;
        let gpu = common::gpu();
        let size = (200u32, 150u32);
        let mesh = Arc::new(hex_shell(2, 3, 2, 3, 4, NodeSet::GaussLobatto).unwrap());
        let camera = fit_camera(&mesh);
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let planes = [[0.0, 0.0, 1.0, 0.45], [1.0, 1.0, 0.0, 0.9]];
        for text in [
            "length(grad(u))",
            "grad(u).z * x - u * u",
            "dot(grad(u), grad(u)) / (1 + abs(u)) + t",
            "u * u - x",
        ] {
            let d = Arc::new(DerivedField::new(&mesh, text).unwrap());
            let step = if d.expression.uses("t") { 1 } else { 0 };
            for cuts in [vec![planes[0]], planes.to_vec()] {
                let view = SpectralView {
                    step,
                    overdraw: false,
                    cuts: cuts.clone(),
                    expression: Some(d.clone()),
                    ..SpectralView::default()
                };
                let pixels = render(&gpu, &mut renderer, &view, size);
                let report = check_derived_cut_pixels(&mesh, &d, (0, step), (&camera, &cuts), size, &pixels);
                eprintln!(
                    "cut {text:?}, {} plane(s): {} px, max error {:.2e}, {:.3} of the bound",
                    cuts.len(),
                    report.covered,
                    report.max_error,
                    report.max_error_ratio
                );
                assert!(report.covered > 2000, "{text}: {report:?}");
                assert!(report.uncomparable * 100 <= report.covered, "{text}: {report:?}");
                assert!(report.passed(), "{text}, {} plane(s): {report:?}", cuts.len());
            }
        }
        // The field itself after derived fields (the cut pass rebound to the new buffer).
        let view = SpectralView { overdraw: false, cuts: vec![planes[0]], ..SpectralView::default() };
        let pixels = render(&gpu, &mut renderer, &view, size);
        let report = galerkin::spectral::reference::check_cut_pixels(
            &mesh,
            0,
            0,
            &camera,
            &[planes[0]],
            size,
            &pixels,
        );
        assert!(report.passed(), "the field after derived fields: {report:?}");
    }

    /// The command line end to end: `spectral render --expr … --out F.exr` writes the derived
    /// value in the `value` channel — every covered pixel equal to the f64 interpreter at the
    /// (ξ, η, element) the file reports, within the bound — and the PNG's legend is labelled
    /// with the expression (the run prints it).
    #[test]
    fn cli_writes_the_derived_value_to_exr() {
        use galerkin::spectral::generate;
        let dir = tempfile::tempdir().unwrap();
        let exr = dir.path().join("grad.exr");
        let text = "length(grad(u)) - 0.5 * u";
        let out = super::galerkin(&[
            "spectral",
            "render",
            "--generate",
            "annulus",
            "--order",
            "5",
            "--expr",
            text,
            "--size",
            "96x72",
            "--out",
            exr.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let image = exr::prelude::read_all_flat_layers_from_file(&exr).unwrap();
        let layer = &image.layer_data[0];
        let channel = |name: &str| -> Vec<f32> {
            let c = layer.channel_data.list.iter().find(|c| c.name.eq(name)).expect("channel");
            match &c.sample_data {
                exr::prelude::FlatSamples::F32(v) => v.clone(),
                _ => panic!("{name} is not f32"),
            }
        };
        let (value, xi, eta, element) = (channel("value"), channel("xi"), channel("eta"), channel("element"));
        let mesh = generate::by_name("annulus", 3, 5, NodeSet::GaussLobatto).unwrap();
        let d = DerivedField::new(&mesh, text).unwrap();
        let mut covered = 0;
        for k in 0..value.len() {
            if element[k].is_nan() || element[k] < 0.0 {
                continue;
            }
            let (e, r) = (element[k] as usize, [f64::from(xi[k]), f64::from(eta[k])]);
            let reference = d.value_at(&mesh, 0, 0, e, r);
            let bound = d.rounding_bound(&mesh, 0, 0, e, r);
            assert!(
                (f64::from(value[k]) - reference).abs() <= bound,
                "pixel {k}: {} vs {reference}",
                value[k]
            );
            covered += 1;
        }
        assert!(covered > 1500, "{covered}");
        let png = dir.path().join("grad.png");
        let out = super::galerkin(&[
            "spectral",
            "render",
            "--generate",
            "annulus",
            "--expr",
            text,
            "--size",
            "96x72",
            "--out",
            png.to_str().unwrap(),
        ]);
        let said = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success() && said.contains(text), "{said}");
    }

    /// What a derived field cannot be drawn with is refused by name, before drawing.
    /// Triangles and tetrahedra VTK wrote (curved, orders 6 and 3): derived fields per pixel —
    /// of the triangles drawn flat, of the tetrahedra on an axis and an oblique cut plane —
    /// each covered pixel within its propagated bound of the f64 interpreter at the pixel's
    /// reference point (Silvester's basis in both; the bound's sums over its terms).
    #[test]
    fn simplices_show_derived_fields() {
        use galerkin::spectral::reference::check_derived_cut_pixels;
        use galerkin::spectral::render::fit_camera;
        let gpu = common::gpu();
        let load = |name: &str| {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
            Arc::new(galerkin::spectral::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}")))
        };
        let expressions = ["length(grad(u))", "u * u - x + y", "grad(u).y / (1 + u * u) + sin(u)"];
        let size = (160u32, 120u32);
        let triangles = load("tri_curved_o6.vtu");
        let mut renderer = SpectralRenderer::new(&gpu, triangles.clone(), &Colormap::viridis()).unwrap();
        let v2 = View2d::fit(&triangles, size.0, size.1);
        for text in expressions {
            let d = Arc::new(DerivedField::new(&triangles, text).unwrap());
            let view =
                SpectralView { overdraw: false, expression: Some(d.clone()), ..SpectralView::default() };
            let pixels = render(&gpu, &mut renderer, &view, size);
            let report = check_derived_pixels(&triangles, &d, (0, 0), &v2, size, &pixels);
            eprintln!(
                "triangles {text:?}: {} px, max error {:.2e}, {:.3} of the bound, {} missing",
                report.covered, report.max_error, report.max_error_ratio, report.missing
            );
            assert!(report.covered > 2000, "{text}: {report:?}");
            assert!(report.uncomparable * 100 <= report.covered, "{text}: {report:?}");
            assert!(report.passed(), "triangles, {text:?}: {report:?}");
        }
        let tets = load("tet_cube_o3.vtu");
        let camera = fit_camera(&tets);
        let mut renderer = SpectralRenderer::new(&gpu, tets.clone(), &Colormap::viridis()).unwrap();
        let planes = [[0.0, 0.0, 1.0, 0.45], [1.0, 1.0, 1.0, 1.6]];
        for text in expressions {
            let d = Arc::new(DerivedField::new(&tets, text).unwrap());
            let view = SpectralView {
                overdraw: false,
                cuts: planes.to_vec(),
                expression: Some(d.clone()),
                ..SpectralView::default()
            };
            let pixels = render(&gpu, &mut renderer, &view, size);
            let report = check_derived_cut_pixels(&tets, &d, (0, 0), (&camera, &planes), size, &pixels);
            eprintln!(
                "tetrahedra {text:?}: {} px, max error {:.2e}, {:.3} of the bound",
                report.covered, report.max_error, report.max_error_ratio
            );
            assert!(report.covered > 2000, "{text}: {report:?}");
            assert!(report.uncomparable * 100 <= report.covered, "{text}: {report:?}");
            assert!(report.passed(), "tetrahedra, {text:?}: {report:?}");
        }
    }

    #[test]
    fn unsuitable_views_are_refused() {
        let gpu = common::gpu();
        let mesh: Arc<SpectralMesh> = Arc::new(annulus(2, 3, 3, 3, NodeSet::GaussLobatto).unwrap());
        let d = Arc::new(DerivedField::new(&mesh, "u * cells").unwrap());
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).unwrap();
        let target = RenderTarget::new(&gpu, "derived", 32, 32, ColorFormat::Rgba8).unwrap();
        for (view, needle) in [
            (
                SpectralView { per_vertex: true, expression: Some(d.clone()), ..SpectralView::default() },
                "per vertex",
            ),
            (
                SpectralView { height: Some(0.0), expression: Some(d.clone()), ..SpectralView::default() },
                "height",
            ),
            // `cells` has one time step.
            (SpectralView { step: 1, expression: Some(d.clone()), ..SpectralView::default() }, "\"cells\""),
        ] {
            let err = renderer.render(&target, &view).err().map(|e| e.to_string()).unwrap_or_default();
            assert!(err.contains(needle), "{needle}: {err}");
        }
    }

    /// Spacetime slices: derived fields of |v| (with its exact gradient), U, v, the
    /// displacement and the strain, per pixel, against the f64 interpreter from each
    /// element's fields at the pixel's point, within 1e-4 of the slice's largest |value| (the
    /// tolerance of the U check in tests/spacetime.rs: the polynomial in f32 on the device,
    /// the point a pixel centre sees in f32). A colour render maps the range it found.
    #[test]
    fn spacetime_slices_show_derived_fields() {
        use galerkin::expression::spacetime::SpacetimeExpression;
        use galerkin::spacetime::generate::pulses;
        use galerkin::spacetime::reference::check_derived_flat_pixels;
        use galerkin::spacetime::{SpacetimeRenderer, SpacetimeView};
        let gpu = common::gpu();
        let m = pulses(6000);
        let mut r = SpacetimeRenderer::from_mesh(&gpu, &m, &Colormap::viridis()).unwrap();
        let t = 0.43 * m.time_range().1;
        let view = SpacetimeView { edges: false, ..SpacetimeView::from_above(r.data().summary(), t) };
        let (w, h) = (160, 160);
        let data = RenderTarget::new(&gpu, "data", w, h, ColorFormat::Rgba32F).unwrap();
        for text in [
            "speed",
            "length(grad(speed))",
            "eps_xx + eps_yy",
            "dot(v, disp) + U * t",
            "sqrt(U) - length(v) / (1 + x * x + y * y)",
        ] {
            let e = Arc::new(SpacetimeExpression::new(text).unwrap());
            r.set_expression(Some(e.clone()), None).unwrap();
            let Pixels::Rgba32F(pixels) = r.render(&data, &view).unwrap() else { panic!("float target") };
            let check = check_derived_flat_pixels(
                &m,
                &e,
                &view,
                r.default_height_scale(),
                (w, h),
                &pixels,
                (1, 1e-4),
            );
            eprintln!(
                "spacetime {text:?}: {} px, worst error {:.2e} of the largest",
                check.checked, check.worst_u
            );
            assert!(check.passed(), "{text}: {} failures; first: {:?}", check.failures, check.first_failure);
            assert!(check.checked > (w * h) as usize / 2, "{} pixels checked", check.checked);
        }
        // A colour render with the automatic range, and per-vertex colour refused.
        let colour = RenderTarget::new(&gpu, "colour", w, h, ColorFormat::Rgba8).unwrap();
        assert!(matches!(r.render(&colour, &view), Ok(Pixels::Rgba8(_))));
        let err = r.render(&colour, &SpacetimeView { per_vertex: true, ..view }).err().map(|e| e.to_string());
        assert!(err.is_some_and(|e| e.contains("per vertex")));
        // Back to U.
        r.set_expression(None, None).unwrap();
        let Pixels::Rgba32F(pixels) = r.render(&data, &view).unwrap() else { panic!("float target") };
        let check = galerkin::spacetime::reference::check_flat_pixels(
            &m,
            &view,
            r.default_height_scale(),
            (w, h),
            &pixels,
            1,
            1e-4,
        );
        assert!(check.passed(), "U after derived fields: {:?}", check.first_failure);
    }
}
