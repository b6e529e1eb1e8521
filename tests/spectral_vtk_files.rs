//! Files written by VTK itself (`scripts/vtk-fixtures.py`, VTK 9.7's
//! vtkXMLUnstructuredGridWriter): two order-3 Lagrange hexahedra and two order-3 Lagrange
//! quadrilaterals, nodes placed by VTK's own `PointIndexFromIJK`, in every encoding the writer
//! offers. Each must read as the same cells, with the field equal to the polynomial the script
//! wrote; hostile variants are refused naming the file and array.

mod common;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spectral::reference::{check_pixels, rounding_bound};
use galerkin::spectral::{vtu, Shape, SpectralMesh, SpectralRenderer, SpectralView, View2d};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk").join(name)
}

/// The script's fields (cubic: exact in the order-3 cells on their affine geometry).
fn hex_u(x: [f64; 3]) -> f64 {
    x[0] * x[0] * x[1] + x[2].powi(3) - x[0] * x[1] * x[2] + 0.5
}
fn quad_u(x: [f64; 3]) -> f64 {
    x[0].powi(3) - 2.0 * x[0] * x[1] * x[1] + x[1]
}

/// The largest difference between the read field and the script's polynomial over a grid of
/// reference points of every element (node and non-node points).
fn worst_field_error(mesh: &SpectralMesh) -> f64 {
    let field = mesh.field_index(Some("u")).expect("field u");
    let samples = [0.0, 0.13, 0.5, 0.71, 1.0];
    let mut worst = 0.0f64;
    for e in 0..mesh.elements() {
        for &a in &samples {
            for &b in &samples {
                for &c in &samples {
                    let err = match mesh.shape {
                        Shape::Hexahedron | Shape::Tetrahedron => {
                            let (x, _) = mesh.map_hex(e, [a, b, c]);
                            (mesh.value_hex(field, 0, e, [a, b, c]) - hex_u(x)).abs()
                        }
                        Shape::Quadrilateral | Shape::Triangle => {
                            let (x, _) = mesh.map(e, a, b);
                            (mesh.value(field, 0, e, a, b) - quad_u(x)).abs()
                        }
                    };
                    worst = worst.max(err);
                }
            }
        }
    }
    worst
}

const HEX_FILES: &[&str] = &[
    "hex_ascii.vtu",
    "hex_binary_none_u32.vtu",
    "hex_binary_none_u64.vtu",
    "hex_binary_zlib_u32.vtu",
    "hex_binary_zlib_u64.vtu",
    "hex_binary_lz4_u32.vtu",
    "hex_binary_lz4_u64.vtu",
    "hex_binary_lzma_u32.vtu",
    "hex_binary_lzma_u64.vtu",
    "hex_appended_none_u32.vtu",
    "hex_appended_none_u64.vtu",
    "hex_appended_zlib_u32.vtu",
    "hex_appended_zlib_u64.vtu",
    "hex_appended_lz4_u32.vtu",
    "hex_appended_lz4_u64.vtu",
    "hex_appended_lzma_u32.vtu",
    "hex_appended_lzma_u64.vtu",
    "hex_appended_raw_zlib_u32.vtu",
    "hex_appended_raw_none_u64.vtu",
    "hex_legacy.vtu",
];

#[test]
fn every_encoding_vtk_writes_reads_as_the_same_lagrange_hexahedra_with_the_exact_field() {
    let reference = vtu::read(&fixture("hex_ascii.vtu")).expect("ascii");
    assert_eq!((reference.elements(), reference.shape), (2, Shape::Hexahedron));
    for name in HEX_FILES {
        let mesh = vtu::read(&fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.elements(), 2, "{name}");
        // The polynomial, at nodes and between them: 1e-12 is rounding of cubic values of
        // size ~10 through the barycentric evaluation; a node out of place errs by ~0.1.
        let err = worst_field_error(&mesh);
        assert!(err < 1e-12, "{name}: the field is off by {err:e}");
        // The same nodes as the ascii file (VTK's ascii doubles round-trip exactly).
        for e in 0..2 {
            assert_eq!(mesh.element_points(e), reference.element_points(e), "{name} element {e}");
        }
    }
}

