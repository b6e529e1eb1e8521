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
