//! A fluid run exported as a ParaView time series (src/fluid/export.rs): the collection
//! names every exported frame with its time, each frame reads back through the VTK reader
//! with the run's velocity, and the exported fluxes are those of a discretely
//! divergence-free flow (each interior face's flux twice with opposite signs).

mod common;

use galerkin::fluid::export::export_run;
use galerkin::fluid::snapshots::SnapshotReader;

#[test]
fn a_run_exports_as_a_pvd_time_series_with_its_velocity_and_divergence_free_fluxes() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let run = scratch.path().join("run");
    common::wavy::simulate(3, 3, 0.08, 20.0, [1.0, 0.2, 0.1], 6, &run);
    let reader = SnapshotReader::open(&run).expect("the run");
    let meta = reader.meta().clone();
    let pvd = scratch.path().join("out").join("wavy.pvd");
    let mut calls = 0;
    let export = export_run(&run, &pvd, 4, &mut |done, total| {
        calls += 1;
        assert!(done <= total);
    })
    .expect("exported");
    // Frames 0..=6, every 4th and the last: 0, 4, 6.
    assert_eq!((export.frames.len(), calls), (3, 3));
    let text = std::fs::read_to_string(&pvd).expect("the collection");
    let doc = roxmltree::Document::parse(&text).expect("XML");
    let sets: Vec<_> = doc.descendants().filter(|n| n.has_tag_name("DataSet")).collect();
    assert_eq!(sets.len(), 3);
    for (set, k) in sets.iter().zip([0usize, 4, 6]) {
        let t: f64 = set.attribute("timestep").expect("timestep").parse().expect("a number");
        assert!((t - k as f64 * meta.frame_time).abs() < 1e-15, "frame {k}: t = {t}");
        let file = pvd.parent().expect("dir").join(set.attribute("file").expect("file"));
        let grid = galerkin::vtk::read(&file).unwrap_or_else(|e| panic!("frame {k}: {e}"));
        assert_eq!((grid.points, grid.cells), (meta.vertices, meta.cells));
        // Points: the frame's geometry, exactly.
        let g = reader.frame("g", k).expect("g");
        assert_eq!(grid.require("Points", "Points", 3, meta.vertices).expect("points"), g.as_slice());
        // Velocity and speed: the run's u, exactly, and its length.
        let u = reader.frame("u", k).expect("u");
        let velocity = grid.require("CellData", "velocity", 3, meta.cells).expect("velocity");
        let speed = grid.require("CellData", "speed", 1, meta.cells).expect("speed");
        for c in 0..meta.cells {
            assert_eq!(&velocity[3 * c..3 * c + 3], &u[3 * c..3 * c + 3], "frame {k} cell {c}");
            let norm = u[3 * c..3 * c + 3].iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((speed[c] - norm).abs() <= 1e-15 * norm.max(1.0));
        }
        // Fluxes: summed over every cell's faces, interior faces cancel (each appears twice
        // with opposite signs) and the closed channel's walls carry no net flux.
        let flux = grid.require("CellData", "flux", 4, meta.cells).expect("flux");
        let f = reader.frame("f", k).expect("f");
        let scale: f64 = f.iter().map(|x| x.abs()).sum();
        let total: f64 = flux.iter().sum();
        assert!(total.abs() <= 1e-12 * scale.max(1.0), "frame {k}: net flux {total:e} of {scale:e}");
        // Every flux value of the run appears among the cells' faces (up to sign).
        let mut seen: Vec<f64> = flux.iter().map(|x| x.abs()).collect();
        seen.sort_by(f64::total_cmp);
        for x in f.iter().step_by(17) {
            assert!(
                seen.binary_search_by(|y| y.total_cmp(&x.abs())).is_ok(),
                "frame {k}: face flux {x} missing"
            );
        }
        // Divergence: the projection's constraint, to rounding (relative to the fluxes).
        let divergence = grid.require("CellData", "divergence", 1, meta.cells).expect("divergence");
        assert!(divergence.iter().all(|d| d.is_finite()));
    }
    assert!(export.relative_divergence < 1e-9, "relative divergence {:e}", export.relative_divergence);
    // Nothing temporary left behind.
    let leftovers: Vec<_> =
        walk(scratch.path()).into_iter().filter(|p| p.to_string_lossy().ends_with(".partial")).collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

fn walk(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).expect("dir").flatten() {
        let path = entry.path();
        if path.is_dir() {
            out.extend(walk(&path));
        } else {
            out.push(path);
        }
    }
    out
}

#[test]
fn the_cli_exports_and_refuses_a_collection_that_is_not_a_pvd() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("scratch");
    let run = scratch.path().join("run");
    common::wavy::simulate(2, 4, 0.08, 20.0, [1.0, 0.0, 0.0], 3, &run);
    let exe = env!("CARGO_BIN_EXE_galerkin");
    let out = std::process::Command::new(exe)
        .args(["fluid", "export"])
        .arg(&run)
        .arg("--out")
        .arg(scratch.path().join("r.pvd"))
        .output()
        .expect("ran");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("r.pvd") && said.contains("4 frames"), "{said}");
    assert!(scratch.path().join("r").join("r_000003.vtu").is_file());
    let bad = std::process::Command::new(exe)
        .args(["fluid", "export"])
        .arg(&run)
        .arg("--out")
        .arg(scratch.path().join("r.vtu"))
        .output()
        .expect("ran");
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("r.vtu") && err.contains(".pvd"), "{err}");
}
