//! Isosurfaces of solid meshes drawn per pixel (`iso.frag`) against the f64 ray caster
//! (`spectral::iso_reference`): curved tetrahedra VTK wrote (orders 3 and 6 on a cube of six),
//! VTK's Lagrange hexahedra (order 3), two iso values each, and curved hexahedra of orders 6
//! and 9 (scripts/vtk-iso-fixtures.py) whose field has a saddle: a level set whose two sheets
//! touch, and nested ones around it (four values). Compared by `iso_reference::compare`: per
//! pixel where both find a surface, the same iso value, and the device's point within its
//! bound of the f64 root along the ray — |Δt| ≤ 4 (δf / |∂f/∂t| + 2⁻²² ℓ + 16 ε t), δf the f32
//! rounding bound of the value there (`rounding_bound_hex`), ℓ the mesh's diagonal (the
//! bisection's resolution), ε t the f32 position's; pixels where one side finds a surface and
//! the other none (or another one) are counted, and allowed only where the ray grazes the
//! surface (|cos| between ray and normal below 0.1: a root the samples straddle only barely)
//! — at most 0.5 % of the pixels that show a surface, for silhouettes and element faces where
//! rasterisation and the reference may pick either side.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{Camera, ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::iso_reference::{compare, iso_reference};
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::{SpectralMesh, SpectralRenderer, SpectralView};

fn load(name: &str) -> SpectralMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
    galerkin::spectral::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn isosurfaces_match_the_f64_ray_caster() {
    let gpu = common::gpu();
    let size = (160u32, 120u32);
    let target =
        RenderTarget::new(&gpu, "isosurfaces", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    // The saddle fixtures' u = 0 is a double cone whose sheets touch at the shared face's
    // centre; 0.04 and 0.12 are nested around it, −0.04 on the other side.
    let saddle: &[f64] = &[0.0, 0.04, 0.12, -0.04];
    // Straight down onto the saddle (the bent grid moves the face centre (1, ½, ½) to
    // (1.06, 0.55, 0.6)): the cone u = 0 alone, its upper sheet seen down to where the two
    // sheets touch.
    let above = Camera {
        eye: [1.06, 0.55, 2.2],
        target: [1.06, 0.55, 0.6],
        up: [0.0, 1.0, 0.0],
        fov_y_degrees: 40.0,
        near: 0.01,
        far: 100.0,
    };
    for (name, values, camera) in [
        ("tet_cube_o3.vtu", None, None),
        ("tet_cube_o6.vtu", None, None),
        ("hex_ascii.vtu", None, None),
        ("hex_saddle_o6.vtu", Some(saddle), None),
        ("hex_saddle_o9.vtu", Some(saddle), None),
        ("hex_saddle_o9.vtu", Some(&[0.0][..]), Some(above)),
    ] {
        let mesh = Arc::new(load(name));
        let (lo, hi) = mesh.value_range(0, 0);
        let values = values.map_or(vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)], |v| v.to_vec());
        let view = SpectralView { iso: values.clone(), overdraw: false, camera, ..SpectralView::default() };
        let camera_given = camera;
        let camera = camera.unwrap_or_else(|| fit_camera(&mesh));
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let reference = iso_reference(&mesh, (0, 0), &camera, &values, size);
        let agreement = compare(&mesh, (0, 0), &px, &reference);
        let shown = agreement.shown;
        eprintln!(
            "{name}: {shown} reference pixels, {} matched (worst {:.3} of the bound, {:.2e} along the ray), {} grazing, {} mismatched",
            agreement.matched,
            agreement.worst_of_bound,
            agreement.worst_along_ray,
            agreement.grazing,
            agreement.mismatched.len()
        );
        for m in agreement.mismatched.iter().take(8) {
            eprintln!("  pixel ({}, {}): {}", m.0 as u32 % size.0, m.0 as u32 / size.0, m.1);
        }
        let mismatched = agreement.mismatched;
        // Two hexahedra's surfaces cover ~600 pixels of 160 × 120; the cubes' ~2,800.
        assert!(shown > 500, "{name}: the surfaces cover {shown} pixels");
        assert!(mismatched.len() * 200 <= shown, "{name}: {} mismatched of {shown}", mismatched.len());
        // Looking down onto the touching point, the rays near it meet two roots between the
        // same two samples: none of them may be missed.
        assert!(camera_given.is_none() || mismatched.is_empty(), "{name} from above: {mismatched:?}");
    }
}

