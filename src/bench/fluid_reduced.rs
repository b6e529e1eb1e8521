//! `galerkin fluid bench-reduced`: the reduced fluid step (seed 000 Fig. 2 right) at Table 1's
//! cavity basis sizes on synthetic bases of the cavity mesh, stage by stage, with both
//! exponentials; and a long run of reduced steps watching the energy (§A.1–A.2).
//!
//! Synthetic bases: `B_u` and `B_h` random orthonormal, `B_f` random fluxes with their
//! divergence removed (so advection stays skew), `B_g` the cavity's rest geometry and smooth
//! random displacements of it, `B_d` by constraint reduction — the step's cost depends only on
//! the reduced sizes, and these bases keep its matrices as well conditioned as real ones.

use std::path::Path;
use std::time::Instant;

use crate::fluid::reduced::bases::{constraint_basis, remove_divergence};
use crate::fluid::reduced::{
    BasisSizes, Exponential, FluidBases, MeshOf, ReducedFluid, ReducedFluidModel, ReducedState, Trajectory,
};
use crate::fluid::scene::FluidScene;
use crate::fluid::FluidError;
use crate::reduce::{Basis, SingleRank};
use crate::tensor::Tensor;

use super::reduce::random;

/// An orthonormal basis of `m` random columns (QR by faer).
fn random_basis(name: &str, n: usize, m: usize, seed: u64) -> Result<Basis, FluidError> {
    let r = random(n * m, seed);
    orthonormal(name, faer::Mat::from_fn(n, m, |i, j| r[i * m + j]))
}

fn orthonormal(name: &str, a: faer::Mat<f64>) -> Result<Basis, FluidError> {
    let (n, m) = (a.nrows(), a.ncols());
    let q = a.qr().compute_thin_Q();
    let data: Vec<f64> = (0..n).flat_map(|i| (0..m).map(move |j| (i, j))).map(|(i, j)| q[(i, j)]).collect();
    Basis::new(name, Tensor::from_vec(&[n, m], data).expect("n×m"), 1e-9)
        .map_err(|e| FluidError::State(e.to_string()))
}

/// Medians of one configuration's stages.
#[derive(Clone, Debug)]
pub struct StepTiming {
    /// "Krylov" or "Padé 13".
    pub exponential: &'static str,
    /// (m_u, m_f, m_g, m_h, m_d).
    pub dims: (usize, usize, usize, usize, usize),
    /// Median seconds: K̂ assembly, V̂ contraction and factorisation, exponential, projection.
    pub stages: [f64; 4],
    /// Median seconds of the whole step.
    pub total: f64,
    /// Median Krylov products per step.
    pub products: usize,
}

/// What the cavity benchmark built.
#[derive(Clone, Debug)]
pub struct CavityBench {
    /// Cells of the mesh.
    pub cells: usize,
    /// Seconds to premultiply the synthetic model.
    pub premultiply_seconds: f64,
    /// Bytes of the reduced model with its bases.
    pub model_bytes: usize,
    /// Bytes of the reduced tensors alone.
    pub tensor_bytes: usize,
    /// Per exponential.
    pub timings: Vec<StepTiming>,
}

