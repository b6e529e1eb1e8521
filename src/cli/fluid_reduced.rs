//! `galerkin fluid train | reduced`: seed 000 §6's reduced fluid from the command line (the
//! work is in `galerkin::fluid::reduced`; this parses and prints).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use galerkin::fluid::reduced::{
    run_reduced, write_lifted, BasisSizes, ReducedFluidModel, ReducedMotion, TrainingSet,
};
use galerkin::reduce::Communicator;

/// Arguments of `galerkin fluid train`.
#[derive(Args)]
pub struct TrainArgs {
    /// Snapshot directories of full runs on one mesh (written by `galerkin fluid simulate`).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Model file to write (safetensors).
    #[arg(long, default_value = "out/fluid-model.safetensors")]
    pub out: PathBuf,
    #[command(flatten)]
    pub sizes: SizeArgs,
}

/// Basis sizes, shared by `fluid train` and `fluid train-scene`.
#[derive(Args)]
pub struct SizeArgs {
    /// Captured-energy threshold of every basis: the fewest modes whose σ² reach this
    /// fraction of the snapshots' (the caps below still apply).
    #[arg(long, default_value_t = 0.9999)]
    pub energy: f64,
    /// Cap on the flux basis B_f (Table 1: cavity 64, eagle 70).
    #[arg(long)]
    pub m_f: Option<usize>,
    /// Cap on the velocity–momentum basis B_u = B_p, after merging (Table 1: cavity 128,
    /// eagle 193).
    #[arg(long)]
    pub m_u: Option<usize>,
    /// Cap on the geometry basis B_g, the mean geometry included (Table 1: cavity 5, eagle 7).
    #[arg(long)]
    pub m_g: Option<usize>,
    /// Cap on the induced-flux basis B_h.
    #[arg(long)]
    pub m_h: Option<usize>,
    /// B_u = B_p also spans each training frame's mid-step velocity (advected and diffused,
    /// before the projection), recomputed from the snapshots: one full advection per frame.
    /// The default: it brings reduced runs closer to the full ones in every case measured
    /// (BENCHMARKS.md, "Mid-step velocities in B_u").
    #[arg(long, overrides_with = "no_mid_step")]
    pub mid_step: bool,
    /// B_u = B_p from the frames' velocities and momenta only (the paper's §6 bases).
    #[arg(long, overrides_with = "mid_step")]
    pub no_mid_step: bool,
}

impl SizeArgs {
    fn sizes(&self) -> BasisSizes {
        BasisSizes {
            energy: self.energy,
            m_f: self.m_f,
            m_u: self.m_u,
            m_g: self.m_g,
            m_h: self.m_h,
            mid_step: !self.no_mid_step,
        }
    }
}

/// Prints a trained model's bases, one line each, and the flux directions its projection
/// solves for.
fn print_bases(model: &ReducedFluidModel) {
    for r in &model.provenance.bases {
        println!("  B_{:<2} {:>8} × {:<4} energy {:.6}  {}", r.name, r.full, r.columns, r.energy, r.note);
    }
    if let Ok(Some(seen)) =
        galerkin::fluid::reduced::step::ReducedFluid::new(model).map(|f| f.seen_flux().cloned())
    {
        println!("  {}", seen.line());
    }
}

/// Arguments of `galerkin fluid train-scene`.
#[derive(Args)]
pub struct TrainSceneArgs {
    /// The scene (e.g. scenes/fluid/cavity.toml: its 14 training runs; a bird or surface
    /// scene: its animation).
    pub scene: PathBuf,
    /// Model file to write (safetensors).
    #[arg(long, default_value = "out/fluid-model.safetensors")]
    pub out: PathBuf,
    /// Work directory for the full runs and the bases (default: beside the model, named after
    /// it with `.work`). Run the same command again to resume a stopped training.
    #[arg(long)]
    pub work: Option<PathBuf>,
    /// Frames per run (default: the scene's).
    #[arg(long, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: Option<usize>,
    /// The cavity's training runs to use, comma-separated (default: all, 0 to 13).
    #[arg(long, value_delimiter = ',')]
    pub runs: Option<Vec<usize>>,
    #[command(flatten)]
    pub sizes: SizeArgs,
}

