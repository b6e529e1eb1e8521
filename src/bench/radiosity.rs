//! `galerkin radiosity bench`: the full radiosity (seed 000 §8, the ground truth and the
//! training data) stage by stage — form factors with visibility (Eq. 15) and the Jacobi solve
//! of Eq. 14 — on the CPU (f64, rayon) and on the device (f32), at a scene's default
//! parameters. Medians of `runs`.

use std::path::PathBuf;
use std::time::Instant;

use crate::gpu::Gpu;
use crate::radiosity::form_factor::{form_factors, NearField};
use crate::radiosity::gpu::GpuRadiosity;
use crate::radiosity::lighting::emission;
use crate::radiosity::solve::solve_jacobi;
use crate::radiosity::{RadiosityError, SceneSpec, JACOBI_TOLERANCE};

/// One row: a scene on one path.
#[derive(Clone, Debug)]
pub struct Row {
    /// The scene file.
    pub scene: PathBuf,
    /// Faces (the form-factor matrix has their square of pairs).
    pub faces: usize,
    /// `CPU f64` or `device f32`.
    pub path: &'static str,
    /// Runs the medians are over.
    pub runs: usize,
    /// Median seconds of the form factors.
    pub form_factors_s: f64,
    /// Median seconds of the Jacobi solve.
    pub solve_s: f64,
    /// Jacobi sweeps to the tolerance.
    pub sweeps: usize,
}

/// Measures each scene on the CPU and, when `gpu` is given, on the device (one run above
/// 2,000 faces: lavapipe takes about a minute per full-scene form-factor pass).
pub fn run(scenes: &[PathBuf], runs: usize, gpu: Option<&Gpu>) -> Result<Vec<Row>, RadiosityError> {
    let device = gpu.map(GpuRadiosity::new).transpose()?;
    let runs = runs.max(1);
    let mut rows = Vec::new();
    for scene in scenes {
        let spec = SceneSpec::load(scene)?;
        let mesh = crate::radiosity::architecture::build(&spec, &spec.defaults())?;
        let (mut ff, mut sv, mut sweeps, mut e) = (Vec::new(), Vec::new(), 0, Vec::new());
        for _ in 0..runs {
            let t = Instant::now();
            let f = form_factors(&mesh, NearField::Regularised);
            ff.push(t.elapsed().as_secs_f64());
            e = emission(&mesh, &mesh.geometry(), &spec.lights, &f);
            let t = Instant::now();
            let (_, k) = solve_jacobi(&f, &mesh.albedo, &e, JACOBI_TOLERANCE, 2000)?;
            sv.push(t.elapsed().as_secs_f64());
            sweeps = k;
        }
        let row = |path, runs, ff: &mut Vec<f64>, sv: &mut Vec<f64>, sweeps| Row {
            scene: scene.clone(),
            faces: mesh.len(),
            path,
            runs,
            form_factors_s: super::median_f64(ff),
            solve_s: super::median_f64(sv),
            sweeps,
        };
        rows.push(row("CPU f64 (rayon)", runs, &mut ff, &mut sv, sweeps));
        if let (Some(gpu), Some(device)) = (gpu, &device) {
            let (mut ff, mut sv, mut sweeps) = (Vec::new(), Vec::new(), 0);
            let device_runs = if mesh.len() > 2000 { 1 } else { runs };
            for _ in 0..device_runs {
                let t = Instant::now();
                let f = device.form_factors(gpu, &mesh, NearField::Regularised)?;
                ff.push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                let (_, k) = device.solve(gpu, &f, &mesh.albedo, &e, 1e-6, 2000)?;
                sv.push(t.elapsed().as_secs_f64());
                sweeps = k;
            }
            rows.push(row("device f32", device_runs, &mut ff, &mut sv, sweeps));
        }
    }
    Ok(rows)
}

