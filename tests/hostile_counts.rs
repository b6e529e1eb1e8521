//! Counts that input declares are checked before anything is allocated from them (issue 24):
//! a Gmsh node or element count of 2⁴⁰, an MFEM element or vertex count of 2⁴⁰, and command
//! line counts of 2⁴⁰ (`--particles`, `--samples`, `--frames`, `--elements`) each give an
//! error naming the count — quickly, without the allocation that used to abort the process.

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

const HUGE: &str = "1099511627776"; // 2^40

/// Runs `f`, which must fail quickly with an error containing every one of `words`.
fn refused<E: std::fmt::Display>(what: &str, f: impl FnOnce() -> Result<(), E>, words: &[&str]) {
    let start = Instant::now();
    let e = match f() {
        Ok(()) => panic!("{what}: accepted"),
        Err(e) => e.to_string(),
    };
    assert!(start.elapsed() < Duration::from_secs(5), "{what}: took {:?}", start.elapsed());
    for w in words {
        assert!(e.contains(w), "{what}: {e:?} does not mention {w:?}");
    }
}

#[test]
fn gmsh_counts_are_checked_against_the_file() {
    let dir = tempfile::Builder::new().prefix("galerkin-hostile-").tempdir().expect("scratch");
    let header = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let cases = [
        ("nodes.msh", format!("{header}$Nodes\n1 {HUGE} 1 {HUGE}\n2 1 0 {HUGE}\n1\n0 0 0\n$EndNodes\n"), "node count"),
        ("blocks.msh", format!("{header}$Nodes\n{HUGE} 1 1 1\n2 1 0 1\n1\n0 0 0\n$EndNodes\n"), "block count"),
        (
            "elements.msh",
            format!("{header}$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0 0\n$EndNodes\n$Elements\n1 {HUGE} 1 {HUGE}\n2 1 2 {HUGE}\n1 1 1 1\n$EndElements\n"),
            "element count",
        ),
    ];
    for (name, text, what) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, &text).expect("write");
        refused(name, || galerkin::mesh::gmsh::read_msh(&path).map(|_| ()), &[name, what, HUGE]);
    }
}

#[test]
fn mfem_counts_are_checked_against_the_file() {
    let dir = tempfile::Builder::new().prefix("galerkin-hostile-").tempdir().expect("scratch");
    let cases = [
        ("elements.mesh", format!("MFEM mesh v1.0\ndimension\n2\nelements\n{HUGE}\n1 3 0 1 2 3\n"), "element count"),
        (
            "vertices.mesh",
            format!("MFEM mesh v1.0\ndimension\n2\nelements\n1\n1 3 0 1 2 3\nvertices\n{HUGE}\n2\n0 0\n1 0\n1 1\n0 1\n"),
            "vertex count",
        ),
        (
            "boundary.mesh",
            format!("MFEM mesh v1.0\ndimension\n2\nelements\n1\n1 3 0 1 2 3\nboundary\n{HUGE}\n1 1 0 1\n"),
            "boundary count",
        ),
    ];
    for (name, text, what) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, &text).expect("write");
        refused(name, || galerkin::spectral::mfem::read_mesh(&path).map(|_| ()), &[name, what, HUGE]);
    }
}

#[test]
fn command_line_counts_are_bounded_before_any_work() {
    let dir = tempfile::Builder::new().prefix("galerkin-hostile-").tempdir().expect("scratch");
    let gst = dir.path().join("huge.gst");
    let gst_text = gst.to_string_lossy().to_string();
    let radiosity = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");
    let fluid = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fluid/tunnel_small.toml");
    let run_dir = dir.path().join("run").to_string_lossy().to_string();
    let cases: [&[&str]; 5] = [
        &["spacetime", "gen", "--elements", HUGE, "--out", &gst_text],
        &["radiosity", "train", radiosity, "--samples", HUGE, "--out", &run_dir],
        &["fluid", "simulate", fluid, "--frames", HUGE, "--out", &run_dir],
        &["fluid", "render", "/nonexistent", "--particles", HUGE],
        &["spacetime", "render", "--elements", HUGE],
    ];
    for args in cases {
        let start = Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(HUGE) && err.contains("over the limit"), "{args:?}: {err}");
        assert!(start.elapsed() < Duration::from_secs(10), "{args:?} took {:?}", start.elapsed());
    }
    let left = std::fs::read_dir(dir.path()).expect("scratch").count();
    assert!(!gst.exists() && left == 0, "a file was left");
    assert!(!Path::new(&run_dir).exists(), "a run directory was made");
}