/// Arguments of `galerkin fluid compare`.
#[derive(Args)]
pub struct CompareArgs {
    /// A model written by `galerkin fluid train-scene`.
    pub model: PathBuf,
    /// The scene (default: the one the model was trained from, refused if it changed since).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Compare on training run K (replayed at the pace it was trained at; the cavity's full run
    /// is simulated again) …
    #[arg(long, conflicts_with = "drive")]
    pub run: Option<usize>,
    /// … or on the full run in this snapshot directory, read instead of simulated: the
    /// reduced run follows that run's own geometry and induced flux from its frame 0 — a
    /// training run (e.g. out/cavity.work/run-00), a held-out obstacle of the same mesh, a
    /// driven cavity (`fluid simulate --drive`); any scene, the bird's too.
    #[arg(long, conflicts_with_all = ["drive", "run"])]
    pub full: Option<PathBuf>,
    /// … or on compressions no run made (keyframes, see `fluid reduced --drive`).
    #[arg(long, default_value = "0=0/0/0,30=0.5/0/0,60=0.5/0/0.4,90=0/0/0.4")]
    pub drive: galerkin::fluid::reduced::CompressionSchedule,
    /// Frames (default: the motion's).
    #[arg(long, value_parser = crate::cli::args::count_from_one_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: Option<usize>,
    /// Simulate the full run with this many times the RK4 substeps its stability needs (the
    /// reduced exponential is exact; refining shows how much of the difference is the full
    /// solver's own time integration). Not with --full.
    #[arg(long, default_value_t = 1)]
    pub refine: usize,
    /// Directory for comparison.csv, energy.png, error.png and error-section.png.
    #[arg(long, default_value = "out/fluid-compare")]
    pub out: PathBuf,
    /// With --full: also split each reduced step into its stages, each against the full
    /// solver's from the same start (advection, the advected velocity's distance from B_u,
    /// projection; energies after each) → split.csv. One full step per frame.
    #[arg(long, requires = "full")]
    pub split: bool,
    /// Also estimate the reduced run's error without the full run and compare the estimate
    /// with the true error (columns error_estimate and effectivity): the unseen-velocity
    /// indicator, from reduced quantities alone, every step (the velocity of the reduced flux
    /// outside B_u and of each step's flux change; models trained before the flux velocity
    /// Gram matrices were measured lack it).
    #[arg(long, conflicts_with = "indicator_every")]
    pub indicator: bool,
    /// … or the residual indicator: the full step from the lifted reduced state, measured
    /// every K-th step (one full step each).
    #[arg(long, value_name = "K", value_parser = crate::cli::args::count_up_to(galerkin::fluid::reduced::indicator::MAX_EVERY))]
    pub indicator_every: Option<usize>,
    /// The reduced projection's normal matrix from the full space, M(g) = B_fᵀPᵀV⁻¹PB_f,
    /// instead of its Galerkin image P̂ᵀV̂⁻¹P̂: computed once per run on a static mesh (the
    /// tunnel), every frame on a moving one at full-space cost.
    #[arg(long)]
    pub exact_projection: bool,
    /// Leave out of the reduced projection the flux directions with less than this fraction
    /// of their velocity energy inside the velocity basis (measured at training on the
    /// training geometries; the projection cannot identify them from a reduced velocity and
    /// gives them coefficients that advect wrongly). 0 keeps every direction; models trained
    /// before the measure existed are not narrowed.
    #[arg(long, value_name = "FRACTION", value_parser = crate::cli::args::fraction, default_value_t = galerkin::fluid::reduced::step::SEEN_FLUX_THRESHOLD)]
    pub seen_flux: f64,
}