/// The rows as a Markdown table.
pub fn table(rows: &[Row]) -> String {
    let mut out = String::from(
        "| scene | faces | pairs | path | runs | form factors (s) | solve (s) | sweeps | frame (s) |\n|---|---:|---:|---|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let name = r.scene.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        out += &format!(
            "| {name} | {} | {} | {} | {} | {:.3} | {:.3} | {} | {:.3} |\n",
            r.faces,
            r.faces * r.faces,
            r.path,
            r.runs,
            r.form_factors_s,
            r.solve_s,
            r.sweeps,
            r.form_factors_s + r.solve_s
        );
    }
    out
}

/// The near field's weight in the ground truth at one scene (issue 28): the full radiosity
/// with centroid form factors (the default, what training and `compare` use) against the
/// exact polygon form factors for near pairs.
#[derive(Clone, Debug)]
pub struct NearFieldRow {
    /// The scene file.
    pub scene: PathBuf,
    /// Faces.
    pub faces: usize,
    /// Pairs integrated exactly.
    pub exact_pairs: usize,
    /// Seconds of the centroid form factors.
    pub centroid_s: f64,
    /// Seconds of the form factors with the exact near field.
    pub exact_s: f64,
    /// `‖b_exact − b_centroid‖ / ‖b_exact‖`, area-weighted over the receiving surfaces and the
    /// three channels (the measure of `radiosity compare`).
    pub receiving_difference: f64,
    /// The largest per-face relative difference on the receiving surfaces.
    pub worst_face: f64,
}

/// Solves each scene at its default parameters with both form-factor methods (one run each,
/// CPU f64) and compares the radiosity on the receiving surfaces.
pub fn near_field(scenes: &[PathBuf], reach: f64) -> Result<Vec<NearFieldRow>, RadiosityError> {
    use crate::radiosity::near_field::form_factors_exact_near;
    let mut rows = Vec::new();
    for scene in scenes {
        let spec = SceneSpec::load(scene)?;
        let mesh = crate::radiosity::architecture::build(&spec, &spec.defaults())?;
        let g = mesh.geometry();
        let t = Instant::now();
        let centroid = form_factors(&mesh, NearField::Regularised);
        let centroid_s = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (exact, exact_pairs) = form_factors_exact_near(&mesh, reach);
        let exact_s = t.elapsed().as_secs_f64();
        let solve = |f| -> Result<Vec<[f64; 3]>, RadiosityError> {
            let e = emission(&mesh, &g, &spec.lights, f);
            Ok(solve_jacobi(f, &mesh.albedo, &e, JACOBI_TOLERANCE, 2000)?.0)
        };
        let (bc, be) = (solve(&centroid)?, solve(&exact)?);
        let (mut diff, mut norm, mut worst) = (0.0, 0.0, 0.0f64);
        for i in (0..mesh.len()).filter(|&i| !mesh.kind[i].is_opening()) {
            let d: f64 = (0..3).map(|c| (be[i][c] - bc[i][c]).powi(2)).sum();
            let b: f64 = (0..3).map(|c| be[i][c].powi(2)).sum();
            diff += g.areas[i] * d;
            norm += g.areas[i] * b;
            if b > 0.0 {
                worst = worst.max((d / b).sqrt());
            }
        }
        rows.push(NearFieldRow {
            scene: scene.clone(),
            faces: mesh.len(),
            exact_pairs,
            centroid_s,
            exact_s,
            receiving_difference: (diff / norm.max(f64::MIN_POSITIVE)).sqrt(),
            worst_face: worst,
        });
    }
    Ok(rows)
}

/// The near-field rows as a Markdown table.
pub fn near_field_table(rows: &[NearFieldRow], reach: f64) -> String {
    let mut out = format!(
        "| scene | faces | pairs within {reach} face diameters, integrated exactly | centroid form factors (s) | with the exact near field (s) | radiosity difference, receiving surfaces | worst face |\n|---|---:|---:|---:|---:|---:|---:|\n"
    );
    for r in rows {
        let name = r.scene.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        out += &format!(
            "| {name} | {} | {} | {:.3} | {:.3} | {:.2} % | {:.1} % |\n",
            r.faces,
            r.exact_pairs,
            r.centroid_s,
            r.exact_s,
            100.0 * r.receiving_difference,
            100.0 * r.worst_face
        );
    }
    out
}