/// The reduced step on `scene`'s mesh (a cavity) at basis sizes `(m_u, m_f, m_g, m_h)`,
/// `steps` steps per exponential. `stage(text)` reports progress.
pub fn cavity_step(
    scene: &Path,
    sizes: (usize, usize, usize, usize),
    steps: usize,
    stage: &mut dyn FnMut(&str),
) -> Result<CavityBench, FluidError> {
    let (mu, mf, mg, mh) = sizes;
    stage("loading the mesh");
    let scene = FluidScene::load(scene)?;
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    let d = mesh.dim();
    stage("synthetic bases");
    let u = random_basis("u", d * mesh.cell_count(), mu, 1)?;
    let raw = random_basis("f", topo.face_count(), mf, 2)?;
    let f = remove_divergence(topo, &raw)?;
    let g0 = mesh.g().to_vec();
    let (lo, hi) = mesh.bounds();
    let ng = g0.len();
    let gcols = faer::Mat::from_fn(ng, mg, |i, j| {
        if j == 0 {
            return g0[i];
        }
        // Smooth displacements: products of sines of the vertex's position.
        let v = i / d;
        let p = mesh.point(v);
        let w: f64 = (0..d)
            .map(|k| ((j + k) as f64 * std::f64::consts::PI * (p[k] - lo[k]) / (hi[k] - lo[k])).sin())
            .product();
        0.01 * w * (1.0 + (i % d) as f64)
    });
    let g = orthonormal("g", gcols)?;
    let h = random_basis("h", topo.face_count(), mh, 3)?;
    let bd = constraint_basis(topo, &f, Some(&h))?;
    let bases = FluidBases { f, u, g, h: Some(h), d: bd, reports: Vec::new() };
    stage("premultiplying");
    let t = Instant::now();
    let gh0 = bases.g.project(&g0);
    let traj = Trajectory {
        g: Tensor::from_vec(&[1, mg], gh0.clone()).expect("1 × m_g"),
        h: Tensor::zeros(&[1, mh]),
        u0: vec![0.0; mu],
        f0: vec![0.0; mf],
    };
    let model = ReducedFluidModel::from_bases(
        MeshOf { mesh, topology: topo, periodic_axis: None },
        &scene.params,
        false,
        bases,
        &BasisSizes::default(),
        vec![],
        vec![traj],
        &SingleRank,
    )?;
    let premultiply_seconds = t.elapsed().as_secs_f64();
    let mut fluid = ReducedFluid::new(&model)?;
    let md = model.dim_of("d");
    let mut timings = Vec::new();
    for (label, exponential) in [("Krylov", Exponential::Krylov(1e-12)), ("Padé 13", Exponential::Pade)] {
        stage(label);
        fluid.exponential = exponential;
        let mut state = ReducedState { u: random(mu, 7), f: random(mf, 8), g: gh0.clone() };
        let (mut st, mut tot, mut prods) = (vec![Vec::new(); 4], Vec::new(), Vec::new());
        for k in 0..steps {
            // A small wobble of the geometry and induced flux, as a moving cavity has.
            let mut g1 = gh0.clone();
            for (j, x) in g1.iter_mut().enumerate().skip(1) {
                *x += 1e-3 * ((k + j) as f64 * 0.1).sin();
            }
            let hh: Vec<f64> = (0..mh).map(|j| 1e-3 * ((k * 7 + j) as f64 * 0.13).cos()).collect();
            let (next, r) = fluid.step(&state, &g1, &hh)?;
            tot.push(r.total_seconds());
            for (s, v) in st.iter_mut().zip([
                r.assemble_seconds,
                r.volume_seconds,
                r.exponential_seconds,
                r.projection_seconds,
            ]) {
                s.push(v);
            }
            prods.push(r.krylov_products as f64);
            state = next;
        }
        let med = |v: &mut Vec<f64>| super::median_f64(v);
        timings.push(StepTiming {
            exponential: label,
            dims: (mu, mf, mg, mh, md),
            stages: [med(&mut st[0]), med(&mut st[1]), med(&mut st[2]), med(&mut st[3])],
            total: med(&mut tot),
            products: med(&mut prods) as usize,
        });
    }
    Ok(CavityBench {
        cells: mesh.cell_count(),
        premultiply_seconds,
        model_bytes: model.bytes(),
        tensor_bytes: model.tensor_bytes(),
        timings,
    })
}

/// The energy over a long reduced run.
#[derive(Clone, Copy, Debug)]
pub struct EnergyRun {
    /// Steps taken.
    pub steps: usize,
    /// Energy at the start.
    pub initial: f64,
    /// Largest energy seen.
    pub maximum: f64,
    /// Energy at the end.
    pub last: f64,
    /// Median seconds per step.
    pub step_seconds: f64,
}

/// `steps` reduced steps of `model` from training run 0's initial state at its first geometry,
/// the geometry held still (ĥ = 0): the setting of §A.2's guarantee.
pub fn energy_run(
    model: &ReducedFluidModel,
    steps: usize,
    progress: &mut dyn FnMut(usize),
) -> Result<EnergyRun, FluidError> {
    let fluid = ReducedFluid::new(model)?;
    let traj =
        model.trajectories.first().ok_or_else(|| FluidError::State("the model has no trajectory".into()))?;
    let mg = model.dim_of("g");
    let g = traj.g.data()[..mg].to_vec();
    let h = vec![0.0; model.dim_of("h")];
    let mut state = ReducedState { u: traj.u0.clone(), f: traj.f0.clone(), g: g.clone() };
    let initial = fluid.energy(&state.u, &g);
    let (mut maximum, mut times) = (initial, Vec::with_capacity(steps.min(1 << 20)));
    for k in 0..steps {
        let t = Instant::now();
        let (next, _) = fluid.step(&state, &g, &h)?;
        if times.len() < 1 << 20 {
            times.push(t.elapsed().as_secs_f64());
        }
        state = next;
        maximum = maximum.max(fluid.energy(&state.u, &g));
        if k % 1000 == 0 {
            progress(k);
        }
    }
    Ok(EnergyRun {
        steps,
        initial,
        maximum,
        last: fluid.energy(&state.u, &g),
        step_seconds: super::median_f64(&mut times),
    })
}

