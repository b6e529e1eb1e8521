//! `radiosity compare`'s measures (seed 000 §9): the error over the receiving surfaces (the
//! headline), over all faces (emitters included) and per room, each checked against a plain
//! recomputation from the full and the reduced radiosity of the same frames; the face groups
//! partition the receiving surfaces; kept full frames give the same errors on a second run.

use std::path::Path;

use galerkin::radiosity::any_scene::AnyScene;
use galerkin::radiosity::compare::{compare, sequence, CompareOptions, FaceGroups};
use galerkin::radiosity::mesh::FaceKind;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, TrainOptions};

const SMALL: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml");

/// Plain area-weighted relative error over the faces `keep` accepts.
fn plain_error(b: &[[f64; 3]], full: &[[f64; 3]], areas: &[f64], keep: &dyn Fn(usize) -> bool) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for i in (0..b.len()).filter(|&i| keep(i)) {
        for c in 0..3 {
            num += areas[i] * (b[i][c] - full[i][c]) * (b[i][c] - full[i][c]);
            den += areas[i] * full[i][c] * full[i][c];
        }
    }
    (num / den).sqrt()
}

#[test]
fn compare_measures_the_receiving_surfaces_all_faces_and_each_room() {
    let scene = AnyScene::load(Path::new(SMALL), None).expect("scene");
    let space = scene.space();
    // A deliberately small model (6 samples, capped bases): errors well above rounding.
    let params = sample_parameters(&space.ranges(), &space.defaults(), 6, 5);
    let options =
        TrainOptions { samples: 6, energy: 0.99, cap: 4, radiosity_cap: 8, ..TrainOptions::default() };
    let configurations = solve_configurations(space, &params, &options, &|_| {}).expect("solved");
    let (model, _) = train(space, &configurations, &options, &|_, _, _| {}).expect("trained");

    let dir = tempfile::Builder::new().prefix("galerkin-compare-").tempdir().expect("scratch");
    let kept = dir.path().join("full");
    let compare_options = CompareOptions {
        frames: vec![3, 2],
        full_frames: Some(kept.clone()),
        timed_full: 1,
        out: dir.path().join("out"),
        full_form_factors: Default::default(),
        random: 3,
        random_seed: 11,
    };
    let report = compare(&scene, Path::new(SMALL), &model, &compare_options, &mut |_| {}).expect("compared");

    // The groups: receiving surfaces = every face that is not an opening; the rooms split them.
    let mesh0 = space.mesh(&sequence(&space.ranges(), 0, 0, 3)).expect("mesh");
    let groups = FaceGroups::of(&scene, &mesh0);
    assert_eq!(groups.names, ["receiving", "living room", "door frame", "bedroom"]);
    let receiving: Vec<usize> = (0..mesh0.len()).filter(|&i| mesh0.kind[i] == FaceKind::Surface).collect();
    assert!(receiving.len() < mesh0.len(), "the scene has openings");
    assert_eq!(groups.faces[0], receiving);
    let mut rooms: Vec<usize> = groups.faces[1..].iter().flatten().copied().collect();
    rooms.sort_unstable();
    assert_eq!(rooms, receiving, "the rooms partition the receiving surfaces");
    assert!(
        groups.faces[1..].iter().all(|f| !f.is_empty()),
        "{:?}",
        groups.faces.iter().map(Vec::len).collect::<Vec<_>>()
    );
    assert_eq!(report.groups, groups);

    // Every frame's errors against a plain recomputation of the same frame.
    for (which, s) in report.sequences.iter().enumerate() {
        let frames = compare_options.frames[which];
        assert_eq!(s.errors.len(), frames);
        for (f, e) in s.errors.iter().enumerate() {
            let p = sequence(&space.ranges(), which, f, frames);
            let mesh = space.mesh(&p).expect("mesh");
            let full = galerkin::radiosity::full_radiosity_of(mesh.clone(), space.lights()).expect("full");
            let (b, _) = model.evaluate(&mesh).expect("reduced");
            let areas = &full.geometry.areas;
            let all = plain_error(&b, &full.radiosity, areas, &|_| true);
            let recv = plain_error(&b, &full.radiosity, areas, &|i| mesh.kind[i] == FaceKind::Surface);
            // 1e-12 relative: the same sums in another order.
            assert!((e.all - all).abs() <= 1e-12 * all, "seq {which} frame {f}: all {} vs {all}", e.all);
            assert!(
                (e.groups[0] - recv).abs() <= 1e-12 * recv,
                "seq {which} frame {f}: {} vs {recv}",
                e.groups[0]
            );
            for (k, faces) in groups.faces.iter().enumerate() {
                let plain = plain_error(&b, &full.radiosity, areas, &|i| faces.contains(&i));
                assert!((e.groups[k] - plain).abs() <= 1e-12 * plain, "group {k}");
            }
            // The best fit: the full radiosity projected on B_b and lifted, written out plainly.
            let basis = model.model().basis("b").expect("B_b").matrix();
            let (rows, m) = (basis.shape()[0], basis.shape()[1]);
            let n = rows / 3;
            let stacked: Vec<f64> = (0..rows).map(|r| full.radiosity[r % n][r / n]).collect();
            let coefficients: Vec<f64> =
                (0..m).map(|k| (0..rows).map(|r| basis.data()[r * m + k] * stacked[r]).sum()).collect();
            let fit: Vec<[f64; 3]> = (0..n)
                .map(|i| {
                    [0, 1, 2]
                        .map(|c| (0..m).map(|k| basis.data()[(c * n + i) * m + k] * coefficients[k]).sum())
                })
                .collect();
            let fit_error = plain_error(&fit, &full.radiosity, areas, &|i| mesh.kind[i] == FaceKind::Surface);
            assert!(
                (e.best_fit - fit_error).abs() <= 1e-10 * fit_error,
                "best fit {} vs {fit_error}",
                e.best_fit
            );
            // The emitters hold most of the norm and are reproduced exactly: the receiving
            // surfaces' error is the larger.
            assert!(e.groups[0] > e.all, "seq {which} frame {f}: receiving {} ≤ all {}", e.groups[0], e.all);
        }
    }

    // The table: a header naming the measures and one row per frame.
    let csv = std::fs::read_to_string(&report.csv).expect("csv");
    let header = csv.lines().next().expect("header");
    for column in [
        "relative_error",
        "error_receiving",
        "error_living_room",
        "error_door_frame",
        "error_bedroom",
        "best_fit_receiving",
    ] {
        assert!(header.split(',').any(|c| c == column), "{header}");
    }
    assert_eq!(csv.lines().count(), 1 + 3 + 2);
    assert!(report.plot.exists());

    // The design space's 16 corners, each against a plain recomputation; their table.
    assert_eq!(report.corners.len(), 16);
    for (p, e) in &report.corners {
        assert!(p.iter().zip(space.ranges()).all(|(v, r)| *v == r[0] || *v == r[1]), "{p:?}");
        let mesh = space.mesh(p).expect("mesh");
        let full = galerkin::radiosity::full_radiosity_of(mesh.clone(), space.lights()).expect("full");
        let (b, _) = model.evaluate(&mesh).expect("reduced");
        let recv =
            plain_error(&b, &full.radiosity, &full.geometry.areas, &|i| mesh.kind[i] == FaceKind::Surface);
        assert!((e.groups[0] - recv).abs() <= 1e-12 * recv, "corner {p:?}: {} vs {recv}", e.groups[0]);
    }
    let (_, worst, at) = report.corners_overall(Some(0)).expect("corners");
    let top = report.corners.iter().map(|(_, e)| e.groups[0]).fold(0.0f64, f64::max);
    assert_eq!(worst, top);
    assert!(report.corners.iter().any(|(p, e)| p.as_slice() == at && e.groups[0] == top));
    let corners_csv = std::fs::read_to_string(compare_options.out.join("corners.csv")).expect("corners.csv");
    assert_eq!(corners_csv.lines().count(), 1 + 16);
    // Each corner's reduced-operator margin and error estimate, in the report and the table's
    // last columns.
    assert!(corners_csv
        .lines()
        .next()
        .is_some_and(|h| h.ends_with(",estimated_error,operator_sigma_min,operator_margin")));
    for ((p, e), line) in report.corners.iter().zip(corners_csv.lines().skip(1)) {
        let mesh = space.mesh(p).expect("mesh");
        let margin = model.operator_margin(&mesh).expect("margin");
        assert!((e.estimate.margin - margin).abs() <= 1e-12 * margin.abs().max(1.0), "corner {p:?}");
        assert_eq!(e.estimate, model.evaluate_estimated(&mesh).expect("estimated").2, "corner {p:?}");
        let written: Vec<f64> = line.rsplit(',').take(3).map(|v| v.parse().expect("a number")).collect();
        assert!((written[0] - margin).abs() <= 5e-7, "{line}");
        assert!((written[2] - e.estimate.error).abs() <= 5e-7, "{line}");
        assert!(margin > 0.0, "corner {p:?}: the small model's reduced operator has a margin {margin}");
        assert!(e.estimate.error > 0.0 && e.estimate.error.is_finite(), "corner {p:?}: {:?}", e.estimate);
    }
    // The random configurations: inside the box, each against a plain recomputation, one row
    // each in random.csv.
    assert_eq!(report.random.len(), 3);
    for (p, e) in &report.random {
        assert!(p.iter().zip(space.ranges()).all(|(v, r)| *v >= r[0] && *v <= r[1]), "{p:?}");
        let mesh = space.mesh(p).expect("mesh");
        let full = galerkin::radiosity::full_radiosity_of(mesh.clone(), space.lights()).expect("full");
        let (b, _) = model.evaluate(&mesh).expect("reduced");
        let recv =
            plain_error(&b, &full.radiosity, &full.geometry.areas, &|i| mesh.kind[i] == FaceKind::Surface);
        assert!((e.groups[0] - recv).abs() <= 1e-9 * recv, "random {p:?}: {} vs {recv}", e.groups[0]);
    }
    let random_csv = std::fs::read_to_string(compare_options.out.join("random.csv")).expect("random.csv");
    assert_eq!(random_csv.lines().count(), 1 + 3);

    // A second run reads the kept full frames back: the same errors.
    let again = compare(&scene, Path::new(SMALL), &model, &compare_options, &mut |_| {}).expect("again");
    for (a, b) in report.sequences.iter().zip(&again.sequences) {
        for (x, y) in a.errors.iter().zip(&b.errors) {
            assert_eq!(x, y);
        }
    }
    assert!(std::fs::read_dir(&kept).expect("kept").count() >= 2);

    // Against the full radiosity with the exact near field: the errors are those of a plain
    // recomputation against that solve (kept frames of the centroid run are not reused).
    use galerkin::radiosity::near_field::{FormFactorMethod, DEFAULT_REACH};
    let method = FormFactorMethod::ExactNear { reach: DEFAULT_REACH };
    let exact_options = CompareOptions { full_form_factors: method, ..compare_options.clone() };
    let exact = compare(&scene, Path::new(SMALL), &model, &exact_options, &mut |_| {}).expect("exact");
    let p = sequence(&space.ranges(), 0, 0, compare_options.frames[0]);
    let mesh = space.mesh(&p).expect("mesh");
    let full = galerkin::radiosity::full_radiosity_with(mesh.clone(), space.lights(), method).expect("full");
    let (b, _) = model.evaluate(&mesh).expect("reduced");
    let recv = plain_error(&b, &full.radiosity, &full.geometry.areas, &|i| mesh.kind[i] == FaceKind::Surface);
    let e = &exact.sequences[0].errors[0];
    assert!((e.groups[0] - recv).abs() <= 1e-12 * recv, "{} vs {recv}", e.groups[0]);
    assert_ne!(e.groups[0], report.sequences[0].errors[0].groups[0]);
}