#[test]
fn vtk_s_default_settings_and_ascii_read_as_the_same_quadrilaterals() {
    for name in ["quad_default.vtu", "quad_ascii.vtu"] {
        let mesh = vtu::read(&fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((mesh.elements(), mesh.shape), (2, Shape::Quadrilateral), "{name}");
        let err = worst_field_error(&mesh);
        assert!(err < 1e-12, "{name}: the field is off by {err:e}");
    }
    // VTK's defaults are appended base64 zlib: the encoding most .vtu files are in.
    let head = std::fs::read_to_string(fixture("quad_default.vtu")).expect("text");
    assert!(head.contains("vtkZLibDataCompressor") && head.contains("encoding=\"base64\""));
}

/// A copy of fixture `name` with `edit` applied to its bytes, in a scratch directory.
fn edited(name: &str, edit: impl FnOnce(&mut Vec<u8>)) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let mut bytes = std::fs::read(fixture(name)).expect("fixture");
    edit(&mut bytes);
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).expect("written");
    (dir, path)
}

fn appended_start(bytes: &[u8]) -> usize {
    let at = bytes.windows(13).position(|w| w == b"<AppendedData").expect("appended");
    at + bytes[at..].iter().position(|&c| c == b'_').expect("marker") + 1
}

#[test]
fn hostile_variants_are_refused_naming_the_file_and_array_before_inflating() {
    // A compression header declaring a 2 GiB block: refused from the header, not inflated.
    let (_d, path) = edited("hex_appended_raw_zlib_u32.vtu", |b| {
        let s = appended_start(b);
        b[s + 4..s + 8].copy_from_slice(&(1u32 << 31).to_le_bytes());
    });
    let e = vtu::read(&path).expect_err("huge block").to_string();
    assert!(
        e.contains("hex_appended_raw_zlib_u32.vtu") && e.contains("array u") && e.contains("declares"),
        "{e}"
    );
    assert!(e.len() < 400, "a short message, not the data: {} bytes", e.len());
    // Corrupt compressed bytes: a short message naming the array.
    let (_d, path) = edited("hex_appended_raw_zlib_u32.vtu", |b| {
        let s = appended_start(b);
        let words = u32::from_le_bytes(b[s..s + 4].try_into().expect("4 bytes")) as usize;
        for x in &mut b[s + 4 * (3 + words)..s + 4 * (3 + words) + 16] {
            *x ^= 0x5a;
        }
    });
    let e = vtu::read(&path).expect_err("corrupt zlib").to_string();
    assert!(e.contains("array u") && e.contains("zlib") && e.len() < 400, "{e}");
    // A count over the limit, an unknown compressor, a bad version: refused by name.
    for (from, to, want) in [
        ("NumberOfPoints=\"128\"", "NumberOfPoints=\"99999999999999\"", "NumberOfPoints"),
        ("vtkLZ4DataCompressor", "vtkBrotliDataCompressor", "vtkBrotliDataCompressor"),
        ("version=\"2.3\"", "version=\"two\"", "version"),
    ] {
        let (_d, path) = edited("hex_binary_lz4_u64.vtu", |b| {
            let text = String::from_utf8(b.clone()).expect("inline binary is text");
            assert!(text.contains(from), "{from}");
            *b = text.replacen(from, to, 1).into_bytes();
        });
        let e = vtu::read(&path).expect_err(want).to_string();
        assert!(e.contains("hex_binary_lz4_u64.vtu") && e.contains(want), "{e}");
    }
    // Truncated at several points: an error, never a panic.
    let whole = std::fs::read(fixture("hex_appended_lzma_u64.vtu")).expect("fixture");
    for cut in [whole.len() / 3, whole.len() / 2, whole.len() - 40] {
        let (_d, path) = edited("hex_appended_lzma_u64.vtu", |b| b.truncate(cut));
        assert!(vtu::read(&path).is_err(), "cut at {cut}");
    }
}