/// Table 1's reduced rows measured on a trained model (the cavity driven, the bird replayed),
/// side by side with the full step at the same size under the same motion.
#[derive(Clone, Debug)]
pub struct ModelBench {
    /// Cells of the mesh.
    pub cells: usize,
    /// Basis sizes (m_u, m_f, m_g, m_h).
    pub dims: (usize, usize, usize, usize),
    /// Median seconds of a full frame (deformation, advection, projection) and its stages.
    pub full: [f64; 4],
    /// Median seconds of a reduced step (t_s), the steps timed alone: [`STEP_ROUNDS`] rounds
    /// of the motion.
    pub reduced: f64,
    /// Median seconds of a reduced step in the loop that also advects the particles between
    /// steps (on the CPU and the device), as an application stepping and drawing does.
    pub reduced_with_particles: f64,
    /// Median seconds of the particles' frame on the CPU (f64) and on the device (f32,
    /// timestamps around the pass), 10 Euler substeps each.
    pub particles: (f64, Option<f64>),
    /// Particles advected.
    pub particle_count: usize,
    /// Why the device could not run the particle pass, if it could not.
    pub device_refused: Option<String>,
    /// Run-time memory in bytes: the reduced step's tensors as it holds them
    /// ([`ReducedFluid::bytes`], Table 1's memory column), the model's reduced tensors as
    /// stored (f64, every axis unfolded), and `B_f` and `B_g`, which the particles read.
    pub memory: ModelMemory,
}

/// What a trained model's run time holds ([`ModelBench::memory`]), in bytes.
#[derive(Clone, Copy, Debug, Default)]
pub struct ModelMemory {
    /// The reduced step's tensors as it lays them out ([`ReducedFluid::bytes`]).
    pub step: usize,
    /// The model's reduced tensors as stored in the file (f64, symmetric axes unfolded).
    pub stored: usize,
    /// `B_f` and `B_g` (f64), read by the particles (§6.5).
    pub particle_bases: usize,
}

/// Rounds of the motion in which [`trained_model`] times the reduced step alone.
pub const STEP_ROUNDS: usize = 5;

/// The motion a trained model is measured under ([`trained_model`]).
#[derive(Clone, Copy, Debug)]
pub enum BenchMotion<'a> {
    /// A cavity model driven by compressions: ĝ from its reduced motion model, ĥ from the
    /// reduced induced-flux tensor; the full step under the same compressions.
    Drive(&'a crate::fluid::reduced::CompressionSchedule),
    /// Training run K replayed (its ĝ and ĥ, seed 000 §6.2; the bird's Table 1 row); the full
    /// step under the scene's own motion of that run, its deformation included.
    Replay(usize),
}

