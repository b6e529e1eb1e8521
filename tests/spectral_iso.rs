//! Isosurfaces of solid meshes drawn per pixel (`iso.frag`) against the f64 ray caster
//! (`spectral::iso_reference`): curved tetrahedra VTK wrote (orders 3 and 6 on a cube of six)
//! and VTK's Lagrange hexahedra (order 3), two iso values each. Per pixel where both find a
//! surface: the same iso value, and the device's point within its bound of the f64 root along
//! the ray — |Δt| ≤ 4 (δf / |∂f/∂t| + 2⁻²² ℓ + 16 ε t), δf the f32 rounding bound of the
//! value there (`rounding_bound_hex`), ℓ the element box's diagonal (the bisection's
//! resolution), ε t the f32 position's; pixels where one side finds a surface and the other
//! none (or another one) are counted, and allowed only where the ray grazes the surface
//! (|cos| between ray and normal below 0.1: a root the samples straddle only barely) or
//! within half a pixel of another element's surface (silhouettes and element faces, where
//! rasterisation and the reference may pick either side) — at most 0.5 % of the pixels that
//! show a surface.

mod common;

use std::path::Path;
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::iso_reference::iso_reference;
use galerkin::spectral::reference::rounding_bound_hex;
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::{SpectralMesh, SpectralRenderer, SpectralView};

fn load(name: &str) -> SpectralMesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name);
    galerkin::spectral::load(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// |∂f/∂t| along unit ray `d` at element `e`'s reference point `r`, and |∇f|.
fn slope(mesh: &SpectralMesh, e: usize, r: [f64; 3], d: [f64; 3]) -> (f64, f64) {
    let (_, g) = mesh.value_gradient_at(0, 0, e, r);
    let (_, j) = mesh.map_hex(e, r);
    let jm = glam::DMat3::from_cols(j[0].into(), j[1].into(), j[2].into());
    let grad = jm.inverse().transpose() * glam::DVec3::from(g);
    (grad.dot(glam::DVec3::from(d)).abs(), grad.length())
}

#[test]
fn isosurfaces_match_the_f64_ray_caster() {
    let gpu = common::gpu();
    let size = (160u32, 120u32);
    let target =
        RenderTarget::new(&gpu, "isosurfaces", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    for name in ["tet_cube_o3.vtu", "tet_cube_o6.vtu", "hex_ascii.vtu"] {
        let mesh = Arc::new(load(name));
        let (lo, hi) = mesh.value_range(0, 0);
        let values = vec![lo + 0.3 * (hi - lo), lo + 0.6 * (hi - lo)];
        let camera = fit_camera(&mesh);
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let view = SpectralView { iso: values.clone(), overdraw: false, ..SpectralView::default() };
        let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        let reference = iso_reference(&mesh, (0, 0), &camera, &values, size);
        let (mut both, mut worst, mut excused, mut mismatched) = (0usize, 0.0f64, 0usize, Vec::new());
        let mut worst_abs = 0.0f64;
        for (k, want) in reference.iter().enumerate() {
            let t = &px[4 * k..4 * k + 4];
            let got =
                (!t[3].is_nan()).then(|| (t[3] as usize, t[2] as usize, f64::from(t[1]), f64::from(t[0])));
            match (got, want) {
                (None, None) => {}
                (Some((e, vk, dist, value)), Some(h)) if vk == h.value_index => {
                    let (ft, grad) = slope(&mesh, h.element, h.reference, h.direction);
                    let (blo, bhi) = mesh.bounds();
                    let diag = (0..3).map(|a| (bhi[a] - blo[a]).powi(2)).sum::<f64>().sqrt();
                    let delta_f = rounding_bound_hex(&mesh, 0, 0, h.element, h.reference);
                    let bound = 4.0
                        * (delta_f / ft.max(1e-12 * grad)
                            + diag * 2f64.powi(-22)
                            + 16.0 * f64::from(f32::EPSILON) * h.distance);
                    let err = (dist - h.distance).abs();
                    both += 1;
                    worst = worst.max(err / bound);
                    worst_abs = worst_abs.max(err);
                    if err > bound {
                        // A different element's surface at the same point is the same surface
                        // (shared faces); another layer is a mismatch.
                        mismatched.push((
                            k,
                            format!(
                                "element {e} at {dist} vs {} at {} (bound {bound:e})",
                                h.element, h.distance
                            ),
                        ));
                    }
                    let _ = value;
                }
                (got, want) => {
                    // Grazing rays and silhouettes.
                    let grazing = want.is_some_and(|h| {
                        let (ft, grad) = slope(&mesh, h.element, h.reference, h.direction);
                        ft < 0.1 * grad
                    });
                    if grazing {
                        excused += 1;
                    } else {
                        mismatched.push((k, format!("device {got:?}, reference {want:?}")));
                    }
                }
            }
        }
        let shown = reference.iter().filter(|h| h.is_some()).count();
        eprintln!(
            "{name}: {shown} reference pixels, {both} matched (worst {worst:.3} of the bound, {worst_abs:.2e} along the ray), {excused} grazing, {} mismatched",
            mismatched.len()
        );
        for m in mismatched.iter().take(8) {
            eprintln!("  pixel ({}, {}): {}", m.0 as u32 % size.0, m.0 as u32 / size.0, m.1);
        }
        // Two hexahedra's surfaces cover ~600 pixels of 160 × 120; the cubes' ~2,800.
        assert!(shown > 500, "{name}: the surfaces cover {shown} pixels");
        assert!(mismatched.len() * 200 <= shown, "{name}: {} mismatched of {shown}", mismatched.len());
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
