//! The command line's grammar, `galerkin <capability> <verb> [args]`: every capability lists
//! its verbs (and prints them when given no verb), bad values are usage errors (exit 2), image outputs are checked
//! before any work, and a file of the wrong kind is named as such.

use std::process::{Command, Output};

fn galerkin(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_galerkin")).args(args).output().expect("ran galerkin")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).to_string()
}

#[test]
fn every_capability_lists_its_verbs() {
    let cases: [(&str, &[&str]); 5] = [
        ("spectral", &["render", "view", "gen", "bench"]),
        ("spacetime", &["render", "view", "gen", "convert", "bench"]),
        ("radiosity", &["render", "view", "train", "compare", "bench"]),
        ("fluid", &["simulate", "render", "view", "export", "train", "reduced", "bench"]),
        ("bench", &["gpu", "reduce", "all"]),
    ];
    for (capability, verbs) in cases {
        let out = galerkin(&[capability, "--help"]);
        assert!(out.status.success(), "{capability} --help: {}", stderr(&out));
        let help = String::from_utf8_lossy(&out.stdout);
        let listed: Vec<&str> =
            help.lines().filter_map(|l| l.strip_prefix("  ")?.split_whitespace().next()).collect();
        for verb in verbs {
            assert!(listed.contains(verb), "`galerkin {capability} --help` does not list {verb}:\n{help}");
        }
        assert!(stderr(&out).is_empty(), "a deprecation note for a current spelling: {}", stderr(&out));
    }
}

#[test]
fn a_capability_without_its_verb_prints_its_help_and_writes_nothing() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    for (capability, verb) in [
        ("spectral", "render"),
        ("spacetime", "convert"),
        ("radiosity", "train"),
        ("fluid", "simulate"),
        ("bench", "gpu"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
            .arg(capability)
            .current_dir(dir.path())
            .output()
            .expect("ran");
        let help = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "galerkin {capability}: {}", stderr(&out));
        assert!(help.contains(&format!("galerkin {capability}")) && help.contains(verb), "{help}");
        assert!(!help.contains('\x1b'), "escape codes in redirected help: {help:?}");
    }
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin")).current_dir(dir.path()).output().expect("ran");
    assert_eq!(out.status.code(), Some(0), "bare galerkin: {}", stderr(&out));
    assert!(String::from_utf8_lossy(&out.stdout).contains("spectral"));
    assert_eq!(std::fs::read_dir(dir.path()).expect("dir").count(), 0, "a bare capability wrote something");
}

#[test]
fn bad_enumerated_values_and_old_spellings_are_usage_errors() {
    let cases: [(&[&str], &[&str]); 5] = [
        (&["spectral", "render", "--generate", "foo"], &["--generate", "foo", "annulus"]),
        (&["spectral", "gen", "--nodes", "lobatto"], &["--nodes", "lobatto", "gll"]),
        (&["spacetime", "render", "--generate", "tornado"], &["--generate", "tornado", "bar1d"]),
        (&["spacetime", "gen", "--generate", "bar1d"], &["--generate", "bar1d", "pulses"]),
        (&["spectral-gen", "--generate", "grid"], &["spectral-gen"]),
    ];
    for (args, words) in cases {
        let out = galerkin(args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "galerkin {args:?}: {err}");
        for w in words {
            assert!(err.contains(w), "galerkin {args:?}: {err:?} does not name {w:?}");
        }
    }
}

#[test]
fn an_image_output_of_unknown_format_is_refused_before_any_work() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let cases: [&[&str]; 4] = [
        &["spectral", "render", "--generate", "coil", "--out"],
        &["spacetime", "render", "--elements", "100000000", "--out"],
        &["radiosity", "render", "scenes/radiosity/two_rooms.toml", "--out"],
        &["fluid", "render", "/nonexistent/run", "--out"],
    ];
    for args in cases {
        let target = dir.path().join("picture.txt");
        let mut all = args.to_vec();
        let t = target.to_string_lossy().to_string();
        all.push(&t);
        let start = std::time::Instant::now();
        let out = galerkin(&all);
        let err = stderr(&out);
        // Exit 2: an argument error, from the parser — so before anything was loaded or drawn.
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(".png or .exr") && err.contains("picture.txt"), "{args:?}: {err}");
        assert!(!target.exists(), "{args:?} wrote {}", target.display());
        assert!(start.elapsed().as_secs() < 20, "{args:?} took {:?}", start.elapsed());
    }
}