/// Arguments of `galerkin fluid reduced`.
#[derive(Args)]
pub struct ReducedArgs {
    /// Model file written by `galerkin fluid train`.
    pub model: PathBuf,
    /// Frames to run (default: the replayed run's whole motion).
    #[arg(long, value_parser = crate::cli::args::count_from_one_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: Option<usize>,
    /// The motion: replay:K replays training run K's reduced geometry and induced flux
    /// (runs numbered from 0 in the order given to `train`), starting from its initial state;
    /// computed:K follows run K's geometry but computes the induced flux from each pair of
    /// frames through the reduced induced-flux tensor.
    #[arg(long, default_value = "replay:0")]
    pub motion: ReducedMotion,
    /// Drive a cavity model by its compressions instead (a motion never trained):
    /// FRAME=A1/A2/A3 keyframes, comma-separated, interpolated linearly and held after the
    /// last, e.g. 0=0/0/0,30=0.5/0/0,60=0.5/0/0.4,90=0/0/0.4. From rest; ĥ from the reduced
    /// induced-flux tensor.
    #[arg(long, conflicts_with = "motion")]
    pub drive: Option<galerkin::fluid::reduced::CompressionSchedule>,
    /// Follow the --motion run's geometry this many times as fast (0.5 half speed, 2 twice;
    /// 1/64 to 64): the geometry interpolated between its frames, the induced flux from the
    /// reduced tensor (the bird's wingbeat slowed down or sped up).
    #[arg(long, conflicts_with = "drive")]
    pub pace: Option<f64>,
    /// Follow the motion of the full run in this snapshot directory instead — any run of the
    /// model's mesh: a held-out obstacle, a driven cavity (`fluid simulate --drive`), a
    /// training run — its geometry and induced flux projected into the model's bases, from
    /// its frame 0.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["motion", "drive", "pace"])]
    pub geometry: Option<PathBuf>,
    /// Estimate the run's error per frame without a full run → indicator.csv in the output
    /// directory: the unseen-velocity indicator, from reduced quantities alone, every step
    /// (the velocity of the reduced flux outside B_u and of each step's flux change; models
    /// trained before the flux velocity Gram matrices were measured lack it).
    #[arg(long, conflicts_with = "indicator_every")]
    pub indicator: bool,
    /// … or the residual indicator: the full step from the lifted reduced state, measured
    /// every K-th step (one full step each).
    #[arg(long, value_name = "K", value_parser = crate::cli::args::count_up_to(galerkin::fluid::reduced::indicator::MAX_EVERY))]
    pub indicator_every: Option<usize>,
    /// The reduced projection's normal matrix from the full space (see `fluid compare
    /// --exact-projection`).
    #[arg(long)]
    pub exact_projection: bool,
    /// Leave out of the reduced projection the flux directions with less than this fraction
    /// of their velocity energy inside the velocity basis (measured at training on the
    /// training geometries; the projection cannot identify them from a reduced velocity and
    /// gives them coefficients that advect wrongly). 0 keeps every direction; models trained
    /// before the measure existed are not narrowed.
    #[arg(long, value_name = "FRACTION", value_parser = crate::cli::args::fraction, default_value_t = galerkin::fluid::reduced::step::SEEN_FLUX_THRESHOLD)]
    pub seen_flux: f64,
    /// Snapshot directory to write, lifted to the full space (for `fluid render`).
    #[arg(long, default_value = "out/fluid-reduced")]
    pub out: PathBuf,
    /// Overwrite a directory that already holds snapshots.
    #[arg(long)]
    pub force: bool,
}

/// Arguments of `galerkin fluid error-study`.
#[derive(Args)]
pub struct StudyArgs {
    /// Training runs (snapshot directories), e.g. the small- and large-obstacle tunnels.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// The test run (not trained on), e.g. the medium-obstacle tunnel.
    #[arg(long)]
    pub test: PathBuf,
    /// Basis sizes m (m_u = m_f = m), comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "8,16,32,64,128")]
    pub sizes: Vec<usize>,
    /// Frames of the test run to step from (at most its last but one).
    #[arg(long, default_value_t = 1000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: usize,
    /// Study every STRIDE-th frame (the full step from each frame dominates the time).
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
    /// The ground truth's RK4 substeps, as a multiple of what its stability needs (the bound
    /// keeps RK4 stable, not accurate; the reduced step's exponential is exact).
    #[arg(long, default_value_t = 4)]
    pub refine: usize,
    /// Directory for errors.csv, summary.csv, fig5d.png and fig5e.png.
    #[arg(long, default_value = "out/fluid-error-study")]
    pub out: PathBuf,
}