/// A cell type the renderer does not draw — here VTK's cubic triangles relabelled as Lagrange
/// wedges (73) — is refused naming the file, the element and the type by its VTK name;
/// VTK's quadratic Lagrange triangle and cubic Lagrange tetrahedra (drawn since simplices
/// joined the spectral meshes) read as such.
#[test]
fn a_cell_type_the_renderer_does_not_draw_is_refused_by_name() {
    let (_d, path) = edited("tri_curved.vtu", |b| {
        *b = String::from_utf8_lossy(b).replace("          69 69\n", "          73 73\n").into_bytes()
    });
    let e = galerkin::spectral::load(&path, &[]).expect_err("a wedge").to_string();
    assert!(
        e.contains("tri_curved.vtu") && e.contains("element 0") && e.contains("VTK_LAGRANGE_WEDGE"),
        "{e}"
    );
    let tri = galerkin::spectral::load(&fixture("tri_lagrange.vtu"), &[]).expect("a triangle");
    assert_eq!((tri.shape, tri.geometry.order), (Shape::Triangle, 2));
    let tet = galerkin::spectral::load(&fixture("tet_curved.vtu"), &[]).expect("a tetrahedron");
    assert_eq!((tet.shape, tet.geometry.order), (Shape::Tetrahedron, 3));
}

/// VTK's time convention for one file: the grid's field data `TimeValue` (written by VTK,
/// `scripts/vtk-fixtures.py`) is the step's time; the field data's other entries are not read;
/// the data are the same as without it.
#[test]
fn a_files_time_value_is_its_steps_time() {
    let timed = galerkin::spectral::load(&fixture("quad_time.vtu"), &[]).expect("the timed file");
    let plain = galerkin::spectral::load(&fixture("quad_default.vtu"), &[]).expect("the same without a time");
    let field = timed.field_index(Some("u")).expect("u");
    assert_eq!(timed.fields[field].times, vec![2.5]);
    assert_eq!(plain.fields[field].times, vec![0.0]);
    assert_eq!(timed.fields[field].steps, plain.fields[field].steps);
    // A TimeValue that is not one finite number is ignored, not an error; a huge declared
    // tuple count is refused naming the array.
    let text = std::fs::read_to_string(fixture("quad_time.vtu")).expect("fixture");
    let (_d, path) = edited("quad_time.vtu", |b| {
        *b = String::from_utf8_lossy(b)
            .replace("NumberOfTuples=\"1\"", "NumberOfTuples=\"99999999999999\"")
            .into_bytes()
    });
    let e = vtu::read(&path).expect_err("a huge field-data count").to_string();
    assert!(e.contains("TimeValue") && e.contains("over the limit"), "{e}");
    assert!(text.contains("TimeValue"));
}

#[test]
fn a_paraview_collection_reads_as_time_steps_at_its_times() {
    let mesh = galerkin::spectral::load(&fixture("quad_series.pvd"), &[]).expect("the collection");
    let field = mesh.field_index(Some("u")).expect("u");
    assert_eq!(mesh.fields[field].times, vec![0.0, 0.5, 1.0]);
    for step in 0..3 {
        for e in 0..mesh.elements() {
            for (a, b) in [(0.3, 0.6), (1.0, 0.0), (0.77, 0.12)] {
                let (x, _) = mesh.map(e, a, b);
                let want = (1.0 + step as f64) * quad_u(x);
                let got = mesh.value(field, step, e, a, b);
                assert!((got - want).abs() < 1e-12, "step {step} element {e}: {got} vs {want}");
            }
        }
    }
    // Hostile collections: a missing file, other cells, several parts at one time.
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    for f in ["quad_series_0.vtu", "hex_ascii.vtu"] {
        std::fs::copy(fixture(f), dir.path().join(f)).expect("copied");
    }
    let collection = |sets: &[(&str, &str)]| {
        let mut text = String::from("<VTKFile type=\"Collection\" version=\"0.1\"><Collection>\n");
        for (t, f) in sets {
            text.push_str(&format!("<DataSet timestep=\"{t}\" part=\"0\" file=\"{f}\"/>\n"));
        }
        text.push_str("</Collection></VTKFile>\n");
        let path = dir.path().join("c.pvd");
        std::fs::write(&path, text).expect("written");
        galerkin::spectral::load(&path, &[]).expect_err("refused").to_string()
    };
    let e = collection(&[("0", "quad_series_0.vtu"), ("1", "gone.vtu")]);
    assert!(e.contains("gone.vtu"), "{e}");
    let e = collection(&[("0", "quad_series_0.vtu"), ("1", "hex_ascii.vtu")]);
    assert!(e.contains("hex_ascii.vtu") && e.contains("elements"), "{e}");
    let e = collection(&[("0", "quad_series_0.vtu"), ("0", "quad_series_0.vtu")]);
    assert!(e.contains("c.pvd") && e.contains("time 0"), "{e}");
    let e = collection(&[]);
    assert!(e.contains("no data set"), "{e}");
}

