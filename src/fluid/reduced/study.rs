//! The one-step error study of seed 000 §7.1 (Fig. 5 (d) and (e)).
//!
//! For a test run's velocity snapshots `u_t` (a run the model was not trained on) and each basis
//! size m: the energy-norm projection `r_t = argmin ‖u_t − B_u r‖_{V(g_t)}` (footnote 2:
//! `r_t = (B_uᵀV(g_t)B_u)⁻¹ B_uᵀ p_t` from the snapshot's momentum `p_t = V(g_t)u_t`, with
//! `B_uᵀV(g_t)B_u = V̂(ĝ_t)` — exact when `g_t` is in span(B_g), which the study reports), the
//! flux `f̂_t = B_fᵀ f_t`; then one **full** step from the lifted state `(B_u r_t, B_f f̂_t)`
//! gives `u_ground` and one **reduced** step from `(r_t, f̂_t)` gives `u_test = B_u û_{t+1}`;
//! the error is `E(u_ground − u_test) / E(u_ground)` with `E(u) = ½uᵀV(g_{t+1})u`. The
//! time-integrated error of a size is the mean over the frames studied (Fig. 5 (e)).
//!
//! The sizes share one trained model: PCA modes are nested, so the model of size m is the
//! leading block of the largest one ([`ReducedFluidModel::truncated`]).

use crate::fluid::snapshots::SnapshotReader;
use crate::fluid::{FluidError, FluidSolver, FluidState};
use crate::mesh::SimplexMesh;

use super::model::{MeshFingerprint, ReducedFluidModel};
use super::step::{ReducedFluid, ReducedState};

/// Most frames a study may take (a cap on a loop driven by input).
pub const MAX_STUDY_FRAMES: usize = 1_000_000;

/// One basis size's errors.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeErrors {
    /// m_u (the velocity–momentum basis).
    pub m_u: usize,
    /// m_f.
    pub m_f: usize,
    /// Frames studied (the step from each to the next).
    pub frames: Vec<usize>,
    /// One-step error per frame.
    pub errors: Vec<f64>,
    /// Median reduced step time (seconds).
    pub reduced_seconds: f64,
    /// Median full step time (seconds).
    pub full_seconds: f64,
    /// Bytes of the size's reduced tensors.
    pub tensor_bytes: usize,
}

impl SizeErrors {
    /// The time-integrated (mean) one-step error.
    pub fn mean(&self) -> f64 {
        if self.errors.is_empty() {
            return f64::NAN;
        }
        self.errors.iter().sum::<f64>() / self.errors.len() as f64
    }
}

/// A whole study.
#[derive(Clone, Debug)]
pub struct ErrorStudy {
    /// Per size, ascending.
    pub sizes: Vec<SizeErrors>,
    /// Worst relative error of the test run's geometry projected onto B_g.
    pub geometry_error: f64,
    /// The frame time.
    pub frame_time: f64,
}

impl ErrorStudy {
    /// Whether the time-integrated error falls with every larger size (Fig. 5 (e)'s claim).
    pub fn monotone(&self) -> bool {
        self.sizes.windows(2).all(|w| w[1].mean() <= w[0].mean())
    }

    /// The study as CSV: `m_u,m_f,frame,time,one_step_error`.
    pub fn csv(&self) -> String {
        let mut out = String::from("m_u,m_f,frame,time,one_step_error\n");
        for s in &self.sizes {
            for (f, e) in s.frames.iter().zip(&s.errors) {
                out += &format!("{},{},{f},{:.6},{e:.9e}\n", s.m_u, s.m_f, *f as f64 * self.frame_time);
            }
        }
        out
    }

    /// The time-integrated errors as CSV: `m_u,m_f,mean_one_step_error,reduced_ms,full_ms`.
    pub fn summary_csv(&self) -> String {
        let mut out = String::from("m_u,m_f,mean_one_step_error,reduced_step_ms,full_step_ms,tensor_mb\n");
        for s in &self.sizes {
            out += &format!(
                "{},{},{:.9e},{:.4},{:.2},{:.2}\n",
                s.m_u,
                s.m_f,
                s.mean(),
                1e3 * s.reduced_seconds,
                1e3 * s.full_seconds,
                s.tensor_bytes as f64 / 1e6
            );
        }
        out
    }
}