#[test]
fn a_file_of_the_wrong_kind_is_named_as_such() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let obj = dir.path().join("room.obj");
    std::fs::write(&obj, "o floor\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("obj");
    let out = galerkin(&["radiosity", "render", &obj.to_string_lossy(), "--out", "unused.png"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("room.obj") && err.contains("Wavefront OBJ") && err.contains("base ="), "{err}");
    assert!(!err.contains("key with no value"), "parsed as TOML: {err}");
    // A VTK file passed where a scene belongs.
    let vtu = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/vtk/quad_default.vtu");
    let out = galerkin(&["fluid", "simulate", vtu, "--out", &dir.path().join("run").to_string_lossy()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("quad_default.vtu") && err.contains("XML (VTK)"), "{err}");
    assert!(!dir.path().join("run").exists(), "a run directory was made");
}

#[test]
fn a_scene_without_openings_warns_that_it_is_dark() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    // A closed box (two triangles per side), no window or skylight objects, no [lights].
    let corners = ["0 0 0", "1 0 0", "1 1 0", "0 1 0", "0 0 1", "1 0 1", "1 1 1", "0 1 1"];
    let mut text = String::from("o box\n");
    for c in corners {
        text += &format!("v {c}\n");
    }
    for f in [
        [1, 3, 2],
        [1, 4, 3],
        [5, 6, 7],
        [5, 7, 8],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 4, 8],
        [3, 8, 7],
        [4, 1, 5],
        [4, 5, 8],
    ] {
        text += &format!("f {} {} {}\n", f[0], f[1], f[2]);
    }
    std::fs::write(dir.path().join("box.obj"), text).expect("obj");
    let scene = dir.path().join("box.toml");
    std::fs::write(&scene, "base = \"box.obj\"\n[materials]\ndefault = [0.5, 0.5, 0.5]\n").expect("scene");
    let png = dir.path().join("box.png");
    let out = galerkin(&[
        "radiosity",
        "render",
        &scene.to_string_lossy(),
        "--size",
        "32x24",
        "--out",
        &png.to_string_lossy(),
    ]);
    let err = stderr(&out);
    // The lights' keys are optional; the picture is made, and the user told why it is black.
    assert!(out.status.success(), "{err}");
    assert!(err.contains("no window or skylight") && err.contains("[openings]"), "{err}");
    assert!(png.exists());
}

#[test]
fn a_log_scale_over_a_range_reaching_zero_and_a_directory_as_output_are_refused_up_front() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    // The generated annulus's field takes negative values: a log scale would draw nothing.
    let png = dir.path().join("log.png");
    let out = galerkin(&["spectral", "render", "--log", "--size", "32x24", "--out", &png.to_string_lossy()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("--log") && err.contains("--range"), "{err}");
    assert!(!png.exists());
    // An output that is a directory: an argument error before any work.
    let folder = dir.path().join("folder.png");
    std::fs::create_dir(&folder).expect("a directory named like an image");
    let out = galerkin(&["spectral", "render", "--out", &folder.to_string_lossy()]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("is a directory"), "{err}");
}

/// Long work in a log (stderr not a terminal): progress as plain lines — what, how far,
/// elapsed, the estimate left — and no escape codes anywhere, logs included.
#[test]
fn redirected_training_output_has_progress_lines_and_no_escape_codes() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/radiosity/two_rooms_small.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["radiosity", "train", &scene.to_string_lossy(), "--samples", "6", "--out"])
        .arg(dir.path().join("model"))
        .env("GALERKIN_LOG", "galerkin=info")
        .output()
        .expect("ran");
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(!err.contains('\u{1b}'), "escape codes in a log: {err:?}");
    let progress: Vec<&str> = err.lines().filter(|l| l.starts_with("full radiosity of samples: ")).collect();
    assert!(!progress.is_empty(), "no progress line for the full solves: {err}");
    assert!(
        progress.iter().any(|l| l.contains("6/6 (100 %)") && l.contains("elapsed") && l.contains("left")),
        "{progress:?}"
    );
    assert!(err.contains("radiosity train: "), "no stage lines: {err}");
}

/// `--volume`'s bad inputs are refused before any picture is written, each naming what is
/// wrong: a quadrilateral mesh, an inverted or empty opacity ramp, a transfer file's bad line,
/// and the ramp flags without `--volume` (a usage error).
#[test]
fn bad_volume_views_and_transfer_functions_are_refused_by_name() {
    let dir = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/vtk");
    let quads = data.join("quad_default.vtu");
    let tets = data.join("tet_cube_o3.vtu");
    let out_png = dir.path().join("v.png");
    let bad_file = dir.path().join("tf.txt");
    std::fs::write(&bad_file, "0 0\n1 one\n").expect("written");
    let (q, t, o, b) = (quads.to_str(), tets.to_str(), out_png.to_str(), bad_file.to_str());
    let (Some(q), Some(t), Some(o), Some(b)) = (q, t, o, b) else { panic!("non-UTF-8 paths") };
    for (args, what) in [
        (vec!["spectral", "render", q, "--volume", "--out", o], "hexahedral and tetrahedral meshes"),
        (vec!["spectral", "render", t, "--volume", "--opacity", "1:0,0:1", "--out", o], "inverted"),
        (vec!["spectral", "render", t, "--volume", "--opacity", "0:0,1:0", "--out", o], "empty"),
        (vec!["spectral", "render", t, "--volume", "--transfer", b, "--out", o], "tf.txt:2"),
    ] {
        let out = galerkin(&args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr(&out).contains(what), "{args:?}: {}", stderr(&out));
        assert!(!out_png.exists(), "{args:?} wrote a picture");
    }
    let out = galerkin(&["spectral", "render", t, "--opacity", "0:0,1:1", "--out", o]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}