/// VTK's Bézier cells, polynomial and rational (RationalWeights 0.6–2.1): our f64 geometry map
/// and field agree with VTK's own evaluation (`EvaluateLocation` and its interpolation weights,
/// written by scripts/vtk-fixtures.py) at four parametric points per cell.
#[test]
fn bezier_cells_evaluate_as_vtk_evaluates_them_rational_ones_too() {
    for name in ["bezier_quad", "bezier_hex", "bezier_quad_rational", "bezier_hex_rational"] {
        let mesh = vtu::read(&fixture(&format!("{name}.vtu"))).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(mesh.weights.is_some(), name.ends_with("rational"), "{name}");
        let json = std::fs::read_to_string(fixture(&format!("{name}.json"))).expect("evaluations");
        let records: Vec<common::evaluations::Record> = serde_json::from_str(&json).expect("JSON");
        assert_eq!(records.len(), 4 * mesh.elements(), "{name}");
        let field = mesh.field_index(Some("u")).expect("u");
        let (worst_x, worst_u) = common::evaluations::worst_differences(&mesh, field, &records);
        // Both sides evaluate (ratios of) Bernstein sums of values of size ~1 in f64.
        assert!(worst_x < 1e-12 && worst_u < 1e-12, "{name}: geometry {worst_x:e}, field {worst_u:e}");
    }
}

/// A rational mesh is written as VTK rational Bézier cells (no polynomial cell represents it)
/// and reads back bit for bit: points, weights and coefficients. (VTK reads the written file as
/// the same cells: `python3 scripts/vtk-check-output.py` on it, checked when this was written.)
#[test]
fn rational_cells_write_as_rational_bezier_cells_and_read_back_the_same() {
    for name in ["bezier_quad_rational.vtu", "bezier_hex_rational.vtu"] {
        let mesh = vtu::read(&fixture(name)).expect("fixture");
        let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
        let out = dir.path().join(name);
        vtu::write(&out, &mesh).expect("written");
        let back = vtu::read(&out).expect("read back");
        assert_eq!(back, mesh, "{name}");
        let text = String::from_utf8_lossy(&std::fs::read(&out).expect("bytes")).into_owned();
        assert!(
            text.contains("<PointData RationalWeights=\"RationalWeights\">"),
            "{name}: VTK would not see the weights"
        );
    }
}

