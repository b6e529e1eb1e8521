//! Isosurfaces, volumes and transparent isosurfaces of meshes MFEM wrote itself
//! (`scripts/mfem-fixtures.py`, PyMFEM 4.10): curved hexahedra (H1 order 3 on curved geometry)
//! and curved tetrahedra (H1 order 5 on quartic geometry, 24 of a box), against the f64 ray
//! casters with the tolerances of tests/spectral_iso.rs (each surface pixel's root within its
//! own f32 bound of the f64 root, at most 0.5 % of the pixels one-sided and only where the ray
//! grazes) and tests/spectral_volume.rs / tests/spectral_iso_sheets.rs (every channel within
//! 1/255, grazing rays at most 3 %). The loaders' agreement with MFEM's own evaluation is
//! tests/spectral_mfem_files.rs's.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::iso_reference::{compare, iso_reference};
use galerkin::spectral::render::fit_camera;
use galerkin::spectral::transfer::TransferFunction;
use galerkin::spectral::volume_reference::{compare_volume, volume_reference, VolumeColours};
use galerkin::spectral::{SpectralMesh, SpectralRenderer, SpectralView};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mfem").join(name)
}

fn load(name: &str) -> Arc<SpectralMesh> {
    Arc::new(
        galerkin::spectral::load(&fixture(&format!("{name}.mesh")), &[fixture(&format!("{name}.gf"))])
            .unwrap_or_else(|e| panic!("{name}: {e}")),
    )
}

const TOLERANCE: f64 = 1.0 / 255.0;

#[test]
fn isosurfaces_and_volumes_of_meshes_mfem_wrote_match_the_f64_ray_casters() {
    let gpu = common::gpu();
    let colormap = Colormap::viridis();
    for name in ["hex_h1_p3", "tet_h1_p5"] {
        let mesh = load(name);
        let (lo, hi) = mesh.value_range(0, 0);
        let at = |s: f64| lo + s * (hi - lo);
        let camera = fit_camera(&mesh);
        let mut renderer = SpectralRenderer::new(&gpu, mesh.clone(), &colormap).expect("renderer");
        // Opaque isosurfaces at 30 % and 60 % of the range.
        let size = (120u32, 90u32);
        let target =
            RenderTarget::new(&gpu, "mfem iso", size.0, size.1, ColorFormat::Rgba32F).expect("target");
        let values = vec![at(0.3), at(0.6)];
        let view = SpectralView { iso: values.clone(), overdraw: false, ..SpectralView::default() };
        let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else { panic!("bytes") };
        let reference = iso_reference(&mesh, (0, 0), &camera, &values, size);
        let agreement = compare(&mesh, (0, 0), &px, &reference);
        eprintln!(
            "{name} isosurfaces: {} reference pixels, {} matched (worst {:.3} of the bound), {} grazing, {} mismatched",
            agreement.shown,
            agreement.matched,
            agreement.worst_of_bound,
            agreement.grazing,
            agreement.mismatched.len()
        );
        assert!(agreement.shown > 500, "{name}: {agreement:?}");
        assert!(agreement.mismatched.len() * 200 <= agreement.shown, "{name}: {agreement:?}");
        // A volume with an isosurface sheet in it, and transparent isosurfaces alone.
        let size = (64u32, 48u32);
        let target =
            RenderTarget::new(&gpu, "mfem volume", size.0, size.1, ColorFormat::Rgba32F).expect("target");
        let tf = TransferFunction::new(
            vec![(lo, 0.0), (at(0.3), 0.6), (at(0.5), 0.05), (hi, 0.9)],
            0.25 * mesh.diagonal(),
        )
        .expect("valid");
        let colours = VolumeColours { colormap: &colormap, range: (lo, hi), log: false };
        for (what, view, tf) in [
            (
                "volume",
                SpectralView { volume: Some(tf.clone()), overdraw: false, ..SpectralView::default() },
                tf.clone(),
            ),
            (
                "transparent isosurfaces",
                SpectralView {
                    iso: values.clone(),
                    iso_opacity: 0.5,
                    overdraw: false,
                    ..SpectralView::default()
                },
                TransferFunction::clear(),
            ),
        ] {
            let Pixels::Rgba32F(px) = renderer.render(&target, &view).expect("rendered") else {
                panic!("bytes")
            };
            let reference = volume_reference(&mesh, (0, 0), &camera, &tf, &view.sheets(), &colours, size, 16);
            let agreement = compare_volume(&px, &reference, TOLERANCE);
            eprintln!(
                "{name} {what}: {} pixels, worst {:.2} of 1/255, {} grazing, {} one-sided, {} mismatched",
                agreement.shown,
                agreement.worst / TOLERANCE,
                agreement.grazing,
                agreement.missing,
                agreement.mismatched.len()
            );
            assert!(agreement.shown > 300, "{name} {what}: {} pixels", agreement.shown);
            assert!(
                agreement.mismatched.is_empty(),
                "{name} {what}: {:?}",
                &agreement.mismatched[..agreement.mismatched.len().min(4)]
            );
            assert!(
                agreement.grazing * 100 <= 3 * agreement.shown,
                "{name} {what}: {} grazing",
                agreement.grazing
            );
        }
    }
}