pub fn error_study(args: &StudyArgs) -> Result<()> {
    use galerkin::fluid::snapshots::SnapshotReader;
    let start = Instant::now();
    let largest = args.sizes.iter().copied().max().unwrap_or(0);
    let set = TrainingSet::open(&args.runs)?;
    let sizes = BasisSizes {
        energy: 1.0,
        m_f: Some(largest),
        m_u: Some(largest),
        m_g: None,
        m_h: None,
        mid_step: false,
    };
    let bar = crate::progress_bar(7, "training the largest basis");
    let model = ReducedFluidModel::fit(&set, &sizes, &mut |_| bar.inc(1))?;
    bar.finish_and_clear();
    println!(
        "fluid error-study: trained m_u {}, m_f {}, m_g {} on {} runs in {:.1} s",
        model.dim_of("u"),
        model.dim_of("f"),
        model.dim_of("g"),
        args.runs.len(),
        start.elapsed().as_secs_f64()
    );
    let test = SnapshotReader::open(&args.test)?;
    let bar = crate::progress_bar(1, "one-step errors");
    let study = galerkin::fluid::reduced::one_step_errors(
        &model,
        &test,
        &args.sizes,
        args.frames,
        args.stride,
        args.refine,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    )?;
    bar.finish_and_clear();
    study.write_outputs(&args.out)?;
    println!("  m_u  m_f  mean one-step error  reduced step  full step  speedup  reduced tensors");
    for s in &study.sizes {
        println!(
            "{:>5} {:>4}  {:>19.3e}  {:>9.3} ms  {:>7.1} ms  {:>6.0}×  {:>8.2} MB",
            s.m_u,
            s.m_f,
            s.mean(),
            1e3 * s.reduced_seconds,
            1e3 * s.full_seconds,
            s.full_seconds / s.reduced_seconds,
            s.tensor_bytes as f64 / 1e6
        );
    }
    println!(
        "time-averaged error {} with basis size; test geometry in span(B_g) to {:.1e}; {:.1} s → {}",
        if study.monotone() { "falls monotonically" } else { "does NOT fall monotonically" },
        study.geometry_error,
        start.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

/// `galerkin fluid train`, over MPI ranks when `mpirun` started it: progress and results from
/// rank 0 only, which alone writes the model.
pub fn train(args: &TrainArgs, ranks: &dyn Communicator) -> Result<()> {
    let start = Instant::now();
    let set = TrainingSet::open(&args.runs)?;
    let frames: usize = set.frames().iter().sum();
    let root = ranks.is_root();
    if root {
        println!(
            "fluid train: {} runs, {frames} frames, {}D mesh of {} cells and {} faces",
            args.runs.len(),
            set.mesh().dim(),
            set.mesh().cell_count(),
            set.topology().face_count()
        );
    }
    let sizes = args.sizes.sizes();
    // FluidBases::build's order (the geometry first), then the model's.
    let stages = ["g", "f", "u", "h", "d", "trajectories", "premultiply"];
    let bar = match root {
        true => crate::progress_bar(stages.len() as u64, "training"),
        false => indicatif::ProgressBar::hidden(),
    };
    let mut stage = |name: &str| {
        tracing::info!(stage = name, seconds = start.elapsed().as_secs_f64(), "fluid train: stage starts");
        bar.set_message(format!("{name} ({:.0} s)", start.elapsed().as_secs_f64()));
        bar.set_position(stages.iter().position(|s| *s == name).unwrap_or(0) as u64);
    };
    let model = ReducedFluidModel::fit_across(&set, &sizes, &mut stage, ranks)?;
    bar.finish_and_clear();
    if ranks.size() > 1 {
        tracing::info!(
            ranks = ranks.size(),
            sent_mb = ranks.bytes_sent() as f64 / 1e6,
            "fluid train: rank 0's communication"
        );
    }
    if !root {
        return Ok(());
    }
    model.save(&args.out)?;
    print_bases(&model);
    println!("trained in {:.1} s → {}", start.elapsed().as_secs_f64(), args.out.display());
    Ok(())
}

/// `galerkin fluid train-scene`, over MPI ranks when `mpirun` started it (each rank simulates
/// its share of the runs; rank 0 alone prints and writes).
pub fn train_scene(args: &TrainSceneArgs, ranks: &dyn Communicator) -> Result<()> {
    use galerkin::fluid::reduced::{SceneTraining, TrainingEvent};
    let start = Instant::now();
    let work = args.work.clone().unwrap_or_else(|| {
        let name = args.out.file_stem().map_or("fluid-model".into(), |s| s.to_string_lossy().into_owned());
        args.out.with_file_name(format!("{name}.work"))
    });
    let options = SceneTraining {
        sizes: args.sizes.sizes(),
        frames: args.frames,
        runs: args.runs.clone(),
        work: work.clone(),
    };
    let root = ranks.is_root();
    if root {
        println!("fluid train-scene: {} (work directory {})", args.scene.display(), work.display());
    }
    let mut bar: Option<indicatif::ProgressBar> = None;
    let mut on_event = |event: TrainingEvent| match event {
        _ if !root => {}
        TrainingEvent::RunStarted { run, index, of, frames } => {
            let b = crate::progress_bar(frames as u64, &format!("run {run} ({} of {of})", index + 1));
            bar = Some(b);
        }
        TrainingEvent::Frame(_) => {
            if let Some(b) = &bar {
                b.inc(1);
            }
        }
        TrainingEvent::Part(part) => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
            println!("  … {part} ({:.0} s)", start.elapsed().as_secs_f64());
        }
        TrainingEvent::StageDone { stage, seconds, peak_mb, resumed } => {
            if let Some(b) = bar.take() {
                b.finish_and_clear();
            }
            let report = galerkin::reduce::reductor::StageReport { stage, seconds, peak_mb, resumed };
            println!("  {}", report.line());
        }
    };
    let model =
        galerkin::fluid::reduced::train_scene_across(&args.scene, &args.out, &options, &mut on_event, ranks)?;
    if !root {
        return Ok(());
    }
    print_bases(&model);
    println!(
        "trained in {:.1} s → {} ({:.1} MB of reduced tensors)",
        start.elapsed().as_secs_f64(),
        args.out.display(),
        model.tensor_bytes() as f64 / 1e6
    );
    Ok(())
}

/// The schedule, after a warning on stderr if it compresses beyond the model's training.
fn warn_beyond(
    model: &ReducedFluidModel,
    schedule: &galerkin::fluid::reduced::CompressionSchedule,
) -> galerkin::fluid::reduced::CompressionSchedule {
    if let Some(w) = model.warn_beyond_training(schedule.largest()) {
        eprintln!("warning: {w}");
    }
    schedule.clone()
}

pub fn compare(desc: &galerkin::gpu::GpuDesc, args: &CompareArgs) -> Result<()> {
    use galerkin::fluid::reduced::compare::ComparedMotion;
    let model = ReducedFluidModel::load(&args.model)?;
    let scene = galerkin::fluid::scene::FluidScene::load(&model.scene_file(args.scene.as_deref())?)?;
    let (motion, frames, title) = match (args.run, &args.full) {
        (_, Some(full)) => {
            let motion = ComparedMotion::Recorded { full: full.clone() };
            let recorded = galerkin::fluid::snapshots::SnapshotReader::open(full)?.meta().frames;
            (
                motion,
                args.frames.unwrap_or(recorded.saturating_sub(1)),
                format!("the run in {}", full.display()),
            )
        }
        (Some(k), None) => {
            // The run's own frame count (a model trained with --frames N), not the scene's.
            let trained = model.trajectories.get(k).map_or(scene.frames, |t| t.frames());
            (ComparedMotion::Training(k), args.frames.unwrap_or(trained), format!("training run {k}"))
        }
        (None, None) => (
            ComparedMotion::Driven(warn_beyond(&model, &args.drive)),
            args.frames.unwrap_or(args.drive.last_frame()),
            "a motion outside the training set".to_string(),
        ),
    };
    let bar =
        crate::progress_bar(frames as u64, if args.full.is_some() { "full run (read)" } else { "full run" });
    let mut c = galerkin::fluid::reduced::compare::compare_with(
        &model,
        &scene,
        &motion,
        (frames, args.refine, projection(args.exact_projection, args.seen_flux)),
        &mut |k| bar.set_position(k as u64),
    )?;
    bar.finish_and_clear();
    let mut indicator_cost = None;
    if args.indicator {
        let (_, seconds) = c.add_unseen_indicator(&model, &mut |_| {})?;
        indicator_cost = Some(seconds);
    } else if let Some(every) = args.indicator_every {
        let bar = crate::progress_bar(frames as u64, "error indicator");
        c.add_indicator(&model, every, &mut |k| bar.set_position(k as u64))?;
        bar.finish_and_clear();
    }
    let gpu = galerkin::gpu::Gpu::new(desc)?;
    c.write_outputs(&gpu, &scene.mesh, &title, frames, &args.out)?;
    let (mean, worst) = c.error_summary();
    let (best_mean, best_worst) = c.projection_summary();
    let (step_mean, step_worst) = c.one_step_summary();
    let (flux_mean, flux_worst) = c.flux_projection_summary();
    let speed = if c.seconds.0.is_finite() {
        format!(
            "full frame {:.3} s, reduced step {:.3} ms ({:.0}×)",
            c.seconds.0,
            1e3 * c.seconds.1,
            c.seconds.0 / c.seconds.1.max(1e-12)
        )
    } else {
        format!("reduced step {:.3} ms (the full run read back)", 1e3 * c.seconds.1)
    };
    if let Some(seen) = &c.seen_flux {
        println!("{}", seen.line());
    }
    println!(
        "fluid compare: {title}, {frames} frames: relative velocity error in the energy norm mean {:.2} %, worst {:.2} % (the best fit in B_u: mean {:.2} %, worst {:.2} %; one reduced step from the full run's previous frame: mean {:.2} %, worst {:.2} %; the full flux's truncation in B_f: mean {:.2} %, worst {:.2} %); energy at the end full {:.4e}, reduced {:.4e}; {speed} → {}",
        100.0 * mean,
        100.0 * worst,
        100.0 * best_mean,
        100.0 * best_worst,
        100.0 * step_mean,
        100.0 * step_worst,
        100.0 * flux_mean,
        100.0 * flux_worst,
        c.energy_full.last().copied().unwrap_or(0.0),
        c.energy_reduced.last().copied().unwrap_or(0.0),
        args.out.display()
    );
    drop(gpu);
    if !c.estimate.is_empty() {
        let (lo, hi) = c.effectivity_range();
        println!(
            "{} indicator: estimate at the end {:.2} % (true {:.2} %); effectivity (estimate ÷ true error) from {lo:.2} to {hi:.2} over frames 1 to {frames}{}",
            if indicator_cost.is_some() { "unseen-velocity" } else { "residual" },
            100.0 * c.estimate.last().copied().unwrap_or(0.0),
            100.0 * c.error.last().copied().unwrap_or(0.0),
            indicator_cost.map_or(String::new(), |s| cost_line(s, c.seconds.1))
        );
    }
    let (adv, proj) = c.reduced_energy_loss.iter().fold((0.0, 0.0), |(a, p), l| (a + l[0], p + l[1]));
    println!(
        "the reduced run's energy lost over its steps: in advection and diffusion {adv:.4e}, in the projection {proj:.4e}"
    );
    if let (true, Some(full)) = (args.split, &args.full) {
        use galerkin::fluid::reduced::diagnose::{split_means, split_steps, StepSplit};
        let bar = crate::progress_bar(frames as u64, "split steps");
        let splits = split_steps(
            &model,
            &scene,
            full,
            frames,
            projection(args.exact_projection, args.seen_flux),
            &mut |k| bar.set_position(k as u64),
        )?;
        bar.finish_and_clear();
        let mut csv = String::from(StepSplit::CSV_HEADER);
        for s in &splits {
            csv += "\n";
            csv += &s.csv_row();
        }
        csv += "\n";
        let path = args.out.join("split.csv");
        galerkin::atomic_file::write(&path, csv.as_bytes())?;
        let [adv, trunc, proj, step, in_basis, flux, adv_own] = split_means(&splits);
        let (mut lost_full_adv, mut lost_red_adv, mut lost_full_proj, mut lost_red_proj, mut lost_start) =
            (0.0, 0.0, 0.0, 0.0, 0.0);
        for s in &splits {
            let e = s.energy;
            lost_start += e[0] - e[1];
            lost_full_adv += e[0] - e[2];
            lost_red_adv += e[1] - e[3];
            lost_full_proj += e[2] - e[4];
            lost_red_proj += e[3] - e[5];
        }
        println!(
            "fluid compare --split: one step from each full frame, means over {frames} frames: advection {:.2} %, the advected velocity outside B_u {:.2} %, projection {:.2} %, whole step {:.2} % ({:.2} % of it inside B_u, what a run carries on), the step's flux {:.2} % off the full one, advection from the flux the step made {:.2} %; energy lost, summed over the steps (each from the full frame): projecting the full frame into the bases {lost_start:.4e}; advection full {lost_full_adv:.4e}, reduced {lost_red_adv:.4e}; projection full {lost_full_proj:.4e}, reduced {lost_red_proj:.4e} → {}",
            100.0 * adv,
            100.0 * trunc,
            100.0 * proj,
            100.0 * step,
            100.0 * in_basis,
            100.0 * flux,
            100.0 * adv_own,
            path.display()
        );
    }
    Ok(())
}

/// The reduced projection the flags ask for.
fn projection(exact: bool, seen_flux: f64) -> galerkin::fluid::reduced::compare::Projection {
    galerkin::fluid::reduced::compare::Projection { exact, seen_flux }
}

pub fn reduced(args: &ReducedArgs) -> Result<()> {
    let model = ReducedFluidModel::load(&args.model)?;
    let fluid = galerkin::fluid::reduced::compare::reduced_fluid(
        &model,
        &projection(args.exact_projection, args.seen_flux),
    )?;
    let k = args.motion.run();
    let recorded = match &args.geometry {
        Some(dir) => {
            let reader = galerkin::fluid::snapshots::SnapshotReader::open(dir)?;
            Some(galerkin::fluid::reduced::Trajectory::recorded(&model, &reader, dir)?)
        }
        None => None,
    };
    let available = match (&args.drive, &recorded) {
        (Some(schedule), _) => schedule.last_frame(),
        (None, Some(traj)) => traj.frames(),
        (None, None) => {
            let run = galerkin::fluid::reduced::run::trajectory(&model, k, &args.motion.to_string())?;
            let frames = run.g.shape()[0].saturating_sub(1);
            (frames as f64 / args.pace.unwrap_or(1.0) + 1e-9).floor() as usize
        }
    };
    let frames = args.frames.unwrap_or(available);
    if frames == 0 {
        return Err(galerkin::fluid::FluidError::State(
            "the motion has no steps to run: give --frames N (at least 1)".into(),
        )
        .into());
    }
    let bar = crate::progress_bar(frames as u64, "reduced steps");
    let run = match (&args.drive, &recorded, &args.geometry) {
        (Some(schedule), _, _) => {
            let schedule = warn_beyond(&model, schedule);
            galerkin::fluid::reduced::run_driven(&model, &fluid, &schedule, frames, &mut |_| bar.inc(1))?
        }
        (None, Some(traj), Some(dir)) => galerkin::fluid::reduced::run::follow(
            &fluid,
            traj,
            true,
            frames,
            &dir.display().to_string(),
            &mut |_| bar.inc(1),
        )?,
        _ => match args.pace {
            Some(pace) => {
                galerkin::fluid::reduced::run_paced(&model, &fluid, k, pace, frames, &mut |_| bar.inc(1))?
            }
            None => run_reduced(&model, &fluid, args.motion, frames, &mut |_| bar.inc(1))?,
        },
    };
    bar.finish_and_clear();
    let (mu, mf, mg, mh) = fluid.dims();
    let first = &run.states[0];
    let last = &run.states[run.states.len() - 1];
    println!(
        "fluid reduced: {frames} frames (m_u {mu}, m_f {mf}, m_g {mg}, m_h {mh}), {:.3} ms per step (median); energy {:.5} → {:.5}",
        1e3 * run.median_step_seconds(),
        fluid.energy(&first.u, &first.g),
        fluid.energy(&last.u, &last.g)
    );
    if let Some(seen) = fluid.seen_flux() {
        println!("{}", seen.line());
    }
    write_lifted(&model, &run, &args.out, args.force)?;
    println!("lifted to the full space → {}", args.out.display());
    // Either indicator: its CSV in the output directory and the estimate at the last frame.
    let indicated = if args.indicator {
        use galerkin::fluid::reduced::unseen::{indicate_unseen, unseen_csv};
        let (frames_out, seconds) = indicate_unseen(&model, &fluid, &run, &mut |_| {})?;
        let cost = cost_line(seconds, run.median_step_seconds());
        Some(("unseen-velocity indicator", unseen_csv(&frames_out), frames_out, cost))
    } else if let Some(every) = args.indicator_every {
        use galerkin::fluid::reduced::indicator::{indicate, indicator_csv};
        let bar = crate::progress_bar(frames as u64, "error indicator");
        // A recorded motion's full-space geometry is the full step's (its velocities are not read).
        let reader =
            args.geometry.as_deref().map(galerkin::fluid::snapshots::SnapshotReader::open).transpose()?;
        let frames_out =
            indicate(&model, &fluid, &run, every, reader.as_ref(), &mut |k| bar.set_position(k as u64))?;
        bar.finish_and_clear();
        Some(("residual indicator", indicator_csv(&frames_out), frames_out, String::new()))
    } else {
        None
    };
    if let Some((name, csv, frames_out, cost)) = indicated {
        let path = args.out.join("indicator.csv");
        galerkin::atomic_file::write(&path, csv.as_bytes())?;
        let last = frames_out.last().map_or(0.0, |f| f.estimate);
        println!(
            "{name}: estimated error at frame {frames} {:.2} %{cost} → {}",
            100.0 * last,
            path.display()
        );
    }
    Ok(())
}

/// "; X µs a step, Y % of the reduced step": what the indicator adds to a step.
fn cost_line(indicator_seconds: f64, step_seconds: f64) -> String {
    format!(
        "; {:.1} µs a step ({:.2} % of the reduced step's {:.3} ms)",
        1e6 * indicator_seconds,
        100.0 * indicator_seconds / step_seconds.max(1e-12),
        1e3 * step_seconds
    )
}

/// Arguments of `galerkin fluid bench-reduced`.
#[derive(Args)]
pub struct BenchArgs {
    /// The small cavity mesh (8,959 cells) and 10⁴ energy steps: a minute instead of several.
    #[arg(long)]
    pub quick: bool,
    /// Reduced steps timed per exponential.
    #[arg(long, default_value_t = 200, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub steps: usize,
    /// Reduced steps of the energy run (default 10⁶; 10⁴ with --quick).
    #[arg(long, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub energy_steps: Option<usize>,
    /// Basis sizes m_u,m_f,m_g,m_h of the cavity step (Table 1's cavity: 128,64,5; m_h ours).
    #[arg(long, default_value = "128,64,5,16", value_parser = crate::cli::args::four_counts)]
    pub sizes: [usize; 4],
    /// Measure a trained model instead (Table 1's reduced rows): the full step on --scene and
    /// the reduced step under the same motion (a cavity model driven by --drive, any other
    /// model replaying a training run, --replay), and reduced particles on the CPU and the
    /// device.
    #[arg(long)]
    pub model: Option<std::path::PathBuf>,
    /// With --model: the scene the model was trained on (its mesh is checked against the
    /// model's), e.g. scenes/fluid/bird.toml for a bird model.
    #[arg(long, default_value = "scenes/fluid/cavity.toml")]
    pub scene: std::path::PathBuf,
    /// With --model: replay training run K (its reduced geometry and induced flux) instead of
    /// driving a cavity model; the default for models that are not a cavity's.
    #[arg(long, conflicts_with = "drive")]
    pub replay: Option<usize>,
    /// With --model: frames of the motion (default: the drive's last keyframe, or the replayed
    /// run's whole length).
    #[arg(long, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_FRAMES))]
    pub frames: Option<usize>,
    /// With --model: particles advected every frame.
    #[arg(long, default_value_t = 10_000, value_parser = crate::cli::args::count_up_to(crate::cli::args::MAX_PARTICLES))]
    pub particles: usize,
    /// With --model: the motion (compression keyframes, see `fluid reduced --drive`).
    #[arg(long, default_value = "0=0/0/0,30=0.5/0/0,60=0.5/0/0.4,90=0/0/0.4")]
    pub drive: galerkin::fluid::reduced::CompressionSchedule,
}

/// `galerkin fluid bench-reduced` ([`galerkin::bench::fluid_reduced::step_report`], or with
/// --model [`galerkin::bench::fluid_reduced::model_report`]).
pub fn bench(desc: &galerkin::gpu::GpuDesc, args: &BenchArgs) -> Result<()> {
    use galerkin::bench::fluid_reduced::{model_report, step_report, BenchMotion, StepBench};
    let start = Instant::now();
    let mut log = |s: &str| eprintln!("[{:6.1} s] {s}", start.elapsed().as_secs_f64());
    let mut emit = |s: &str| print!("{s}");
    if let Some(path) = &args.model {
        let model = ReducedFluidModel::load(path)?;
        let gpu = galerkin::gpu::Gpu::new(desc).ok();
        let drive;
        let motion = match (args.replay, &model.cavity) {
            (None, Some(_)) => {
                drive = warn_beyond(&model, &args.drive);
                BenchMotion::Drive(&drive)
            }
            (k, _) => BenchMotion::Replay(k.unwrap_or(0)),
        };
        model_report(
            &model,
            &args.scene,
            motion,
            args.frames,
            args.particles,
            gpu.as_ref(),
            &mut log,
            &mut emit,
        )?;
        drop(gpu);
        return Ok(());
    }
    let [mu, mf, mg, mh] = args.sizes;
    let mut bench = StepBench::new(args.quick);
    bench.sizes = (mu, mf, mg, mh);
    bench.steps = args.steps;
    if let Some(n) = args.energy_steps {
        bench.energy_steps = n;
    }
    let bar = crate::progress_bar(bench.energy_steps as u64, "reduced steps (energy)");
    let result = step_report(&bench, &mut log, &mut |k, _| bar.set_position(k as u64), &mut emit);
    bar.finish_and_clear();
    Ok(result?)
}
