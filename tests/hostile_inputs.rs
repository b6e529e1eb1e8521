//! The hostile-input table (issue 24): every format the command line reads, starting from a
//! valid file, in the variants a careful tester tries — empty, truncated at three offsets, a
//! directory in the file's place, a coordinate or value made NaN, a version we do not read,
//! an index out of range. Each must be refused with an error that names the file, within
//! seconds, and without the process's peak memory growing past a bound (read from
//! /proc/self/status; the table runs as the only test of its binary, so nothing else moves it).
//! Counts set huge are in `hostile_counts.rs`; fuzzing (`make fuzz`) covers what a table cannot.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// A format: a valid file's bytes, its file name, how the command line reads it, and edits
/// (find → replace, applied once) that must each make it invalid.
struct Format {
    name: &'static str,
    file: &'static str,
    valid: Vec<u8>,
    read: fn(&Path) -> Result<(), String>,
    edits: Vec<(&'static str, &'static str, &'static str)>,
    /// Valid files read with it, written beside it in every case (name, bytes).
    beside: Vec<(&'static str, Vec<u8>)>,
}

/// A closed unit cube, one object, consistently oriented.
const CUBE_OBJ: &str = "o cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 3 4 8\nf 3 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";

/// The process's peak resident memory so far, in MiB (VmHWM).
fn peak_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status");
    let kb: f64 = status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("VmHWM");
    kb / 1024.0
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn bytes(path: &str) -> Vec<u8> {
    std::fs::read(repo(path)).expect("a file of the repository")
}

/// Runs the `galerkin` binary (to make valid files the way a user does).
fn galerkin(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("galerkin runs");
    assert!(out.status.success(), "galerkin {args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn formats(scratch: &Path) -> Vec<Format> {
    // A spacetime mesh and a fluid run with its reduced model, written by the engine itself.
    let gst = scratch.join("valid.gst");
    galerkin(&[
        "spacetime",
        "gen",
        "--generate",
        "pulses",
        "--elements",
        "300",
        "--out",
        gst.to_str().expect("utf-8"),
    ]);
    let sim = scratch.join("sim");
    let tunnel = repo("scenes/fluid/tunnel_small.toml");
    galerkin(&[
        "fluid",
        "simulate",
        tunnel.to_str().expect("utf-8"),
        "--frames",
        "2",
        "--out",
        sim.to_str().expect("utf-8"),
    ]);
    let model = scratch.join("model.safetensors");
    galerkin(&["fluid", "train", sim.to_str().expect("utf-8"), "--out", model.to_str().expect("utf-8")]);
    let msh = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";
    vec![
        Format {
            name: "VTU (ascii Lagrange hexahedra, VTK 9)",
            file: "hex.vtu",
            valid: bytes("tests/data/vtk/hex_ascii.vtu"),
            read: |p| galerkin::spectral::vtu::read(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![
                ("NaN in the field", "0.5 0.5035231481481481", "nan 0.5035231481481481"),
                ("another version", "version=\"2.3\"", "version=\"7.0\""),
                (
                    "a cell type of none",
                    "type=\"UInt8\" Name=\"types\" format=\"ascii\"",
                    "type=\"UInt8\" Name=\"types\" format=\"nonsense\"",
                ),
            ],
            beside: vec![],
        },
        Format {
            name: "VTU (appended zlib, VTK's default)",
            file: "zlib.vtu",
            valid: bytes("tests/data/vtk/hex_appended_zlib_u32.vtu"),
            read: |p| galerkin::spectral::vtu::read(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![("an unknown compressor", "vtkZLibDataCompressor", "vtkNoSuchCompressor")],
            beside: vec![],
        },
        Format {
            name: "MFEM mesh",
            file: "quad.mesh",
            valid: bytes("tests/data/mfem/quad_h1_p4.mesh"),
            // As `galerkin spectral render MESH --field GF` reads it: with a valid GridFunction.
            read: |p| {
                let gf = repo("tests/data/mfem/quad_h1_p4.gf");
                galerkin::spectral::load(p, &[gf]).map(|_| ()).map_err(|e| e.to_string())
            },
            edits: vec![
                ("another version", "MFEM mesh v1.0", "MFEM mesh v9.0"),
                ("a vertex out of range", "1 3 0 1 5 4\n", "1 3 0 1 5 99\n"),
            ],
            beside: vec![],
        },
        Format {
            name: "MFEM GridFunction",
            file: "quad.gf",
            valid: bytes("tests/data/mfem/quad_h1_p4.gf"),
            // With its valid mesh.
            read: |p| {
                let mesh = repo("tests/data/mfem/quad_h1_p4.mesh");
                galerkin::spectral::load(&mesh, &[p.to_path_buf()]).map(|_| ()).map_err(|e| e.to_string())
            },
            edits: vec![
                ("an unknown collection", "H1_2D_P4", "H7_9D_P4"),
                ("NaN among the values", "0.60551628181174066", "nan"),
            ],
            beside: vec![],
        },
        Format {
            name: "Gmsh MSH 4.1",
            file: "tet.msh",
            valid: msh.as_bytes().to_vec(),
            read: |p| galerkin::mesh::gmsh::read_msh(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![
                ("another version", "4.1 0 8", "2.2 0 8"),
                ("NaN coordinate", "0 0 1\n$EndNodes", "0 0 nan\n$EndNodes"),
                ("a node out of range", "1 1 2 3 4\n", "1 1 2 3 9\n"),
                ("a degenerate tetrahedron", "0 0 1\n$EndNodes", "0 0 0\n$EndNodes"),
            ],
            beside: vec![],
        },
        Format {
            name: "OBJ surface (a frame of an animated boundary)",
            file: "cube.obj",
            valid: CUBE_OBJ.as_bytes().to_vec(),
            read: |p| {
                galerkin::mesh::animation::SurfaceAnimation::read_sequence(&[p.to_path_buf()])
                    .map(|_| ())
                    .map_err(|e| e.to_string())
            },
            edits: vec![
                ("NaN vertex", "v 0 0 0", "v nan 0 0"),
                ("a face index out of range", "f 1 3 2", "f 1 3 99"),
                ("an open surface (a face removed)", "f 1 3 2\n", "\n"),
            ],
            beside: vec![],
        },
        Format {
            name: "radiosity scene",
            file: "rooms.toml",
            valid: bytes("scenes/radiosity/two_rooms_small.toml"),
            read: |p| galerkin::radiosity::scene::SceneSpec::load(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![
                ("NaN size", "living = [6.0,", "living = [nan,"),
                ("an unknown key", "[lights]", "[lights]\nbrightness = 3"),
            ],
            beside: vec![],
        },
        Format {
            name: "fluid scene",
            file: "tunnel.toml",
            valid: bytes("scenes/fluid/tunnel_small.toml"),
            read: |p| galerkin::fluid::scene::FluidScene::load(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![
                ("NaN cell", "cell = 0.1", "cell = nan"),
                ("a negative cell", "cell = 0.1", "cell = -0.1"),
            ],
            beside: vec![],
        },
        Format {
            name: "spacetime .gst",
            file: "pulses.gst",
            valid: std::fs::read(&gst).expect("the .gst"),
            read: |p| galerkin::spacetime::gst::open(p).map(|_| ()).map_err(|e| e.to_string()),
            edits: vec![],
            beside: vec![],
        },
        Format {
            name: "reduced fluid model",
            file: "model.safetensors",
            valid: std::fs::read(&model).expect("the model"),
            read: |p| {
                galerkin::fluid::reduced::ReducedFluidModel::load(p).map(|_| ()).map_err(|e| e.to_string())
            },
            edits: vec![("another format", "galerkin", "galerkon")],
            beside: vec![],
        },
        Format {
            name: "fluid snapshot header (snapshots.json, read with its directory)",
            file: "snapshots.json",
            valid: std::fs::read(sim.join("snapshots.json")).expect("the header"),
            read: |p| {
                let dir = p.parent().expect("a directory");
                galerkin::fluid::snapshots::SnapshotReader::open(dir).map(|_| ()).map_err(|e| e.to_string())
            },
            edits: vec![("more frames than written", "\"frames\": ", "\"frames\": 9000")],
            beside: ["mesh.json", "u.f64", "p.f64", "f.f64", "g.f64", "h.f64"]
                .map(|f| (f, std::fs::read(sim.join(f)).expect("the run's files")))
                .to_vec(),
        },
    ]
}

#[test]
fn every_format_refuses_hostile_variants_naming_the_file_in_bounded_time_and_memory() {
    let scratch = tempfile::Builder::new().prefix("galerkin-hostile-").tempdir().expect("scratch");
    let formats = formats(scratch.path());
    let start_peak = peak_mib();
    let mut cases = 0;
    for (k, format) in formats.iter().enumerate() {
        let case_dir = scratch.path().join(format!("case{k}"));
        let check = |what: &str, setup: &dyn Fn(&Path)| {
            let dir = case_dir.join(what.replace(|c: char| !c.is_ascii_alphanumeric(), "_"));
            std::fs::create_dir_all(&dir).expect("case dir");
            for (name, bytes) in &format.beside {
                std::fs::write(dir.join(name), bytes).expect("written");
            }
            let path = dir.join(format.file);
            setup(&path);
            let start = Instant::now();
            let result = (format.read)(&path);
            let took = start.elapsed();
            let e = match result {
                Ok(()) => panic!("{}: {what}: accepted", format.name),
                Err(e) => e,
            };
            let named = e.contains(format.file) || e.contains(&dir.display().to_string());
            assert!(named, "{}: {what}: the error does not name the file: {e}", format.name);
            assert!(took < Duration::from_secs(5), "{}: {what}: took {took:?}", format.name);
            assert!(e.len() < 2000, "{}: {what}: a message of {} bytes", format.name, e.len());
        };
        // The valid file itself loads (so each variant fails for what it changed).
        let valid_dir = case_dir.join("valid");
        std::fs::create_dir_all(&valid_dir).expect("valid dir");
        for (name, bytes) in &format.beside {
            std::fs::write(valid_dir.join(name), bytes).expect("written");
        }
        let valid_path = valid_dir.join(format.file);
        std::fs::write(&valid_path, &format.valid).expect("written");
        if let Err(e) = (format.read)(&valid_path) {
            panic!("{}: the valid file is refused: {e}", format.name);
        }
        let len = format.valid.len();
        check("empty", &|p| std::fs::write(p, b"").expect("written"));
        // (Not the last bytes: a text format without an end marker cut inside its last number
        // is a valid file with a shorter number.)
        for cut in [len / 3, len / 2, 2 * len / 3] {
            check(&format!("truncated at {cut} of {len}"), &|p| {
                std::fs::write(p, &format.valid[..cut]).expect("written")
            });
        }
        check("a directory", &|p| std::fs::create_dir_all(p).expect("a directory"));
        for (what, find, replace) in &format.edits {
            let text = String::from_utf8_lossy(&format.valid);
            assert!(text.contains(find), "{}: {what}: the valid file has no {find:?}", format.name);
            let edited = text.replacen(find, replace, 1);
            check(what, &|p| std::fs::write(p, edited.as_bytes()).expect("written"));
        }
        cases += 5 + format.edits.len();
    }
    let grown = peak_mib() - start_peak;
    eprintln!(
        "{cases} hostile variants of {} formats refused; peak memory grew {grown:.1} MiB",
        formats.len()
    );
    // The largest valid file here is a few hundred kB: 256 MiB is far above what reading any of
    // them needs, far below what an unchecked count or an unbounded inflation takes.
    assert!(grown < 256.0, "peak memory grew {grown:.1} MiB");
}