/// Measures `model` under `motion`: `full_frames` frames of the full solver on `scene` under
/// the same motion; `frames` reduced steps timed alone, [`STEP_ROUNDS`] times; then the
/// `frames` steps again, each followed by `particles` particles advected from the reduced
/// state (on `gpu` too, if given), every part timed.
pub fn trained_model(
    model: &ReducedFluidModel,
    scene: &Path,
    motion: BenchMotion<'_>,
    (frames, full_frames): (usize, usize),
    particles: usize,
    gpu: Option<&crate::gpu::Gpu>,
    stage: &mut dyn FnMut(&str),
) -> Result<ModelBench, FluidError> {
    use crate::fluid::particles::seed_particles;
    use crate::fluid::reduced::particles::ReducedParticles;
    use crate::fluid::scene::Motion;
    let (mg, mh) = (model.dim_of("g"), model.dim_of("h"));
    // Where the reduced side's ĝ and ĥ come from, resolved once.
    enum Reduced<'m> {
        Drive(&'m crate::fluid::reduced::CavityMotion, &'m crate::fluid::reduced::CompressionSchedule),
        Replay(usize, &'m crate::fluid::reduced::Trajectory),
    }
    let reduced_motion = match motion {
        BenchMotion::Drive(schedule) => Reduced::Drive(
            model.cavity.as_ref().ok_or_else(|| FluidError::State("not a cavity model".into()))?,
            schedule,
        ),
        BenchMotion::Replay(k) => {
            let traj = model.trajectories.get(k).ok_or_else(|| {
                FluidError::State(format!(
                    "run {k}: the model has training runs 0 to {}",
                    model.trajectories.len().saturating_sub(1)
                ))
            })?;
            let available = traj.g.shape()[0].saturating_sub(1);
            if frames > available {
                return Err(FluidError::State(format!("{frames} frames: training run {k} has {available}")));
            }
            Reduced::Replay(k, traj)
        }
    };
    stage("the full step");
    let mut scene = FluidScene::load(scene)?;
    model.check_mesh(&crate::fluid::reduced::MeshFingerprint::of(
        &scene.mesh,
        &scene.topology,
        scene.periodic_axis,
    ))?;
    if let (Reduced::Replay(k, _), Motion::Cavity { .. }) = (&reduced_motion, &scene.motion) {
        scene.set_run(*k)?;
    }
    let mut solver =
        crate::fluid::FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params)?;
    let mut state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity)?;
    let mut full = vec![Vec::new(); 4];
    for t in 1..=full_frames {
        let start = Instant::now();
        let g = match (motion, &scene.motion) {
            (BenchMotion::Drive(schedule), Motion::Cavity { cavity, .. }) => {
                cavity.mapped_for(schedule.at(t))
            }
            (BenchMotion::Drive(_), _) => {
                return Err(FluidError::State("a driven benchmark's scene must be the model's cavity".into()))
            }
            (BenchMotion::Replay(_), _) => scene.geometry(t)?,
        };
        let td = start.elapsed().as_secs_f64();
        let (next, r) = solver.step(&state, &g, t)?;
        for (v, x) in full.iter_mut().zip([
            td,
            r.advection_seconds,
            r.projection_seconds,
            start.elapsed().as_secs_f64(),
        ]) {
            v.push(x);
        }
        state = next;
    }
    let cells = scene.mesh.cell_count();
    drop(scene.motion);
    stage("the reduced steps and particles");
    let fluid = ReducedFluid::new(model)?;
    let reference = ReducedParticles::new(model)?;
    let seeds = seed_particles(reference.mesh(), particles);
    let mut cpu = seeds.clone();
    // A device that cannot hold the pass's buffers is reported, not fatal to the CPU rows.
    let mut device_refused = None;
    let mut device = match gpu {
        Some(g) => match crate::fluid::gpu::GpuParticles::new_reduced(g, &reference, &seeds) {
            Ok(p) => Some((p, g)),
            Err(e) => {
                stage(&format!("particles on the device refused: {e}"));
                device_refused = Some(e.to_string());
                None
            }
        },
        None => None,
    };
    let mut profiler = gpu
        .map(|g| crate::gpu::Profiler::new(g, 1))
        .transpose()
        .map_err(|e| FluidError::State(e.to_string()))?;
    let (mu, mf) = (model.dim_of("u"), model.dim_of("f"));
    let row = |t: &crate::tensor::Tensor, m: usize, k: usize| t.data()[k * m..(k + 1) * m].to_vec();
    let geometry = |t: usize| -> Result<Vec<f64>, FluidError> {
        match &reduced_motion {
            Reduced::Drive(cavity, schedule) => cavity.geometry(schedule.at(t)),
            Reduced::Replay(_, traj) => Ok(row(&traj.g, mg, t)),
        }
    };
    let rest = match &reduced_motion {
        Reduced::Replay(_, traj) => ReducedState { u: traj.u0.clone(), f: traj.f0.clone(), g: geometry(0)? },
        Reduced::Drive(..) => ReducedState { u: vec![0.0; mu], f: vec![0.0; mf], g: geometry(0)? },
    };
    let step = |s: &ReducedState, t: usize| -> Result<(ReducedState, f64), FluidError> {
        let g1 = geometry(t)?;
        let h1 = match &reduced_motion {
            Reduced::Replay(_, traj) if mh > 0 => row(&traj.h, mh, t),
            _ => fluid.induced_flux(&s.g, &g1).ok_or_else(|| FluidError::State("no tensor H".into()))?,
        };
        let (next, r) = fluid.step(s, &g1, &h1)?;
        Ok((next, r.total_seconds()))
    };
    // The step alone: the driven motion from rest, STEP_ROUNDS times.
    let mut reduced = Vec::new();
    for _ in 0..STEP_ROUNDS {
        let mut s = rest.clone();
        for t in 1..=frames {
            let (next, seconds) = step(&s, t)?;
            reduced.push(seconds);
            s = next;
        }
    }
    // Then stepping and advecting the particles in turn, each timed.
    let (mut interleaved, mut particles_cpu, mut particles_gpu) = (Vec::new(), Vec::new(), Vec::new());
    let mut s = rest;
    for t in 1..=frames {
        let (next, seconds) = step(&s, t)?;
        interleaved.push(seconds);
        let start = Instant::now();
        reference.advect(&s.g, &next.g, &next.f, model.frame_time, 10, &mut cpu)?;
        particles_cpu.push(start.elapsed().as_secs_f64());
        if let (Some((p, g)), Some(prof)) = (&mut device, &mut profiler) {
            g.run(|rec| {
                prof.record_reset(rec);
                prof.scope(rec, "particles", |rec| {
                    p.record_reduced_frame(rec, &s.g, &next.g, &next.f)?;
                    p.record_advect(rec, model.frame_time, 10)
                })
            })
            .map_err(|e| FluidError::State(e.to_string()))??;
            let r = prof.results().map_err(|e| FluidError::State(e.to_string()))?;
            particles_gpu.push(r.first().map_or(0.0, |x| x.1 * 1e-3));
        }
        s = next;
    }
    let med = |v: &mut Vec<f64>| super::median_f64(v);
    let bases: usize = ["f", "g"].iter().filter_map(|b| model.basis(b)).map(|b| 8 * b.matrix().len()).sum();
    Ok(ModelBench {
        cells,
        dims: (mu, mf, mg, mh),
        full: [med(&mut full[0]), med(&mut full[1]), med(&mut full[2]), med(&mut full[3])],
        reduced: med(&mut reduced),
        reduced_with_particles: med(&mut interleaved),
        particles: (med(&mut particles_cpu), (!particles_gpu.is_empty()).then(|| med(&mut particles_gpu))),
        particle_count: particles,
        device_refused,
        memory: ModelMemory { step: fluid.bytes(), stored: model.tensor_bytes(), particle_bases: bases },
    })
}