/// A weight that is not positive (the rational map could divide by zero) is refused naming the
/// file, the element and the weight.
#[test]
fn a_rational_weight_that_is_not_positive_is_refused_naming_the_element() {
    let text = std::fs::read_to_string(fixture("bezier_quad_rational.vtu")).expect("fixture");
    let start = text.find("Name=\"RationalWeights\"").expect("weights array");
    let open = start + text[start..].find('>').expect("tag") + 1;
    let first = open + text[open..].find(|c: char| !c.is_whitespace()).expect("values");
    let end = first + text[first..].find(char::is_whitespace).expect("end of value");
    for bad in ["0", "-1", "nan"] {
        let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
        let path = dir.path().join("bad_weight.vtu");
        std::fs::write(&path, format!("{}{bad}{}", &text[..first], &text[end..])).expect("written");
        let e = vtu::read(&path).expect_err("a bad weight").to_string();
        assert!(
            e.contains("bad_weight.vtu") && e.contains("element 0") && e.contains("rational weight"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn a_cut_plane_that_misses_the_mesh_is_an_error_not_an_empty_image() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let out = dir.path().join("miss.png");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["spectral", "render"])
        .arg(fixture("bezier_hex.vtu"))
        .args(["--cut", "z=5", "--size", "64x48", "--out"])
        .arg(&out)
        .output()
        .expect("ran");
    assert!(!run.status.success(), "exit 0 for a plane outside the mesh");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("cut plane 0") && err.contains("misses the mesh"), "{err}");
    assert!(!out.exists(), "an image was written");
}

/// VTK's default-encoded quadrilaterals rendered: every covered pixel shows the script's
/// polynomial at its centre (closed form) within the pixel's f32 rounding bound; the Bézier
/// quadrilaterals (whose reference is VTK's evaluation, matched above to 1e-12) pass the
/// f64 per-pixel check with no pixel missing.
#[test]
fn vtk_written_quadrilaterals_render_pixel_exact() {
    let gpu = common::gpu();
    let (w, h) = (256, 128);
    let render = |mesh: &Arc<SpectralMesh>| {
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let target = RenderTarget::new(&gpu, "vtk fixture", w, h, ColorFormat::Rgba32F).expect("target");
        let Pixels::Rgba32F(px) = r.render(&target, &SpectralView::default()).expect("rendered") else {
            panic!("a float target returned bytes")
        };
        px
    };
    let mesh = Arc::new(vtu::read(&fixture("quad_default.vtu")).expect("VTK's default file"));
    let px = render(&mesh);
    let view = View2d::fit(&mesh, w, h);
    let mut covered = 0;
    for y in 0..h {
        for x in 0..w {
            let t = &px[4 * (y * w + x) as usize..][..4];
            if t[3].is_nan() || t[3] < 0.0 {
                continue;
            }
            covered += 1;
            let p = view.pixel_centre(x, y, w, h);
            let e = t[3] as usize;
            let q = mesh.inverse_map(e, p, [0.5, 0.5]).expect("inside").map(|c| c.clamp(0.0, 1.0));
            // The f32 evaluation's bound at this point, plus 1e-9 for the f64 reference's own
            // rounding of a cubic of size ~10.
            let bound = rounding_bound(&mesh, 0, 0, e, q) + 1e-9;
            let exact = quad_u([p[0], p[1], 0.0]);
            assert!((f64::from(t[0]) - exact).abs() <= bound, "pixel ({x}, {y}): {} vs {exact}", t[0]);
        }
    }
    assert!(covered > 10_000, "{covered} pixels covered");
    for name in ["bezier_quad.vtu", "bezier_quad_rational.vtu"] {
        let bezier = Arc::new(vtu::read(&fixture(name)).expect("Bézier"));
        let px = render(&bezier);
        let report = check_pixels(&bezier, 0, 0, &View2d::fit(&bezier, w, h), (w, h), &px);
        eprintln!("{name}: {report:?}");
        assert!(report.passed() && report.covered > 10_000, "{name}: {report:?}");
    }
}

#[test]
fn a_paraview_file_series_reads_as_the_same_time_steps_as_the_collection() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    for k in 0..3 {
        let f = format!("quad_series_{k}.vtu");
        std::fs::copy(fixture(&f), dir.path().join(&f)).expect("copied");
    }
    let series = dir.path().join("quad.vtu.series");
    std::fs::write(
        &series,
        r#"{ "file-series-version" : "1.0", "files" : [
            { "name" : "quad_series_2.vtu", "time" : 1.0 },
            { "name" : "quad_series_0.vtu", "time" : 0 },
            { "name" : "quad_series_1.vtu", "time" : 0.5 } ] }"#,
    )
    .expect("written");
    let from_series = galerkin::spectral::load(&series, &[]).expect("the series");
    let from_pvd = galerkin::spectral::load(&fixture("quad_series.pvd"), &[]).expect("the collection");
    assert_eq!(from_series.fields, from_pvd.fields, "the same steps at the same times");
    std::fs::write(&series, r#"{ "file-series-version" : "2.0", "files" : [] }"#).expect("written");
    let e = galerkin::spectral::load(&series, &[]).expect_err("version").to_string();
    assert!(e.contains("quad.vtu.series") && e.contains("2.0"), "{e}");
}

