//! Values, lengths and options checked where they are read (issue 49): the hostile-input
//! leftovers, a case per class — endless runs, values accepted that must be refused, and
//! errors too vague to act on. Every file here is made by the engine's own generators and then
//! damaged; each case must be refused, quickly, naming the file and the line, element, array
//! or option.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

/// Runs `f`, which must fail within 20 s with an error containing every one of `words`.
fn refused<E: std::fmt::Display>(what: &str, f: impl FnOnce() -> Result<(), E>, words: &[&str]) -> String {
    let start = Instant::now();
    let e = match f() {
        Ok(()) => panic!("{what}: accepted"),
        Err(e) => e.to_string(),
    };
    assert!(start.elapsed() < Duration::from_secs(20), "{what}: took {:?}", start.elapsed());
    for w in words {
        assert!(e.contains(w), "{what}: {e:?} does not mention {w:?}");
    }
    e
}

fn galerkin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("galerkin runs")
}

/// Runs the binary, which must succeed.
fn made(args: &[&str]) {
    let out = galerkin(args);
    assert!(out.status.success(), "galerkin {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

/// Runs the binary, which must fail with exit code `code` within 20 s, its stderr containing
/// every one of `words`.
fn cli_refused(args: &[&str], code: i32, words: &[&str]) {
    let start = Instant::now();
    let out = galerkin(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "galerkin {args:?}: {stderr}");
    assert!(start.elapsed() < Duration::from_secs(20), "galerkin {args:?} took {:?}", start.elapsed());
    for w in words {
        assert!(stderr.contains(w), "galerkin {args:?}: {stderr:?} does not mention {w:?}");
    }
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn text(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A shipped scene with one line edited (which must be there).
fn edited(scene: &str, find: &str, replace: &str) -> String {
    let text = std::fs::read_to_string(repo(scene)).expect("a shipped scene");
    assert!(text.contains(find), "{scene} has no {find:?}");
    text.replacen(find, replace, 1)
}

/// A small bird (about 20,000 cells) with `frames` animation frames.
fn bird_scene(frames: usize) -> String {
    format!(
        "[bird]\nframes = {frames}\n[box]\nlo = [-1.4, -1.8, -1.3]\nhi = [1.4, 1.8, 1.3]\nspacing = 0.25\n\
         [flow]\ninitial_velocity = [0.0, 0.0, 0.0]\nviscosity = 1e-3\nframe_time = 0.02\nframes = 2\n"
    )
}

/// Endless runs: a scene's frame count of 2⁴⁰ is refused where it is read, and frames past a
/// surface animation's end are refused before the first step, by the library and the CLI.
#[test]
fn endless_runs_are_refused_before_the_first_step() {
    use galerkin::fluid::scene::FluidScene;
    let huge = edited("scenes/fluid/tunnel_small.toml", "frames = ", "frames = 1099511627776 #");
    refused(
        "frames = 2^40",
        || FluidScene::parse(&huge, Path::new("tunnel.toml")).map(|_| ()),
        &["tunnel.toml", "frames", "at most 1000000"],
    );
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let bird = scratch.path().join("bird.toml");
    std::fs::write(&bird, bird_scene(12)).expect("written");
    let mut scene = FluidScene::load(&bird).expect("the small bird");
    assert_eq!(scene.max_frames(), 11);
    let out = scratch.path().join("run");
    refused(
        "400 frames of a 12-frame animation",
        || galerkin::fluid::run::simulate_run(&mut scene, 400, &out, false, &mut |_, _, _, _| {}).map(|_| ()),
        &["400 frames", "12 frames", "at most 11 steps"],
    );
    assert!(!out.join("snapshots.json").exists(), "a run was started");
    cli_refused(
        &["fluid", "simulate", text(&bird), "--frames", "400", "--out", text(&out)],
        1,
        &["400 frames", "at most 11 steps"],
    );
}

/// A tunnel run of 2 frames and a model trained on it, written by the engine.
fn tunnel_run(scratch: &Path) -> (PathBuf, PathBuf) {
    let sim = scratch.join("sim");
    made(&[
        "fluid",
        "simulate",
        text(&repo("scenes/fluid/tunnel_small.toml")),
        "--frames",
        "2",
        "--out",
        text(&sim),
    ]);
    let model = scratch.join("model.safetensors");
    made(&["fluid", "train", text(&sim), "--out", text(&model)]);
    (sim, model)
}

/// Copies the snapshot directory `from` to `to`.
fn copy_run(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("dir");
    for e in std::fs::read_dir(from).expect("run").flatten() {
        if e.path().is_file() {
            std::fs::copy(e.path(), to.join(e.file_name())).expect("copied");
        }
    }
}

/// Snapshots: a NaN or 1e308 in a velocity, an array a byte too long, a negative frame time —
/// each refused where read, naming the file and the frame or key; a run stopped by a signal
/// (its header says `"complete": false`) keeps up to one frame more without being refused.
#[test]
fn snapshot_values_and_lengths_are_checked_where_read() {
    use galerkin::fluid::snapshots::SnapshotReader;
    use galerkin::reduce::SnapshotSource;
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let (sim, _) = tunnel_run(scratch.path());
    let header = std::fs::read_to_string(sim.join("snapshots.json")).expect("header");
    assert!(header.contains("\"complete\": true"), "a finished run is marked complete: {header}");
    let run = SnapshotReader::open(&sim).expect("the valid run");
    let len = run.meta().len("u");
    for (what, value, reason) in [("NaN", f64::NAN, "not finite"), ("1e308", 1e308, "past the limit")] {
        let dir = scratch.path().join(format!("u-{what}"));
        copy_run(&sim, &dir);
        let mut bytes = std::fs::read(dir.join("u.f64")).expect("u");
        // Frame 1, value 3.
        let at = 8 * (len + 3);
        bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
        std::fs::write(dir.join("u.f64"), bytes).expect("written");
        let damaged = SnapshotReader::open(&dir).expect("the header and lengths are fine");
        refused(
            &format!("{what} in u (frame)"),
            || damaged.frame("u", 1).map(|_| ()),
            &["u.f64", "frame 1", "value 3", reason],
        );
        refused(
            &format!("{what} in u (rows for the PCA)"),
            || -> Result<(), String> {
                let mut source = damaged.source("u").map_err(|e| e.to_string())?;
                source.rows(0..len).map(|_| ()).map_err(|e| e.to_string())
            },
            &["u.f64", "frame 1", "row 3", reason],
        );
    }
    let long = scratch.path().join("long");
    copy_run(&sim, &long);
    let mut bytes = std::fs::read(long.join("f.f64")).expect("f");
    bytes.push(0);
    std::fs::write(long.join("f.f64"), &bytes).expect("written");
    refused("f.f64 a byte too long", || SnapshotReader::open(&long).map(|_| ()), &["f.f64", "bytes"]);
    // The same extra bytes after an interrupt: part of a frame the run did not finish.
    let header_path = long.join("snapshots.json");
    std::fs::write(&header_path, header.replace("\"complete\": true", "\"complete\": false"))
        .expect("written");
    assert!(SnapshotReader::open(&long).is_ok(), "an unfinished run's partial frame is refused");
    // A signal after push wrote a whole quantity of the next frame, before the header counted
    // it: one whole frame more is an unfinished run's; one byte past that is not.
    let f_len = 8 * run.meta().len("f");
    bytes.truncate(bytes.len() - 1);
    bytes.extend(std::iter::repeat_n(0u8, f_len));
    std::fs::write(long.join("f.f64"), &bytes).expect("written");
    assert!(SnapshotReader::open(&long).is_ok(), "an unfinished run's whole next frame is refused");
    bytes.push(0);
    std::fs::write(long.join("f.f64"), &bytes).expect("written");
    refused(
        "an unfinished run's f.f64 past one frame more",
        || SnapshotReader::open(&long).map(|_| ()),
        &["f.f64", "at most one more"],
    );
    let negative = scratch.path().join("negative");
    copy_run(&sim, &negative);
    let dt = serde_json::from_str::<serde_json::Value>(&header).expect("json")["frame_time"].clone();
    let edit = header.replacen(&format!("\"frame_time\": {dt}"), "\"frame_time\": -0.02", 1);
    assert_ne!(edit, header);
    std::fs::write(negative.join("snapshots.json"), edit).expect("written");
    refused(
        "a negative frame time",
        || SnapshotReader::open(&negative).map(|_| ()),
        &["snapshots.json", "frame_time -0.02"],
    );
}

/// Reduced models: a flipped bit inside a tensor, a NaN or 1e308 in one (written with valid
/// checksums, as a buggy writer would), a negative frame time — refused at load, naming the
/// file and the tensor or key, not later as a singular Padé denominator.
#[test]
fn reduced_model_values_are_checked_at_load() {
    use galerkin::fluid::reduced::ReducedFluidModel;
    use galerkin::reduce::{load_arrays, save_arrays};
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let (_, model) = tunnel_run(scratch.path());
    ReducedFluidModel::load(&model).expect("the valid model");
    // A bit flipped in the middle of the data (past the header: inside some array).
    let mut bytes = std::fs::read(&model).expect("model");
    let at = bytes.len() - bytes.len() / 4;
    bytes[at] ^= 0x10;
    let flipped = scratch.path().join("flipped.safetensors");
    std::fs::write(&flipped, &bytes).expect("written");
    let e = refused(
        "a flipped bit",
        || ReducedFluidModel::load(&flipped).map(|_| ()),
        &["flipped.safetensors", "do not match the checksum"],
    );
    assert!(e.contains('`'), "the array is not named: {e}");
    let (meta, arrays) = load_arrays(&model).expect("arrays");
    let name = "tensor/A";
    for (what, value, reason) in [("NaN", f64::NAN, "not finite"), ("1e308", 1e308, "past the limit")] {
        let mut arrays = arrays.clone();
        let mut data = arrays[name].data().to_vec();
        data[5] = value;
        let shape = arrays[name].shape().to_vec();
        arrays.insert(name.to_string(), galerkin::tensor::Tensor::from_vec(&shape, data).expect("tensor"));
        let path = scratch.path().join(format!("{what}.safetensors"));
        let list: Vec<(String, &galerkin::tensor::Tensor)> =
            arrays.iter().map(|(n, t)| (n.clone(), t)).collect();
        save_arrays(&path, meta.clone(), &list).expect("written");
        refused(
            &format!("{what} in {name}"),
            || ReducedFluidModel::load(&path).map(|_| ()),
            &[&format!("{what}.safetensors"), "`tensor/A` entry 5", reason],
        );
    }
    let mut meta = meta;
    meta.insert("extra/frame_time".into(), "-0.02".into());
    let path = scratch.path().join("dt.safetensors");
    let list: Vec<(String, &galerkin::tensor::Tensor)> = arrays.iter().map(|(n, t)| (n.clone(), t)).collect();
    save_arrays(&path, meta, &list).expect("written");
    refused(
        "a negative frame time",
        || ReducedFluidModel::load(&path).map(|_| ()),
        &["dt.safetensors", "frame_time", "-0.02"],
    );
    // A motion of a training run the model does not have names the motion asked for.
    let reduced = scratch.path().join("r");
    cli_refused(
        &["fluid", "reduced", text(&model), "--motion", "computed:1000000", "--out", text(&reduced)],
        1,
        &["computed:1000000", "training runs 0 to 0"],
    );
    // A model trained from snapshot directories names no scene: compare asks for one.
    cli_refused(&["fluid", "compare", text(&model), "--out", text(&reduced)], 1, &["give --scene"]);
    // A run of another mesh: two fingerprints and what differs, not a debug dump of both.
    let coarse = scratch.path().join("coarse.toml");
    std::fs::write(&coarse, edited("scenes/fluid/tunnel_small.toml", "cell = 0.1", "cell = 0.2"))
        .expect("written");
    let other = scratch.path().join("other");
    made(&["fluid", "simulate", text(&coarse), "--frames", "2", "--out", text(&other)]);
    cli_refused(
        &["fluid", "reduced", text(&model), "--geometry", text(&other), "--out", text(&reduced)],
        1,
        &[
            "other",
            "not the mesh the model was trained on",
            "cells",
            "against",
            "trained on [2D,",
            "given [2D,",
        ],
    );
    let out =
        galerkin(&["fluid", "reduced", text(&model), "--geometry", text(&other), "--out", text(&reduced)]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("MeshFingerprint {"), "a debug dump: {stderr}");
    // --frames 0 on a reduced run is an argument error, not "NaN ms per step".
    cli_refused(
        &["fluid", "reduced", text(&model), "--frames", "0", "--out", text(&scratch.path().join("r"))],
        2,
        &["--frames", "at least 1"],
    );
    // One indicator at a time: both asked for is an argument error naming both.
    let estimated = scratch.path().join("estimated");
    cli_refused(
        &[
            "fluid",
            "reduced",
            text(&model),
            "--indicator",
            "--indicator-every",
            "2",
            "--out",
            text(&estimated),
        ],
        2,
        &["--indicator", "--indicator-every"],
    );
    // The unseen-velocity indicator writes one row per frame, every estimate finite and ≥ 0.
    made(&["fluid", "reduced", text(&model), "--frames", "2", "--indicator", "--out", text(&estimated)]);
    let csv = std::fs::read_to_string(estimated.join("indicator.csv")).expect("indicator.csv");
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("frame,unseen_velocity,step_unseen_velocity,error_estimate"));
    let estimates: Vec<f64> =
        lines.map(|l| l.rsplit(',').next().and_then(|v| v.parse().ok()).expect("a number")).collect();
    assert_eq!(estimates.len(), 3, "{csv}");
    assert!(estimates.iter().all(|e| e.is_finite() && *e >= 0.0), "{csv}");
}

/// Values accepted that must be refused: a linear quadrilateral with 25 points, a NaN Lamé
/// parameter in one element of a material others define well, a negative exitance in an OBJ
/// scene, a camera whose up vector is zero or along its line of sight.
#[test]
fn out_of_range_values_are_refused_where_read() {
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    // VTK_QUAD (9) of 25 points: an order-4 cell that must be VTK_LAGRANGE_QUADRILATERAL (70).
    let gen = scratch.path().join("grid.vtu");
    made(&["spectral", "gen", "--generate", "grid", "--order", "4", "--out", text(&gen)]);
    let quad = scratch.path().join("quad25.vtu");
    let cells = galerkin::spectral::vtu::read(&gen).expect("the generated file").elements();
    // The writer's appended raw types array: `cells` bytes of 70 in a row (no run of 32 'F's
    // occurs in the XML); each becomes 9.
    let mut bytes = std::fs::read(&gen).expect("bytes");
    let run = bytes.windows(cells).position(|w| w.iter().all(|&b| b == 70)).expect("the types run");
    bytes[run..run + cells].fill(9);
    std::fs::write(&quad, &bytes).expect("written");
    refused(
        "VTK_QUAD with 25 points",
        || galerkin::spectral::vtu::read(&quad).map(|_| ()),
        &["quad25.vtu", "element 0", "VTK_QUAD", "has 4 points, not 25"],
    );

    // Two tetrahedra of material 0; the second's λ is NaN.
    let tet = |nan: bool| {
        format!(
            r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="5" NumberOfCells="2">
      <Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">0 0 0  1 0 0  0 1 0  0 0 1  1 1 1</DataArray></Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3  1 2 3 4</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4 8</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10 10</DataArray>
      </Cells>
      <CellData>
        <DataArray type="Float64" Name="coefficients" NumberOfComponents="40" format="ascii">{}</DataArray>
        <DataArray type="Float64" Name="lambda" format="ascii">2 {}</DataArray>
        <DataArray type="Float64" Name="mu" format="ascii">1 1</DataArray>
        <DataArray type="Int32" Name="material" format="ascii">0 0</DataArray>
      </CellData>
    </Piece>
  </UnstructuredGrid>
</VTKFile>"#,
            vec!["0"; 80].join(" "),
            if nan { "nan" } else { "2" }
        )
    };
    let lame = scratch.path().join("lame.vtu");
    std::fs::write(&lame, tet(false)).expect("written");
    galerkin::spacetime::vtu::read(&lame).expect("the valid pair");
    std::fs::write(&lame, tet(true)).expect("written");
    refused(
        "NaN λ",
        || galerkin::spacetime::vtu::read(&lame).map(|_| ()),
        &["lame.vtu", "element 1", "finite"],
    );

    // A negative exitance (and albedo ≥ 1) in an OBJ radiosity scene.
    use common::obj_box::{box_obj, write_scene, SCENE};
    let dir = scratch.path().join("obj");
    let negative =
        SCENE.replace("window_exitance = [10.0, 10.0, 10.0]", "window_exitance = [10.0, -1.0, 10.0]");
    let path = write_scene(&dir, &negative, &box_obj(1.5));
    refused(
        "negative exitance",
        || galerkin::radiosity::obj::ObjScene::load(&path).map(|_| ()),
        &["scene.toml:", "window_exitance", "channel 1 (green)"],
    );
    let bright = SCENE.replace("floor = [0.4, 0.3, 0.2]", "floor = [0.4, 1.3, 0.2]");
    let path = write_scene(&dir, &bright, &box_obj(1.5));
    refused(
        "albedo 1.3",
        || galerkin::radiosity::obj::ObjScene::load(&path).map(|_| ()),
        &["scene.toml", "floor", "[0, 1)"],
    );

    // A camera with no view.
    let camera = galerkin::render::Camera { eye: [0.0, 0.0, 5.0], ..Default::default() };
    let zero = galerkin::render::Camera { up: [0.0; 3], ..Default::default() };
    assert!(galerkin::render::Camera::default().check().is_ok());
    refused("up along the line of sight", || camera.check(), &["up vector", "line of sight"]);
    refused("zero up", || zero.check(), &["up vector is zero"]);
}

/// Options that do not apply to the input chosen are usage errors (exit 2), not ignored.
#[test]
fn options_that_do_not_apply_are_refused() {
    let vtu = repo("tests/data/vtk/quad_ascii.vtu");
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let png = scratch.path().join("x.png");
    cli_refused(
        &["spectral", "render", text(&vtu), "--order", "3", "--out", text(&png)],
        2,
        &["--order", "generated"],
    );
    cli_refused(
        &["spectral", "render", text(&vtu), "--geometry-order", "2", "--out", text(&png)],
        2,
        &["--geometry-order"],
    );
    cli_refused(&["spectral", "gen", "--out", text(&scratch.path().join("x.txt"))], 2, &["x.txt", ".vtu"]);
    // Combinations and values the parser can judge are usage errors too, not errors of the work.
    let small = repo("scenes/radiosity/two_rooms_small.toml");
    cli_refused(
        &["radiosity", "render", text(&small), "--view", "--lights", "sky"],
        2,
        &["--lights", "viewer"],
    );
    cli_refused(
        &["radiosity", "render", text(&small), "--exposure", "-1", "--out", text(&png)],
        2,
        &["--exposure", "positive"],
    );
    cli_refused(&["spacetime", "view", "--expr", "U"], 2, &["--expr", "viewer"]);
    cli_refused(&["fluid", "bench-reduced", "--sizes", "1,2"], 2, &["--sizes", "four numbers"]);
    cli_refused(
        &["spectral", "render", "--geometry-order", "13", "--out", text(&png)],
        2,
        &["--geometry-order", "13", "orders run from 1 to 12"],
    );
    cli_refused(
        &["spacetime", "render", "--generate", "bar1d", "--elements", "500", "--out", text(&png)],
        2,
        &["--elements", "bar1d"],
    );
    assert!(!png.exists(), "a picture was written");
}

/// OBJ errors name the file and the line; a vertex at 1e308 is named as such, not as the
/// degenerate triangle it makes.
#[test]
fn obj_errors_name_the_line() {
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let obj = common::obj_box::box_obj(1.0);
    for (what, find, replace, words) in [
        (
            "a face index out of range",
            "f 1 2 3\n",
            "f 1 2 99\n",
            vec!["line", "face vertex 99 does not exist"],
        ),
        (
            "a coordinate that is no number",
            "v 0 0 0\n",
            "v 0 zero 0\n",
            vec!["line 2", "\"zero\" is not a number"],
        ),
        ("a vertex at 1e308", "v 0 0 0\n", "v 0 1e308 0\n", vec!["line 2", "past the limit"]),
    ] {
        let path = scratch.path().join("frame_0.obj");
        std::fs::write(&path, obj.replacen(find, replace, 1)).expect("written");
        let mut w = words.clone();
        w.push("frame_0.obj");
        refused(
            what,
            || {
                galerkin::mesh::animation::SurfaceAnimation::read_sequence(std::slice::from_ref(&path))
                    .map(|_| ())
            },
            &w,
        );
    }
}

/// A radiosity model's visibility file: without its face count, or with a NaN inside a tensor,
/// refused at load naming the file and the key or tensor and entry.
#[test]
fn radiosity_visibility_files_are_checked_at_load() {
    use galerkin::radiosity::reduced::ReducedRadiosity;
    let scratch = tempfile::Builder::new().prefix("galerkin-values-").tempdir().expect("scratch");
    let model = scratch.path().join("model");
    let scene = repo("scenes/radiosity/two_rooms_small.toml");
    made(&["radiosity", "train", text(&scene), "--samples", "6", "--out", text(&model)]);
    ReducedRadiosity::load(&model).expect("the valid model");
    let path = model.join("visibility.safetensors");
    let bytes = std::fs::read(&path).expect("visibility");
    // safetensors: an 8-byte header length, the JSON header, then the tensors' bytes.
    let n = u64::from_le_bytes(bytes[..8].try_into().expect("8 bytes")) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + n]).expect("json header");
    let header_text = std::str::from_utf8(&bytes[8..8 + n]).expect("utf-8");
    let faces = header_text.find("\"faces\"").expect("a face count");
    let mut no_faces = bytes.clone();
    no_faces[8 + faces + 2] = b'x'; // "fxces": same length, the key gone.
    std::fs::write(&path, &no_faces).expect("written");
    refused(
        "no face count",
        || ReducedRadiosity::load(&model).map(|_| ()),
        &["visibility.safetensors", "\"faces\""],
    );
    let start = header["emission"]["data_offsets"][0].as_u64().expect("emission offsets") as usize;
    let mut nan = bytes.clone();
    let at = 8 + n + start + 8; // emission entry 1
    nan[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    std::fs::write(&path, &nan).expect("written");
    refused(
        "a NaN emission",
        || ReducedRadiosity::load(&model).map(|_| ()),
        &["visibility.safetensors", "emission: entry 1", "not finite"],
    );
}