/// Bad iso views: a value outside the field's range is a warning (and the picture has no
/// surface pixel), not an error; a quadrilateral mesh, a NaN value, more than eight values and
/// isosurfaces together with cut planes are refused by name.
#[test]
fn iso_views_that_cannot_be_drawn_are_refused_or_warned() {
    use galerkin::spectral::picture::view_warnings;
    let gpu = common::gpu();
    let mesh = Arc::new(load("tet_cube_o3.vtu"));
    let (lo, hi) = mesh.value_range(0, 0);
    let outside = SpectralView { iso: vec![hi + 1.0], ..SpectralView::default() };
    let warnings = view_warnings(&mesh, &outside);
    assert!(warnings.len() == 1 && warnings[0].contains("outside the field's range"), "{warnings:?}");
    assert!(view_warnings(&mesh, &SpectralView { iso: vec![0.5 * (lo + hi)], ..SpectralView::default() })
        .is_empty());
    let target = RenderTarget::new(&gpu, "iso", 64, 48, ColorFormat::Rgba32F).expect("target");
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let Pixels::Rgba32F(px) = r.render(&target, &outside).expect("drawn") else { panic!("bytes") };
    assert!(px.chunks_exact(4).all(|t| t[3].is_nan()), "no surface outside the range");
    for (view, what) in [
        (SpectralView { iso: vec![f64::NAN], ..SpectralView::default() }, "not a finite number"),
        (SpectralView { iso: vec![0.5; 9], ..SpectralView::default() }, "at most 8"),
        (
            SpectralView { iso: vec![0.5], cuts: vec![[0.0, 0.0, 1.0, 0.5]], ..SpectralView::default() },
            "cut planes",
        ),
    ] {
        let err = r.render(&target, &view).expect_err("refused").to_string();
        assert!(err.contains(what), "{err}");
    }
    let quads = Arc::new(load("quad_default.vtu"));
    let mut q = SpectralRenderer::new(&gpu, quads, &Colormap::viridis()).expect("renderer");
    let err =
        q.render(&target, &SpectralView { iso: vec![0.5], ..SpectralView::default() }).expect_err("refused");
    assert!(err.to_string().contains("hexahedral and tetrahedral meshes"), "{err}");
}

/// VTK's own evaluation of the saddle fixtures (geometry and field at parametric points, in
/// the `.json` the script wrote beside them) is ours to 1e-11 (values of size 1); and the
/// value bounds the isosurface pass culls elements by contain the field wherever it is
/// sampled, and overestimate its sampled spread at most fourfold.
#[test]
fn saddle_fixtures_and_value_bounds_agree_with_vtk_and_the_samples() {
    for name in ["hex_saddle_o6", "hex_saddle_o9"] {
        let mesh = load(&format!("{name}.vtu"));
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(format!("{name}.json"));
        let data: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(path).expect("VTK's samples")).expect("json");
        let samples = data["evaluations"].as_array().expect("evaluations");
        assert_eq!(samples.len(), 6);
        for s in samples {
            let f = |v: &serde_json::Value| -> Vec<f64> {
                v.as_array().expect("array").iter().map(|x| x.as_f64().expect("number")).collect()
            };
            let (e, r, x) = (s["element"].as_u64().expect("element") as usize, f(&s["ref"]), f(&s["x"]));
            let r = [r[0], r[1], r[2]];
            let (ours, _) = mesh.map_hex(e, r);
            for a in 0..3 {
                assert!((ours[a] - x[a]).abs() < 1e-11, "{name} e {e} at {r:?}: x {ours:?} vs VTK's {x:?}");
            }
            let (u, want) = (mesh.value_hex(0, 0, e, r), s["value"].as_f64().expect("value"));
            assert!((u - want).abs() < 1e-11, "{name} e {e} at {r:?}: u {u} vs VTK's {want}");
        }
    }
    for name in ["tet_cube_o6.vtu", "hex_saddle_o9.vtu", "hex_ascii.vtu"] {
        let mesh = load(name);
        let bounds = galerkin::spectral::proxy::value_bounds(&mesh, 0, 0).expect("bounds");
        let mut sampled = vec![[f64::MAX, f64::MIN]; mesh.elements()];
        mesh.for_each_sample(|e, r| {
            let v = mesh.value_hex(0, 0, e, r);
            sampled[e] = [sampled[e][0].min(v), sampled[e][1].max(v)];
        });
        for (e, (b, s)) in bounds.iter().zip(&sampled).enumerate() {
            let slack = 1e-12 * (1.0 + s[0].abs().max(s[1].abs()));
            assert!(
                b[0] <= s[0] + slack && s[1] <= b[1] + slack,
                "{name} element {e}: bounds {b:?}, sampled {s:?}"
            );
            // Bernstein bounds overestimate by at most the interior control values' reach.
            assert!(
                b[1] - b[0] <= 4.0 * (s[1] - s[0]) + slack,
                "{name} element {e}: bounds {b:?}, sampled {s:?}"
            );
        }
    }
}