/// Scene files whose sizes ask for meshes past the documented limits are refused before the
/// mesh is built, naming the key: a radiosity room of 10⁶ m (it used to reach 3.7 GB before
/// failing elsewhere), a fluid stuffing spacing of 10⁻⁹ (the lattice count used to overflow),
/// a fluid mesh whose simulation would not fit the machine's memory, the fuzzer's slow scene
/// under the fuzzer's cell budget, a tunnel obstacle refined to 10⁻¹² of a cell.
#[test]
fn scene_sizes_are_bounded_before_any_mesh_is_built() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    // A shipped scene with one line edited (which must be there).
    let edited = |p: &str, find: &str, replace: &str| {
        let text = std::fs::read_to_string(root.join(p)).expect("a shipped scene");
        assert!(text.contains(find), "{p} has no {find:?}");
        text.replacen(find, replace, 1)
    };
    let huge =
        edited("radiosity/two_rooms_small.toml", "living = [6.0, 5.0, 2.7]", "living = [1e6, 5.0, 2.7]");
    refused(
        "10⁶ m room",
        || galerkin::radiosity::scene::SceneSpec::parse(&huge, Path::new("rooms.toml")).map(|_| ()),
        &["rooms.toml", "cell", "at most 50000"],
    );
    let fine = edited("fluid/cavity_small.toml", "spacing = 0.2", "spacing = 1e-9");
    refused(
        "spacing 1e-9",
        || galerkin::fluid::scene::FluidScene::parse(&fine, Path::new("cavity.toml")).map(|_| ()),
        &["cavity.toml", "lattice cells", "raise the spacing"],
    );
    // Within the lattice limit (about 4.5·10⁷ lattice cells) but a mesh of about 4.5·10⁸ cells
    // whose simulation would need terabytes: refused before the lattice is built (the fuzzer's
    // scene target found the lattice limit alone let a scene's meshing exhaust memory).
    let big = edited("fluid/cavity_small.toml", "spacing = 0.2", "spacing = 0.009");
    refused(
        "spacing 0.009",
        || galerkin::fluid::scene::FluidScene::parse(&big, Path::new("cavity.toml")).map(|_| ()),
        &["cavity.toml", "GB to simulate", "raise the spacing"],
    );
    // The scene the fuzzer's scene target timed out on (a valid 2.2·10⁶-cell bird: 10 s to mesh
    // natively, over 90 s under AddressSanitizer): within this machine's budget, but refused
    // at once under the fuzzer's budget of 20,000 cells, naming the spacing.
    let timeout = edited("fluid/bird.toml", "lo = [-1.4, -1.8, -1.3]", "lo = [-3.6, -3.0, -2.2]")
        .replacen("hi = [1.4, 1.8, 1.3]", "hi = [2.6, 3.0, 2.6]", 1)
        .replacen("spacing = 0.1025", "spacing = 0.1", 1);
    assert!(timeout.contains("spacing = 0.1\n") && timeout.contains("hi = [2.6, 3.0, 2.6]"));
    refused(
        "the fuzzer's timeout scene under its budget",
        || {
            let budget = galerkin::mesh::budget::CellBudget::cells(20_000.0);
            galerkin::fluid::scene::FluidScene::parse_within(&timeout, Path::new("bird.toml"), &budget)
                .map(|_| ())
        },
        &["bird.toml", "spacing 0.1", "past the budget of 2.000e4", "raise the spacing"],
    );
    let refined =
        edited("fluid/tunnel_small.toml", "obstacle_refinement = 0.5", "obstacle_refinement = 1e-12");
    refused(
        "obstacle_refinement 1e-12",
        || galerkin::fluid::scene::FluidScene::parse(&refined, Path::new("tunnel.toml")).map(|_| ()),
        &["tunnel.toml", "obstacle_refinement"],
    );
}