/// Runs the study of `model` on the test run `test` for basis sizes `sizes` (m_u = m_f = m,
/// each at most the model's), over frames `0, stride, 2·stride, …` below `frames` (at most the
/// run's last but one), the full steps taking `refinement` times the RK4 substeps their
/// stability needs ([`FluidSolver::with_substep_refinement`]). `progress(done, total)` is
/// called after each step pair.
pub fn one_step_errors(
    model: &ReducedFluidModel,
    test: &SnapshotReader,
    sizes: &[usize],
    frames: usize,
    stride: usize,
    refinement: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<ErrorStudy, FluidError> {
    let (mesh, topo) = model.mesh_and_topology()?;
    let meta = test.meta();
    model.check_mesh(&MeshFingerprint::of(
        &SimplexMesh::new(meta.dim, test.frame("g", 0)?, test.cells().to_vec())?,
        &topo,
        meta.periodic_axis,
    ))?;
    if stride == 0 {
        return Err(FluidError::State("stride must be at least 1".into()));
    }
    let last = meta.frames.saturating_sub(1).min(frames).min(MAX_STUDY_FRAMES);
    let studied: Vec<usize> = (0..last).step_by(stride).collect();
    if studied.is_empty() {
        return Err(FluidError::State(format!("the test run has {} frames: nothing to step", meta.frames)));
    }
    let (mu_max, mf_max) = (model.dim_of("u"), model.dim_of("f"));
    for &m in sizes {
        if m == 0 || m > mu_max.min(mf_max) {
            return Err(FluidError::State(format!(
                "basis size {m}: the model has m_u {mu_max} and m_f {mf_max}; train with larger caps"
            )));
        }
    }
    let params = crate::fluid::FluidParams {
        viscosity: model.viscosity,
        forcing: [0.0; 3],
        frame_time: model.frame_time,
    };
    let mut solver =
        FluidSolver::new(mesh.clone(), topo.clone(), params)?.with_substep_refinement(refinement);
    let d = mesh.dim();
    let bg = model.basis("g").ok_or_else(|| FluidError::State("the model has no basis g".into()))?;
    let mut geometry_error: f64 = 0.0;
    let total = sizes.len() * studied.len();
    let mut done = 0;
    let mut out = Vec::new();
    let mut sorted = sizes.to_vec();
    sorted.sort_unstable();
    sorted.dedup();
    for &m in &sorted {
        let cut = model.truncated(m, m, None, &topo)?;
        let fluid = ReducedFluid::new(&cut)?;
        let (bu, bf) = (cut.basis("u").expect("u"), cut.basis("f").expect("f"));
        let bh = cut.basis("h");
        let mut errors = Vec::with_capacity(studied.len());
        let (mut tr, mut tf) = (Vec::new(), Vec::new());
        for &t in &studied {
            let (g0, g1) = (test.frame("g", t)?, test.frame("g", t + 1)?);
            let (p, f, h) = (test.frame("p", t)?, test.frame("f", t)?, test.frame("h", t + 1)?);
            let (gh0, gh1) = (bg.project(&g0), bg.project(&g1));
            for g in [&g0, &g1] {
                let e = rel(&bg.lift(&bg.project(g)), g);
                geometry_error = geometry_error.max(e);
            }
            let r = fluid.project_velocity(&bu.project(&p), &gh0)?;
            let fh = bf.project(&f);
            let hh = bh.map(|b| b.project(&h)).unwrap_or_default();
            let t0 = std::time::Instant::now();
            let (next, _) = fluid.step(&ReducedState { u: r.clone(), f: fh.clone(), g: gh0 }, &gh1, &hh)?;
            tr.push(t0.elapsed().as_secs_f64());
            let u_test = bu.lift(&next.u);
            let state = FluidState { g: g0, u: bu.lift(&r), f: bf.lift(&fh) };
            let t1 = std::time::Instant::now();
            let (ground, _) = solver.step(&state, &g1, t + 1)?;
            tf.push(t1.elapsed().as_secs_f64());
            let vols = mesh.volumes_at(&g1);
            let energy = |u: &dyn Fn(usize) -> f64| -> f64 {
                (0..u_test.len()).map(|i| 0.5 * vols[i / d] * u(i).powi(2)).sum()
            };
            let e_ground = energy(&|i| ground.u[i]);
            let e_diff = energy(&|i| ground.u[i] - u_test[i]);
            let err = if e_ground > 0.0 { e_diff / e_ground } else { 0.0 };
            if !err.is_finite() {
                return Err(FluidError::State(format!(
                    "basis size {m}, frame {t}: the one-step error is not finite"
                )));
            }
            errors.push(err);
            done += 1;
            progress(done, total);
        }
        out.push(SizeErrors {
            m_u: fluid.dims().0,
            m_f: fluid.dims().1,
            frames: studied.clone(),
            errors,
            reduced_seconds: crate::bench::median_f64(&mut tr),
            full_seconds: crate::bench::median_f64(&mut tf),
            tensor_bytes: cut.tensor_bytes(),
        });
    }
    Ok(ErrorStudy { sizes: out, geometry_error, frame_time: model.frame_time })
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let den: f64 = b.iter().map(|y| y * y).sum();
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

impl ErrorStudy {
    /// Writes the study into `dir`: errors.csv (per size and frame), summary.csv (per size),
    /// and the plots fig5d.png (error over time) and fig5e.png (error against basis size).
    pub fn write_outputs(&self, dir: &std::path::Path) -> Result<(), FluidError> {
        std::fs::create_dir_all(dir).map_err(FluidError::io(dir))?;
        for (name, text) in [("errors.csv", self.csv()), ("summary.csv", self.summary_csv())] {
            let path = dir.join(name);
            crate::atomic_file::write(&path, text.as_bytes()).map_err(FluidError::io(&path))?;
        }
        super::plot::plot_over_time(self, &dir.join("fig5d.png"))?;
        super::plot::plot_by_size(self, &dir.join("fig5e.png"))
    }
}