/// Isosurfaces coloured by a second field (`--colour-by`, `iso_colour.frag`): the field v is the
/// node interpolant of x + 2y − z, which on isoparametric elements is that linear function
/// exactly (the geometry is interpolated by the same basis). At every pixel where the device
/// draws a surface, the colouring value it reports must be v at its own root, x = eye + t d:
/// within 4 (δv + √6 · 10⁻⁶ ℓ) — δv the f32 rounding bound of v there, 10⁻⁶ ℓ the point's error
/// when Newton stops (10⁻⁶ in reference units, elements at most the diagonal ℓ across), √6 = |∇v|.
/// The surfaces themselves are those of u: compared with the f64 ray caster as above.
#[test]
fn isosurfaces_coloured_by_a_second_field() {
    use galerkin::spectral::reference::rounding_bound_hex;
    use galerkin::spectral::Field;
    let gpu = common::gpu();
    let size = (64u32, 48u32);
    let target = RenderTarget::new(&gpu, "iso colour", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    for name in ["tet_cube_o3.vtu", "hex_saddle_o6.vtu"] {
        let mut mesh = load(name);
        assert_eq!(mesh.values_per_element(), mesh.points_per_element(), "{name}: isoparametric");
        let v: Vec<f64> = mesh.points.iter().map(|p| p[0] + 2.0 * p[1] - p[2]).collect();
        mesh.fields.push(Field { name: "v".into(), times: vec![0.0], steps: vec![v] });
        let mesh = Arc::new(mesh);
        let (lo, hi) = mesh.value_range(0, 0);
        let values = vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)];
        let view = SpectralView {
            iso: values.clone(),
            colour_by: Some(1),
            overdraw: false,
            ..SpectralView::default()
        };
        let camera = fit_camera(&mesh);
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else { panic!("bytes") };
        let reference = iso_reference(&mesh, (0, 0), &camera, &values, size);
        let agreement = compare(&mesh, (0, 0), &px, &reference);
        assert!(
            agreement.shown > 300 && agreement.mismatched.len() * 200 <= agreement.shown,
            "{name}: {agreement:?}"
        );
        let diag = mesh.diagonal();
        let (mut checked, mut worst) = (0usize, 0.0f64);
        for (k, hit) in reference.iter().enumerate() {
            let p = &px[4 * k..4 * k + 4];
            let Some(h) = hit else { continue };
            if p[3].is_nan() {
                continue;
            }
            let (_, d) = camera.pixel_ray(k as u32 % size.0, k as u32 / size.0, size.0, size.1);
            let x: [f64; 3] = std::array::from_fn(|a| camera.eye[a] + f64::from(p[1]) * d[a]);
            let exact = x[0] + 2.0 * x[1] - x[2];
            let bound =
                4.0 * (rounding_bound_hex(&mesh, 1, 0, h.element, h.reference) + 6f64.sqrt() * 1e-6 * diag);
            let err = (f64::from(p[0]) - exact).abs();
            worst = worst.max(err / bound);
            assert!(err <= bound, "{name} pixel {k}: v {} vs {exact} (bound {bound:e})", p[0]);
            checked += 1;
        }
        eprintln!("{name}: {checked} pixels coloured by v, worst {worst:.3} of the bound");
        assert!(checked > 200, "{name}: {checked}");
    }
    // Without --iso there is nothing to colour; a field that does not exist is refused.
    let mesh = Arc::new(load("tet_cube_o3.vtu"));
    let err = galerkin::spectral::picture::check_view(
        &mesh,
        &SpectralView { colour_by: Some(0), ..SpectralView::default() },
    )
    .expect_err("refused");
    assert!(err.to_string().contains("give --iso"), "{err}");
    let mut r = SpectralRenderer::new(&gpu, mesh, &Colormap::viridis()).expect("renderer");
    let err = r
        .render(&target, &SpectralView { iso: vec![0.5], colour_by: Some(3), ..SpectralView::default() })
        .expect_err("refused");
    assert!(err.to_string().contains("no such field"), "{err}");
}