/// What [`step_report`] measures.
#[derive(Clone, Debug)]
pub struct StepBench {
    /// The cavity scene whose mesh carries the synthetic bases.
    pub scene: std::path::PathBuf,
    /// Basis sizes (m_u, m_f, m_g, m_h).
    pub sizes: (usize, usize, usize, usize),
    /// Reduced steps timed per exponential.
    pub steps: usize,
    /// Reduced steps of the energy run.
    pub energy_steps: usize,
    /// Where the small tunnel's training runs are kept between runs.
    pub work: std::path::PathBuf,
}

impl StepBench {
    /// Table 1's cavity sizes (128, 64, 5; m_h 16) on the cavity (`quick`: the small cavity
    /// and 10⁴ energy steps instead of 10⁶).
    pub fn new(quick: bool) -> Self {
        Self {
            scene: if quick { "scenes/fluid/cavity_small.toml" } else { "scenes/fluid/cavity.toml" }.into(),
            sizes: (128, 64, 5, 16),
            steps: 200,
            energy_steps: if quick { 10_000 } else { 1_000_000 },
            work: "out/bench-fluid-reduced".into(),
        }
    }
}

/// The reduced step at Table 1's cavity sizes on synthetic bases of the cavity mesh, stage by
/// stage with both exponentials ([`cavity_step`]), and the energy over many reduced steps of a
/// small tunnel model trained here ([`energy_run`]), as Markdown through `emit`. `log` reports
/// stages, `progress` the energy run's steps.
pub fn step_report(
    bench: &StepBench,
    log: &mut dyn FnMut(&str),
    progress: &mut dyn FnMut(usize, usize),
    emit: &mut dyn FnMut(&str),
) -> Result<(), FluidError> {
    let b = cavity_step(&bench.scene, bench.sizes, bench.steps, log)?;
    emit(&format!(
        "Reduced step on {} ({} cells, synthetic bases; premultiplied in {:.1} s; reduced tensors {:.1} MB, with the bases {:.1} MB), medians of {} steps:\n\n",
        bench.scene.display(),
        b.cells,
        b.premultiply_seconds,
        b.tensor_bytes as f64 / 1e6,
        b.model_bytes as f64 / 1e6,
        bench.steps
    ));
    emit("| exponential | m_u | m_f | m_g | m_h | m_d | K̂ (ms) | V̂ (ms) | exp (ms) | projection (ms) | step (ms) | Krylov products |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for t in &b.timings {
        let (a, f, g, h, d) = t.dims;
        emit(&format!(
            "| {} | {a} | {f} | {g} | {h} | {d} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {} |\n",
            t.exponential,
            1e3 * t.stages[0],
            1e3 * t.stages[1],
            1e3 * t.stages[2],
            1e3 * t.stages[3],
            1e3 * t.total,
            if t.exponential.starts_with("Krylov") { t.products.to_string() } else { "—".into() }
        ));
    }
    log("training the small tunnel for the energy run");
    let (runs, _) = crate::fluid::reduced::example::small_tunnel_runs(&bench.work, 100)?;
    let model = ReducedFluidModel::fit(
        &crate::fluid::reduced::TrainingSet::open(&runs)?,
        &BasisSizes::default(),
        &mut |_| {},
    )?;
    let total = bench.energy_steps;
    let e = energy_run(&model, total, &mut |k| progress(k, total))?;
    emit(&format!(
        "\nEnergy over {} reduced steps of the small tunnel (m_u {}, m_f {}, static geometry): start {:.9}, maximum {:.9}, final {:.9}; {:.4} ms per step.\n",
        e.steps,
        model.dim_of("u"),
        model.dim_of("f"),
        e.initial,
        e.maximum,
        e.last,
        1e3 * e.step_seconds
    ));
    Ok(())
}

