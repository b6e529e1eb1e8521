//! Spacetime data files and streaming (seed 003, the issue's large-data part): the `.gst`
//! binary round trip and its errors, VTK `.vtu` reading and writing and their errors, a
//! renderer streaming a memory-mapped file through a small resident window against one holding
//! the whole mesh, and per-stage frame times. GPU tests run with validation on.

mod common;

use std::path::Path;

use galerkin::render::{ColorFormat, Colormap, Pixels, RenderTarget};
use galerkin::spacetime::generate::{pulses, structured_mesh, PULSES_MATERIAL};
use galerkin::spacetime::{
    gst, vtu, Material, SpacetimeData, SpacetimeError, SpacetimeMesh, SpacetimeRenderer, SpacetimeView,
};

fn file_error(e: SpacetimeError, path: &Path, wants: &str) {
    let text = e.to_string();
    assert!(text.contains(&path.display().to_string()), "error does not name the file: {text}");
    assert!(text.contains(wants), "error {text:?} lacks {wants:?}");
}

#[test]
fn gst_files_round_trip_bit_for_bit() {
    let scratch = common::Scratch::new();
    let data = SpacetimeData::from_mesh(&pulses(3000)).unwrap();
    let path = scratch.file("round.gst");
    let summary = gst::write(&path, &data).unwrap();
    assert_eq!(&summary, data.summary());
    let back = gst::open(&path).unwrap();
    assert_eq!(back.records(), data.records());
    assert_eq!(back.lowest_times(), data.lowest_times());
    assert_eq!(back.materials(), data.materials());
    assert_eq!(back.summary(), data.summary());
    assert_eq!(back.path(), Some(path.as_path()));
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 4096 + 244 * data.len() as u64);
}