/// `radiosity render --faces FILE.csv` (and `FILE.npy`) writes the full radiosity of every
/// face in f64 that reads back to the same bits as a plain solve of the same configuration in
/// this process with the exact near field — `render`'s default, the truth training trains
/// against (the solve is deterministic) — with each face's part, kind, area and centroid.
#[test]
fn the_per_face_table_reads_back_to_the_solve() {
    let dir = tempfile::Builder::new().prefix("galerkin-faces-").tempdir().expect("scratch");
    let render_faces = |table: &Path| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_galerkin"))
            .args(["radiosity", "render", SMALL, "--params", "window_width=2.2", "--size", "32x24", "--out"])
            .arg(dir.path().join("r.png"))
            .arg("--faces")
            .arg(table)
            .output()
            .expect("ran");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    };
    let csv = dir.path().join("faces.csv");
    render_faces(&csv);
    let scene = AnyScene::load(Path::new(SMALL), None).expect("scene");
    let p = scene.parameters_from(&[("window_width".to_string(), 2.2)]).expect("params");
    let mesh = scene.space().mesh(&p).expect("mesh");
    // `render`'s full solve defaults to the exact near field (what training trains against).
    let exact = galerkin::radiosity::near_field::FormFactorMethod::ExactNear {
        reach: galerkin::radiosity::near_field::DEFAULT_REACH,
    };
    let full =
        galerkin::radiosity::full_radiosity_with(mesh.clone(), scene.space().lights(), exact).expect("full");
    // The same numbers as NumPy's array: faces × 8 f64, kind and the CSV's numbers, bit for bit.
    let npy = dir.path().join("faces.npy");
    render_faces(&npy);
    let bytes = std::fs::read(&npy).expect("npy");
    let array = npyz::NpyFile::new(&bytes[..]).expect("an NPY file");
    assert_eq!(array.shape(), [mesh.len() as u64, 8]);
    let values: Vec<f64> = array.into_vec().expect("f64 values");
    for i in 0..mesh.len() {
        let row = &values[8 * i..8 * i + 8];
        let kind = match mesh.kind[i] {
            FaceKind::Surface => 0.0,
            FaceKind::Window => 1.0,
            FaceKind::Skylight => 2.0,
        };
        assert_eq!(row[0], kind, "row {i}: kind");
        assert_eq!(row[1].to_bits(), full.geometry.areas[i].to_bits(), "row {i}: area");
        for c in 0..3 {
            assert_eq!(row[2 + c].to_bits(), full.geometry.centroids[i][c].to_bits(), "row {i}: centroid");
            assert_eq!(row[5 + c].to_bits(), full.radiosity[i][c].to_bits(), "row {i} channel {c}");
        }
    }
    let text = std::fs::read_to_string(&csv).expect("table");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some(galerkin::radiosity::face_table::HEADER));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), mesh.len());
    for (i, row) in rows.iter().enumerate() {
        let num = |k: usize| row[k].parse::<f64>().unwrap_or_else(|e| panic!("row {i} column {k}: {e}"));
        assert_eq!(row[0], i.to_string());
        assert_eq!(row[1], mesh.part_of(i));
        assert_eq!(row[2] == "surface", mesh.kind[i] == FaceKind::Surface, "row {i}: {}", row[2]);
        assert_eq!(num(3).to_bits(), full.geometry.areas[i].to_bits(), "row {i}: area");
        for c in 0..3 {
            assert_eq!(num(7 + c).to_bits(), full.radiosity[i][c].to_bits(), "row {i} channel {c}");
        }
    }
}