/// Table 1's reduced rows on a trained `model` ([`trained_model`]): the full step on `scene`
/// (median of 8 frames) and the reduced step under the same `motion` (`frames` of it; a
/// drive's default is its last keyframe, a replay's its whole run), and `particles`
/// particles from the reduced state on the CPU and `gpu`, as Markdown.
#[allow(clippy::too_many_arguments)]
pub fn model_report(
    model: &ReducedFluidModel,
    scene: &Path,
    motion: BenchMotion<'_>,
    frames: Option<usize>,
    particles: usize,
    gpu: Option<&crate::gpu::Gpu>,
    log: &mut dyn FnMut(&str),
    emit: &mut dyn FnMut(&str),
) -> Result<(), FluidError> {
    let (frames, what) = match motion {
        BenchMotion::Drive(schedule) => {
            (frames.unwrap_or(schedule.last_frame()).max(1), "frames of compressions".to_string())
        }
        BenchMotion::Replay(k) => {
            let available = model.trajectories.get(k).map_or(1, |t| t.g.shape()[0].saturating_sub(1));
            (frames.unwrap_or(available).max(1), format!("frames of training run {k} replayed"))
        }
    };
    let b = trained_model(model, scene, motion, (frames, 8), particles, gpu, log)?;
    let (mu, mf, mg, mh) = b.dims;
    let [td, ta, tp, total] = b.full;
    let device = match (b.particles.1, &b.device_refused) {
        (Some(s), _) => format!("{:.2} ms", 1e3 * s),
        (None, Some(why)) => format!("refused: {why}"),
        (None, None) => "no device".into(),
    };
    emit(&format!(
        "Model of {} ({} cells; m_u {mu}, m_f {mf}, m_g {mg}, m_h {mh}), {frames} {what}:\n\n\
         | quantity | time |\n|---|---:|\n\
         | full step t_d (median of 8 frames) | {td:.3} s |\n\
         | full step t_a | {ta:.3} s |\n\
         | full step t_p | {tp:.3} s |\n\
         | full step, total | {total:.3} s |\n\
         | reduced step t_s (median of {} steps timed alone) | {:.3} ms ({:.0}× the full step) |\n\
         | reduced step, stepping and advecting particles in turn (median of {frames}) | {:.3} ms |\n\
         | particles t_pa, {} from the reduced state, 10 substeps a frame, CPU | {:.2} ms |\n\
         | the same on the device | {device} |\n\
         | run-time memory of the reduced step (its tensors as it holds them) | {:.1} MB |\n\
         | the model's reduced tensors as stored (f64, unfolded) | {:.1} MB |\n\
         | B_f and B_g, read by the particles | {:.1} MB |\n",
        scene.display(),
        b.cells,
        STEP_ROUNDS * frames,
        1e3 * b.reduced,
        total / b.reduced,
        1e3 * b.reduced_with_particles,
        b.particle_count,
        1e3 * b.particles.0,
        b.memory.step as f64 / 1e6,
        b.memory.stored as f64 / 1e6,
        b.memory.particle_bases as f64 / 1e6
    ));
    Ok(())
}