#[test]
fn malformed_gst_files_are_refused_naming_file_and_element() {
    let scratch = common::Scratch::new();
    let data = SpacetimeData::from_mesh(&pulses(1500)).unwrap();
    let good = scratch.file("good.gst");
    gst::write(&good, &data).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let n = data.len();
    let write = |name: &str, b: &[u8]| {
        let p = scratch.file(name);
        std::fs::write(&p, b).unwrap();
        p
    };

    let p = write("truncated.gst", &bytes[..bytes.len() - 100]);
    file_error(gst::open(&p).err().unwrap(), &p, "truncated");
    let p = write("short.gst", &bytes[..100]);
    file_error(gst::open(&p).err().unwrap(), &p, "too short");
    let mut b = bytes.clone();
    b[0] = b'X';
    let p = write("magic.gst", &b);
    file_error(gst::open(&p).err().unwrap(), &p, "magic");
    let mut b = bytes.clone();
    b[8] = 7;
    let p = write("version.gst", &b);
    file_error(gst::open(&p).err().unwrap(), &p, "version 7");

    // The index: element 10's lowest time made later than element 11's.
    let index = 4096 + 240 * n;
    let mut b = bytes.clone();
    let late = (data.lowest_times()[n - 1] + 1.0).to_le_bytes();
    b[index + 4 * 10..index + 4 * 11].copy_from_slice(&late);
    let p = write("unsorted.gst", &b);
    file_error(gst::open(&p).err().unwrap(), &p, "element 11: the index is not sorted");

    // A NaN coefficient in element 700: the file opens (records are not read at open), and the
    // first slice that reads the element fails naming it.
    let e = 700;
    let mut b = bytes.clone();
    let at = 4096 + 240 * e + 80 + 4 * 7;
    b[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let p = write("nan.gst", &b);
    let bad = gst::open(&p).unwrap();
    let t = f64::from(data.records()[e].lowest_time()) + 1e-4;
    let gpu = common::gpu();
    let mut r = SpacetimeRenderer::new(&gpu, bad, &Colormap::viridis()).unwrap();
    file_error(
        r.slice(t, None).err().unwrap(),
        &p,
        &format!("element {e}: a displacement coefficient is not finite"),
    );
    drop(r);

    // The writer: out-of-order elements are refused, and an unfinished file leaves nothing.
    let out = scratch.file("unfinished.gst");
    let mut w = gst::GstWriter::create(&out, data.materials()).unwrap();
    w.push(&data.records()[n - 1]).unwrap();
    file_error(w.push(&data.records()[0]).err().unwrap(), &out, "element 1: lowest time");
    drop(w);
    assert!(!out.exists());
    let left = std::fs::read_dir(out.parent().unwrap()).unwrap().flatten();
    assert!(
        !left.into_iter().any(|e| e.file_name().to_string_lossy().contains("unfinished.gst")),
        "a temporary was left"
    );
}

#[test]
fn vtu_files_round_trip_and_read_ascii_and_compressed_forms() {
    let scratch = common::Scratch::new();
    let mesh = pulses(1500);
    let path = scratch.file("round.vtu");
    vtu::write(&path, &mesh).unwrap();
    let back = vtu::read(&path).unwrap();
    assert_eq!(back, mesh, "appended raw binary round trip is exact (f64)");

    // A hand-written ASCII file as another program might write it: one tetrahedron, no frame
    // (the bounding box is the default) and no material index, u = (x t, y²) in local
    // coordinates of the bounding box frame centred at (0.5, 0.5, 0.5) with extents 1.
    let mut coefficients = [0.0; 40];
    coefficients[2 * 6] = 1.0; // x t → u_x
    coefficients[2 * 7 + 1] = 1.0; // y² → u_y
    let coeff_text: Vec<String> = coefficients.iter().map(|c| c.to_string()).collect();
    let ascii = format!(
        r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="4" NumberOfCells="1">
      <Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">0 0 0  1 0 0  0 1 0  0 0 1</DataArray></Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10</DataArray>
      </Cells>
      <CellData>
        <DataArray type="Float64" Name="coefficients" NumberOfComponents="40" format="ascii">{}</DataArray>
        <DataArray type="Float64" Name="lambda" format="ascii">2</DataArray>
        <DataArray type="Float64" Name="mu" format="ascii">1</DataArray>
      </CellData>
    </Piece>
  </UnstructuredGrid>
</VTKFile>"#,
        coeff_text.join(" ")
    );
    let p = scratch.file("ascii.vtu");
    std::fs::write(&p, &ascii).unwrap();
    let m = vtu::read(&p).unwrap();
    assert_eq!(m.materials, vec![Material { lambda: 2.0, mu: 1.0, density: 1.0 }]);
    let f = &m.fields[0];
    assert_eq!(f.frame.centre, [0.5; 3]);
    let x = [0.2, 0.3, 0.1];
    let u = galerkin::spacetime::evaluate(&f.frame, &m.materials[0], &f.coefficients, x).displacement;
    let q = f.frame.local(x);
    assert!((u[0] - q[0] * q[2]).abs() < 1e-15 && (u[1] - q[1] * q[1]).abs() < 1e-15, "{u:?}");

    // The same data written by VTK with zlib compression in inline base64 blocks: rebuild the
    // file with each array as one compressed block (header UInt32: 1 block, sizes, stream).
    let block = |values: &[u8]| {
        let z = miniz_oxide::deflate::compress_to_vec_zlib(values, 6);
        let mut b = Vec::new();
        for w in [1u32, values.len() as u32, values.len() as u32, z.len() as u32] {
            b.extend_from_slice(&w.to_le_bytes());
        }
        b.extend_from_slice(&z);
        base64(&b)
    };
    let f64s = |v: &[f64]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let zipped = ascii
        .replace(
            r#"byte_order="LittleEndian">"#,
            r#"byte_order="LittleEndian" compressor="vtkZLibDataCompressor">"#,
        )
        .replace(
            r#"<DataArray type="Float64" Name="coefficients" NumberOfComponents="40" format="ascii">"#,
            r#"<DataArray type="Float64" Name="coefficients" NumberOfComponents="40" format="binary">"#,
        )
        .replace(&coeff_text.join(" "), &block(&f64s(&coefficients)));
    let p = scratch.file("zlib.vtu");
    std::fs::write(&p, &zipped).unwrap();
    assert_eq!(vtu::read(&p).unwrap(), m);

    // Errors name the file and the element or array.
    let cases = [
        ("celltype.vtu", ascii.replace(">10<", ">5<"), "element 0: cell type 5"),
        ("index.vtu", ascii.replace(">0 1 2 3<", ">0 1 2 9<"), "element 0: vertex index 9 is out of range"),
        ("lambda.vtu", ascii.replace(r#"Name="lambda""#, r#"Name="lam""#), "no CellData array \"lambda\""),
        (
            "comps.vtu",
            ascii.replace(r#"NumberOfComponents="40""#, r#"NumberOfComponents="20""#),
            "array coefficients: 40 values in 20 components",
        ),
        ("number.vtu", ascii.replace(">2<", ">two<"), "array lambda: \"two\" is not a number"),
        ("flat.vtu", ascii.replace("0 0 1</DataArray>", "0 0 0</DataArray>"), "degenerate"),
        (
            "mu.vtu",
            ascii.replace(r#"Name="mu" format="ascii">1<"#, r#"Name="mu" format="ascii">-1<"#),
            "needs μ > 0",
        ),
    ];
    for (name, text, wants) in cases {
        let p = scratch.file(name);
        std::fs::write(&p, text).unwrap();
        file_error(vtu::read(&p).err().unwrap(), &p, wants);
    }
    let p = scratch.file("truncated.vtu");
    let full = std::fs::read(&path).unwrap();
    std::fs::write(&p, &full[..full.len() - 5000]).unwrap();
    file_error(vtu::read(&p).err().unwrap(), &p, "truncated");
}

fn base64(b: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in b.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// Renders `mesh` at `times` from memory (whole) and from a `.gst` file through a window of at
/// most a quarter of the elements, asserting the same slices and pixels; returns how many
/// slices uploaded records and how many of those reused part of the window.
fn compare_streamed(
    gpu: &galerkin::gpu::Gpu,
    scratch: &common::Scratch,
    name: &str,
    mesh: &SpacetimeMesh,
    times: &[f64],
) -> (usize, usize) {
    let n = mesh.tets.len();
    let path = scratch.file(name);
    gst::write(&path, &SpacetimeData::from_mesh(mesh).unwrap()).unwrap();
    let colormap = Colormap::viridis();
    let mut whole = SpacetimeRenderer::from_mesh(gpu, mesh, &colormap).unwrap();
    let mut streamed =
        SpacetimeRenderer::new(gpu, gst::open(&path).unwrap(), &colormap).unwrap().with_window_limit(n / 4);
    let target = RenderTarget::new(gpu, "fields", 96, 96, ColorFormat::Rgba32F).unwrap();
    let (mut uploads, mut partial) = (0, 0);
    for &t in times {
        let a = whole.slice(t, Some(0.002)).unwrap();
        let b = streamed.slice(t, Some(0.002)).unwrap();
        assert_eq!((a.active, a.triangles, a.lines), (b.active, b.triangles, b.lines), "{name}, t = {t}");
        let window = streamed.resident().unwrap();
        assert!(window.len() <= n / 4, "window {window:?}");
        uploads += usize::from(b.streamed > 0);
        // Moving on uploads only what is not resident yet (the window is a ring).
        partial += usize::from(b.streamed > 0 && b.streamed < window.len());
        let mut ta = whole.slice_triangles().unwrap();
        let mut tb = streamed.slice_triangles().unwrap();
        let key = |x: &(u32, [[f32; 2]; 3])| (x.0, x.1.map(|p| p.map(f32::to_bits)));
        ta.sort_by_key(key);
        tb.sort_by_key(key);
        assert!(ta == tb, "{name}, t = {t}: the streamed slice differs");
        let view = SpacetimeView { u_max: Some(1.0), ..SpacetimeView::from_above(whole.data().summary(), t) };
        assert_eq!(view.subdivide, None);
        let (Pixels::Rgba32F(pa), Pixels::Rgba32F(pb)) =
            (whole.render(&target, &view).unwrap(), streamed.render(&target, &view).unwrap())
        else {
            panic!("float targets")
        };
        // Without subdivision the slice is watertight (neighbours cut shared edges with the same
        // f32 arithmetic; a tent mesh is conforming within a slab), so every pixel centre is
        // covered once, whatever the draw order the slicer's atomics produce: the same pixels,
        // bit for bit (NaN background too). (Subdivided neighbours meet at f32 T-junctions where
        // either may win a pixel.)
        assert!(
            pa.iter().zip(&pb).all(|(x, y)| x.to_bits() == y.to_bits()),
            "{name}, t = {t}: pixels differ"
        );
    }
    (uploads, partial)
}

#[test]
fn a_streamed_file_renders_as_the_resident_mesh() {
    let scratch = common::Scratch::new();
    let gpu = common::gpu();
    // 12 time layers: the active range at any t is one layer, a twelfth of the elements, and
    // the window (three layers) moves in whole jumps. Forward in time (as playback), then back.
    let mut mesh = structured_mesh(12, 12, 12, [1.0, 1.0], 1.0, PULSES_MATERIAL);
    galerkin::spacetime::generate::project_field(
        &mut mesh,
        &galerkin::spacetime::generate::crossing_pulses(PULSES_MATERIAL, [1.0, 1.0]),
    );
    let (uploads, _) =
        compare_streamed(&gpu, &scratch, "layers.gst", &mesh, &[0.05, 0.3, 0.37, 0.55, 0.81, 0.97, 0.2]);
    assert!(uploads >= 3, "only {uploads} slices streamed");
    // A tent-pitched mesh: lowest times spread continuously, so a moving window keeps part of
    // what it holds and uploads the rest.
    let crack =
        galerkin::spacetime::scenario::generate(galerkin::spacetime::scenario::Scenario::Crack, 12_000);
    let [t0, t1] = SpacetimeData::from_mesh(&crack).unwrap().summary().time;
    let times: Vec<f64> = (0..12).map(|k| t0 + (t1 - t0) * (0.1 + 0.07 * f64::from(k))).collect();
    let (uploads, partial) = compare_streamed(&gpu, &scratch, "tents.gst", &crack, &times);
    assert!(uploads >= 3, "only {uploads} slices streamed");
    assert!(partial >= 1, "no slice reused the resident part of the window");
    // A window too small for the active range is an error that says so.
    let path = scratch.file("layers.gst");
    let mut tiny = SpacetimeRenderer::new(&gpu, gst::open(&path).unwrap(), &Colormap::viridis())
        .unwrap()
        .with_window_limit(10);
    let e = tiny.slice(0.5, None).err().unwrap();
    assert!(matches!(e, SpacetimeError::TooManyActive { limit: 10, .. }), "{e}");
}

#[test]
fn frames_report_per_stage_device_times() {
    let gpu = common::gpu();
    let mesh = pulses(6000);
    let mut r = SpacetimeRenderer::from_mesh(&gpu, &mesh, &Colormap::viridis()).unwrap();
    let target = RenderTarget::new(&gpu, "frame", 160, 90, ColorFormat::Rgba8).unwrap();
    let t = 0.5 * mesh.time_range().1;
    let view = SpacetimeView {
        u_max: Some(0.05),
        subdivide: Some(0.001),
        ..SpacetimeView::looking_at(r.data().summary(), t)
    };
    let Some(mut profiler) = galerkin::gpu::Profiler::new(&gpu, 4).ok() else {
        eprintln!("skipped: no timestamp queries on this device");
        return;
    };
    let (stats, times) = r.frame(&target, &view, Some(&mut profiler)).unwrap();
    let times = times.unwrap();
    assert!(times.slice_ms > 0.0 && times.subdivide_ms > 0.0 && times.draw_ms > 0.0, "{times:?}");
    assert_eq!(stats, r.slice(t, view.subdivide).unwrap(), "frame() slices as slice() does");
    // The subdivision asked for more triangles than the first buffers hold: the frame grew them
    // and redid the slice. A frame without a profiler or subdivision works too.
    assert!(stats.triangles > 3 * 1024, "{stats:?}");
    let (coarse, none) = r.frame(&target, &SpacetimeView { subdivide: None, ..view }, None).unwrap();
    assert!(none.is_none());
    assert!(coarse.triangles < stats.triangles, "{coarse:?} vs {stats:?}");
}

#[test]
fn the_cli_generates_converts_and_refuses_bad_input_naming_it() {
    let scratch = common::Scratch::new();
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        (out.status.code(), stderr)
    };
    let gst_path = scratch.file("cli.gst");
    let vtu_path = scratch.file("cli.vtu");
    let back = scratch.file("cli-back.gst");
    let s = |p: &Path| p.to_string_lossy().to_string();
    // spacetime gen streams a scenario to .gst; convert to .vtu and back: the same records.
    let (code, err) =
        run(&["spacetime", "gen", "--generate", "booster", "--elements", "3000", "--out", &s(&gst_path)]);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(run(&["spacetime", "convert", &s(&gst_path), &s(&vtu_path)]).0, Some(0));
    assert_eq!(run(&["spacetime", "convert", &s(&vtu_path), &s(&back)]).0, Some(0));
    let (a, b) = (gst::open(&gst_path).unwrap(), gst::open(&back).unwrap());
    assert_eq!(a.len(), b.len());
    // .vtu holds f64; records are f32 of the same values, so the round trip is exact. The
    // elements are re-sorted by lowest time (ties keep file order), so compare as sets.
    let key = |r: &galerkin::spacetime::ElementRecord| bytemuck::bytes_of(r).to_vec();
    let mut ra: Vec<_> = a.records().iter().map(key).collect();
    let mut rb: Vec<_> = b.records().iter().map(key).collect();
    ra.sort();
    rb.sort();
    assert!(ra == rb, "records changed in the .gst → .vtu → .gst round trip");
    // Bad input: each error names the file (or lists what exists) and exits 1.
    let missing = scratch.file("missing.gst");
    let (code, err) = run(&["spacetime", "render", &s(&missing)]);
    assert_eq!(code, Some(1));
    assert!(err.contains(&s(&missing)), "{err}");
    // Unknown data sets are argument errors (exit 2) listing the choices; bar1d is no
    // tetrahedral data set, so `gen` does not offer it.
    let (code, err) = run(&["spacetime", "gen", "--generate", "volcano", "--out", &s(&gst_path)]);
    assert_eq!(code, Some(2));
    assert!(err.contains("volcano") && err.contains("crack") && err.contains("--generate"), "{err}");
    let (code, err) = run(&["spacetime", "gen", "--generate", "bar1d", "--out", &s(&gst_path)]);
    assert_eq!(code, Some(2));
    assert!(err.contains("'bar1d'") && err.contains("--generate") && err.contains("pulses"), "{err}");
    let (code, err) = run(&["spacetime", "render", &s(&gst_path), "--time", "99"]);
    assert_eq!(code, Some(1));
    assert!(err.contains("outside the data set's time span"), "{err}");
    let text = scratch.file("notes.txt");
    std::fs::write(&text, "not spacetime data").unwrap();
    // A file of another kind is an argument error (exit 2), refused before any work.
    let (code, err) = run(&["spacetime", "convert", &s(&text), &s(&vtu_path)]);
    assert_eq!(code, Some(2));
    assert!(err.contains(&s(&text)) && err.contains(".gst or .vtu"), "{err}");
}

/// Two writers of one `.gst` name at once (two `spacetime gen --out x.gst`): each writes its own
/// temporary, both finish, and the file is the complete output of one of them — never a mix.
#[test]
fn concurrent_writers_of_one_file_never_mix() {
    let scratch = common::Scratch::new();
    let out = scratch.file("both.gst");
    let small = SpacetimeData::from_mesh(&pulses(1000)).unwrap();
    let large = SpacetimeData::from_mesh(&pulses(3000)).unwrap();
    let mut a = gst::GstWriter::create(&out, small.materials()).unwrap();
    let mut b = gst::GstWriter::create(&out, large.materials()).unwrap();
    for (ra, rb) in small.records().iter().zip(large.records()) {
        a.push(ra).unwrap();
        b.push(rb).unwrap();
    }
    for rb in &large.records()[small.len()..] {
        b.push(rb).unwrap();
    }
    a.finish().unwrap();
    b.finish().unwrap();
    let back = gst::open(&out).unwrap();
    assert_eq!(back.len(), large.len(), "the last writer to finish wins, whole");
    let left: Vec<_> = std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".partial"))
        .collect();
    assert!(left.is_empty(), "temporaries left: {left:?}");
}

/// A mesh the reader would refuse (a NaN corner, a degenerate tetrahedron) is not written as
/// `.vtu` either (`spacetime convert` from a bad `.gst` used to write one): the error names the
/// element and no file appears.
#[test]
fn a_bad_mesh_is_not_written() {
    let scratch = common::Scratch::new();
    let good = pulses(1000);
    let mut nan = good.clone();
    let corner = nan.tets[7][2] as usize;
    nan.vertices[corner][0] = f64::NAN;
    let mut flat = good.clone();
    let t = flat.tets[3];
    flat.tets[3] = [t[0], t[1], t[1], t[3]];
    for (name, mesh) in [("nan.vtu", &nan), ("flat.vtu", &flat)] {
        let out = scratch.file(name);
        let e = vtu::write(&out, mesh).expect_err(name).to_string();
        assert!(e.contains(name) && e.contains("element"), "{name}: {e}");
        assert!(!out.exists(), "{name} was written");
    }
    vtu::write(&scratch.file("good.vtu"), &good).expect("a good mesh is written");
}