/// Element edges on isosurfaces (`--edges`): the surface is darkened where it meets a face of
/// its element. Drawn with and without, the pixels that change are those whose f64 surface
/// point (the ray caster's) lies within the edge width of a face along the surface
/// (`iso_reference::face_distance_px`, the twin of the shader's measure): every pixel under
/// half the width changes and none over 1.5 widths does — except where the device's root lies
/// in another element than the reference's or the two sides disagree by f32 rounding at the
/// band's edge, at most 1 % of the pixels showing the surface; and some pixels do change.
#[test]
fn isosurface_element_edges_darken_where_the_surface_meets_element_faces() {
    use galerkin::spectral::iso_reference::{face_distance_px, ISO_EDGE_PX};
    let gpu = common::gpu();
    let size = (128u32, 96u32);
    let target = RenderTarget::new(&gpu, "iso edges", size.0, size.1, ColorFormat::Rgba8).expect("target");
    for name in ["tet_cube_o3.vtu", "hex_saddle_o6.vtu"] {
        let mesh = Arc::new(load(name));
        let (lo, hi) = mesh.value_range(0, 0);
        let values = vec![lo + 0.45 * (hi - lo)];
        let camera = fit_camera(&mesh);
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let mut draw = |edges: bool| {
            let view =
                SpectralView { iso: values.clone(), overdraw: false, edges, ..SpectralView::default() };
            match renderer.render(&target, &view).expect("rendered") {
                Pixels::Rgba8(px) => px,
                Pixels::Rgba32F(_) => panic!("a colour target returned floats"),
            }
        };
        let (plain, edged) = (draw(false), draw(true));
        let reference = iso_reference(&mesh, (0, 0), &camera, &values, size);
        let (mut shown, mut darkened, mut wrong) = (0usize, 0usize, Vec::new());
        for (k, hit) in reference.iter().enumerate() {
            let changed = (0..3).any(|c| plain[4 * k + c].abs_diff(edged[4 * k + c]) >= 2);
            darkened += usize::from(changed);
            let Some(h) = hit else { continue };
            shown += 1;
            let px = face_distance_px(&mesh, (0, 0), h, &camera, size.1);
            if (px < 0.5 * ISO_EDGE_PX && !changed) || (px > 1.5 * ISO_EDGE_PX && changed) {
                wrong.push((k, px, changed));
            }
        }
        eprintln!("{name}: {shown} surface pixels, {darkened} on element edges, {} disagree", wrong.len());
        assert!(darkened > 50 && darkened * 2 < shown, "{name}: {darkened} of {shown}");
        assert!(wrong.len() * 100 <= shown, "{name}: {:?}", &wrong[..wrong.len().min(10)]);
    }
}