/// VTK's Lagrange hexahedra (an appended zlib file) through a cut plane: every covered pixel
/// shows the script's cubic at its point on the plane (closed form) within the pixel's f32
/// bound, and none inside an element is missing.
#[test]
fn vtk_written_hexahedra_render_pixel_exact_through_a_cut_plane() {
    use galerkin::spectral::reference::{plane_point, rounding_bound_hex};
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let (w, h) = (240u32, 180u32);
    let mesh = Arc::new(vtu::read(&fixture("hex_appended_zlib_u32.vtu")).expect("VTK's hexahedra"));
    let camera = fit_camera(&mesh);
    let cut = [0.0, 0.0, 1.0, 0.4];
    let view = SpectralView { overdraw: false, cuts: vec![cut], ..SpectralView::default() };
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let target = RenderTarget::new(&gpu, "vtk hexahedra", w, h, ColorFormat::Rgba32F).expect("target");
    let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    let (mut covered, mut missing) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let t = &px[4 * (y * w + x) as usize..][..4];
            let p = plane_point(&camera, cut, x, y, (w, h));
            if t[3].is_nan() {
                if mesh.locate_hex(p, -1e-3).is_some() {
                    missing += 1;
                }
                continue;
            }
            covered += 1;
            let e = t[3] as usize;
            let q = mesh.inverse_map_hex(e, p, [0.5; 3]).expect("inside").map(|c| c.clamp(0.0, 1.0));
            // The f32 bound at this point, plus 1e-9 for the f64 reference's own rounding.
            let bound = rounding_bound_hex(&mesh, 0, 0, e, q) + 1e-9;
            assert!(
                (f64::from(t[0]) - hex_u(p)).abs() <= bound,
                "pixel ({x}, {y}): {} vs {}",
                t[0],
                hex_u(p)
            );
        }
    }
    assert!(covered > 2500 && missing == 0, "{covered} covered, {missing} missing");
}

/// VTK's Bézier hexahedra (perturbed control points: curved) through two cut planes: every
/// covered pixel shows the Bernstein polynomial at its point on the plane (the f64 reference,
/// which agrees with VTK's own evaluation to 1e-12 above) within the pixel's f32 bound, none
/// outside its element, none inside an element missing.
#[test]
fn vtk_written_bezier_hexahedra_render_pixel_exact_through_cut_planes() {
    use galerkin::spectral::reference::check_cut_pixels;
    use galerkin::spectral::render::fit_camera;
    let gpu = common::gpu();
    let size = (240u32, 180u32);
    let target =
        RenderTarget::new(&gpu, "bezier hexahedra", size.0, size.1, ColorFormat::Rgba32F).expect("target");
    for name in ["bezier_hex.vtu", "bezier_hex_rational.vtu"] {
        let mesh = Arc::new(vtu::read(&fixture(name)).expect("VTK's Bézier hexahedra"));
        let field = mesh.field_index(Some("u")).expect("u");
        let camera = fit_camera(&mesh);
        let (lo, hi) = mesh.bounds();
        let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
        let mid: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
        for cut in [[0.0, 0.0, 1.0, mid[2]], [0.3, 0.2, 1.0, 0.3 * mid[0] + 0.2 * mid[1] + mid[2]]] {
            let view = SpectralView { field, overdraw: false, cuts: vec![cut], ..SpectralView::default() };
            let Pixels::Rgba32F(px) = r.render(&target, &view).expect("rendered") else {
                panic!("a float target returned bytes")
            };
            let report = check_cut_pixels(&mesh, field, 0, &camera, &[cut], size, &px);
            eprintln!("{name} plane {cut:?}: {report:?}");
            assert!(report.covered > 1500 && report.passed(), "{name} plane {cut:?}: {report:?}");
        }
    }
}

