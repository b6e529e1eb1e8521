//! The capabilities' benchmarks are library functions returning reports (the command line
//! prints them): run here at their smallest sizes with validation on, each must produce its
//! tables with a row per configuration and finite, positive times. (What the times are is for
//! BENCHMARKS.md, never asserted.)

mod common;

use std::path::PathBuf;

#[test]
fn the_spectral_benchmark_reports_every_order_and_size() {
    let gpu = common::gpu();
    let mut text = String::new();
    galerkin::bench::spectral::report(&gpu, true, 1, &mut |s| text.push_str(s)).expect("the benchmark ran");
    let rows: Vec<&str> =
        text.lines().filter(|l| l.starts_with("| artery") || l.starts_with("| coil")).collect();
    assert_eq!(rows.len(), 6, "orders 1, 3, 8 of the artery and the coil:\n{text}");
    for row in &rows {
        let ms: f64 = row
            .split('|')
            .nth(3)
            .and_then(|c| c.split_whitespace().next())
            .and_then(|v| v.parse().ok())
            .expect(row);
        assert!(ms.is_finite() && ms > 0.0, "{row}");
    }
    for size in ["512×384", "1024×768", "2048×1536"] {
        assert!(text.contains(&format!("| {size} |")), "no row for {size}:\n{text}");
    }
    for elements in ["840", "1666", "3332", "6664"] {
        assert!(
            text.lines().any(|l| l.starts_with(&format!("| {elements} |"))),
            "no row for {elements}:\n{text}"
        );
    }
}

#[test]
fn the_radiosity_benchmark_reports_both_paths() {
    let gpu = common::gpu();
    let scene = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/radiosity/two_rooms_small.toml"));
    let rows = galerkin::bench::radiosity::run(std::slice::from_ref(&scene), 1, Some(&gpu))
        .expect("the benchmark ran");
    assert_eq!(rows.len(), 2, "{rows:?}");
    for r in &rows {
        assert_eq!(r.faces, 496);
        assert!(r.form_factors_s > 0.0 && r.solve_s > 0.0 && r.sweeps > 0, "{r:?}");
    }
    let table = galerkin::bench::radiosity::table(&rows);
    assert_eq!(table.lines().count(), 4, "{table}");
    // The near-field comparison: some pairs integrated exactly, a finite difference between
    // the two ground truths (its size is for BENCHMARKS.md).
    let near = galerkin::bench::radiosity::near_field(&[scene], 4.0).expect("the comparison ran");
    assert_eq!(near.len(), 1);
    let r = &near[0];
    assert!(r.exact_pairs > 0 && r.exact_pairs < r.faces * r.faces, "{r:?}");
    assert!(r.receiving_difference.is_finite() && r.receiving_difference > 0.0, "{r:?}");
    assert_eq!(galerkin::bench::radiosity::near_field_table(&near, 4.0).lines().count(), 3);
}

#[test]
fn the_fluid_benchmark_reports_every_size_table_1_and_the_particles() {
    let gpu = common::gpu();
    let mut text = String::new();
    galerkin::bench::fluid::report(&gpu, true, 2, &mut |s| text.push_str(s)).expect("the benchmark ran");
    // Three cavity sizes and one bird size, each with positive stage times.
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| {
            l.starts_with("| ") && l.split('|').nth(1).is_some_and(|c| c.trim().parse::<usize>().is_ok())
        })
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 4, "{text}");
    for r in &rows {
        for col in [5, 6, 7] {
            let v: f64 = r[col].split_whitespace().next().and_then(|v| v.parse().ok()).expect("a time");
            assert!(v.is_finite() && v >= 0.0, "{r:?}");
        }
    }
    assert!(text.contains("| cavity | 88671 |") && text.contains("| eagle | 300217 |"), "{text}");
    assert!(text.contains("Particles: 10,000 in"), "{text}");
}

/// The number in column `k` of a Markdown row (units after it ignored).
fn column(row: &str, k: usize) -> f64 {
    row.split('|').nth(k).and_then(|c| c.split_whitespace().next()).and_then(|v| v.parse().ok()).expect(row)
}

#[test]
fn the_spacetime_benchmark_reports_every_size_and_pixel_count() {
    use galerkin::bench::spacetime::{report, SpacetimeBench};
    let gpu = common::gpu();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut bench = SpacetimeBench::new(true, dir.path(), None);
    bench.sizes = vec![2000, 5000];
    bench.frames = 2;
    let mut text = String::new();
    report(&gpu, &bench, &mut |_| {}, &mut |s| text.push_str(s)).expect("the benchmark ran");
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("| ") && l[2..].starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    // One row for the smaller data set; for the larger the plain row, the subdivided row and
    // four pixel counts. Rows name the elements the data sets have, near the sizes asked for.
    assert_eq!(rows.len(), 7, "{text}");
    let elements: Vec<f64> = rows.iter().map(|r| column(r, 1)).collect();
    assert!(
        (1500.0..3000.0).contains(&elements[0]) && (4000.0..7000.0).contains(&elements[1]),
        "{elements:?}"
    );
    for row in &rows {
        let ms = column(row, 6);
        assert!(ms.is_finite() && ms > 0.0, "{row}");
    }
    for size in ["320×180", "640×360", "1280×720", "1920×1080"] {
        assert!(text.contains(&format!("| {size} |")), "no row for {size}:\n{text}");
    }
    assert!(text.contains("The floor"), "{text}");
    // The data sets were generated into the folder and are reused.
    assert!(dir.path().join("pulses-5000.gst").is_file());
}

#[test]
fn the_reduced_fluid_benchmark_reports_both_exponentials_and_the_energy() {
    use galerkin::bench::fluid_reduced::{step_report, StepBench};
    let dir = tempfile::tempdir().expect("temp dir");
    let mut bench = StepBench::new(true);
    bench.scene = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/fluid/cavity_small.toml"));
    bench.sizes = (16, 8, 3, 4);
    bench.steps = 3;
    bench.energy_steps = 50;
    bench.work = dir.path().to_path_buf();
    let mut text = String::new();
    step_report(&bench, &mut |_| {}, &mut |_, _| {}, &mut |s| text.push_str(s)).expect("the benchmark ran");
    let rows: Vec<&str> =
        text.lines().filter(|l| l.starts_with("| Krylov") || l.starts_with("| Padé")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    for row in &rows {
        assert_eq!(column(row, 2), 16.0, "{row}");
        let ms = column(row, 11);
        assert!(ms.is_finite() && ms > 0.0, "{row}");
    }
    assert!(text.contains("Energy over 50 reduced steps"), "{text}");
}

/// `galerkin bench all --out FILE` on a file without the generated part's markers refuses at
/// once — naming the file and the marker, exit 1 — before an hour of benchmarks, and leaves the
/// file as it was.
#[test]
fn bench_all_refuses_an_out_file_without_markers_before_running() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("notes.md");
    std::fs::write(&file, "# My notes\n\nno markers here\n").expect("wrote");
    let start = std::time::Instant::now();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_galerkin"))
        .args(["bench", "all", "--quick", "--out"])
        .arg(&file)
        .output()
        .expect("ran galerkin");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("notes.md") && stderr.contains(galerkin::bench::report::BEGIN_MARKER),
        "{stderr}"
    );
    assert!(out.stdout.is_empty(), "a benchmark ran: {}", String::from_utf8_lossy(&out.stdout));
    assert!(start.elapsed().as_secs() < 30, "refused only after {:?}", start.elapsed());
    assert_eq!(std::fs::read_to_string(&file).expect("read"), "# My notes\n\nno markers here\n");
}