/// Cell data as VTK writes it (quad_cells.vtu: no point data, a scalar `pressure` of 1.5 + 2c
/// on cell c, a vector `flux`): the scalar is a piecewise-constant field, drawn so that every
/// covered pixel shows its element's value within the pixel's f32 rounding bound; the vector
/// is not a field. A file whose only array is a vector (quad_vectors.vtu) is refused naming
/// the file and listing its arrays.
#[test]
fn vtk_written_cell_data_draws_as_piecewise_constant_fields() {
    let mesh = Arc::new(vtu::read(&fixture("quad_cells.vtu")).expect("cell data only"));
    let names: Vec<&str> = mesh.fields.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["pressure"]);
    let gpu = common::gpu();
    let (w, h) = (256, 128);
    let mut r = SpectralRenderer::new(&gpu, mesh.clone(), &Colormap::viridis()).expect("renderer");
    let target = RenderTarget::new(&gpu, "cell data", w, h, ColorFormat::Rgba32F).expect("target");
    let Pixels::Rgba32F(px) = r.render(&target, &SpectralView::default()).expect("rendered") else {
        panic!("a float target returned bytes")
    };
    let view = View2d::fit(&mesh, w, h);
    let mut covered = [0usize; 2];
    for y in 0..h {
        for x in 0..w {
            let t = &px[4 * (y * w + x) as usize..][..4];
            if t[3].is_nan() || t[3] < 0.0 {
                continue;
            }
            let e = t[3] as usize;
            covered[e] += 1;
            let p = view.pixel_centre(x, y, w, h);
            let q = mesh.inverse_map(e, p, [0.5, 0.5]).expect("inside").map(|c| c.clamp(0.0, 1.0));
            let exact = 1.5 + 2.0 * e as f64;
            let bound = rounding_bound(&mesh, 0, 0, e, q) + 1e-12;
            assert!(
                (f64::from(t[0]) - exact).abs() <= bound,
                "pixel ({x}, {y}) of element {e}: {} vs {exact}",
                t[0]
            );
        }
    }
    assert!(covered.iter().all(|&c| c > 2_000), "{covered:?} pixels covered per element");
    let err = vtu::read(&fixture("quad_vectors.vtu")).expect_err("nothing to draw").to_string();
    for word in ["quad_vectors.vtu", "no field to draw", "velocity (3 components)", "cell data none"] {
        assert!(err.contains(word), "{err:?} does not say {word:?}");
    }
}

/// A partitioned data set written by VTK's parallel writer (hex_pieces.pvtu: the two
/// hexahedra split into a piece each by vtkExtractUnstructuredGridPiece) reads as the same
/// data set as the whole file, element by element: the same field coefficients, and the same
/// nodes to f32 rounding (the extractor stores its points as Float32: 2.4 at most, so within
/// 2.4 · 2⁻²⁴ ≈ 1.5e-7); a missing piece is refused naming it.
#[test]
fn a_partitioned_vtk_data_set_reads_as_one() {
    let pieces = galerkin::spectral::load(&fixture("hex_pieces.pvtu"), &[]).expect("the .pvtu");
    let whole = vtu::read(&fixture("hex_ascii.vtu")).expect("the whole");
    assert_eq!(pieces.elements(), 2);
    assert_eq!(pieces.points.len(), whole.points.len());
    for (a, b) in pieces.points.iter().zip(&whole.points) {
        assert!((0..3).all(|c| (a[c] - b[c]).abs() <= 1.5e-7), "{a:?} vs {b:?}");
    }
    assert_eq!(pieces.fields, whole.fields);
    let dir = tempfile::tempdir().expect("scratch");
    std::fs::copy(fixture("hex_pieces.pvtu"), dir.path().join("hex_pieces.pvtu")).expect("copied");
    std::fs::copy(fixture("hex_pieces_0.vtu"), dir.path().join("hex_pieces_0.vtu")).expect("copied");
    let err =
        galerkin::spectral::load(&dir.path().join("hex_pieces.pvtu"), &[]).expect_err("a piece missing");
    assert!(err.to_string().contains("hex_pieces_1.vtu"), "{err}");
}
