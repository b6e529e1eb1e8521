//! `galerkin fluid train | reduced`: seed 000 §6's reduced fluid from the command line (the
//! work is in `galerkin::fluid::reduced`; this parses and prints).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use galerkin::fluid::reduced::{
    run_reduced, write_lifted, BasisSizes, FluidBases, ReducedFluid, ReducedFluidModel, ReducedMotion,
    TrainingSet,
};

/// Arguments of `galerkin fluid train`.
#[derive(Args)]
pub struct TrainArgs {
    /// Snapshot directories of full runs on one mesh (written by `galerkin fluid simulate`).
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// Model file to write (safetensors).
    #[arg(long, default_value = "out/fluid-model.safetensors")]
    pub out: PathBuf,
    /// Captured-energy threshold of every basis: the fewest modes whose σ² reach this
    /// fraction of the snapshots' (the caps below still apply).
    #[arg(long, default_value_t = 0.9999)]
    pub energy: f64,
    /// Cap on the flux basis B_f.
    #[arg(long)]
    pub m_f: Option<usize>,
    /// Cap on the velocity–momentum basis B_u = B_p (after merging).
    #[arg(long)]
    pub m_u: Option<usize>,
    /// Cap on the geometry basis B_g (the mean geometry included).
    #[arg(long)]
    pub m_g: Option<usize>,
    /// Cap on the induced-flux basis B_h.
    #[arg(long)]
    pub m_h: Option<usize>,
}

/// Arguments of `galerkin fluid reduced`.
#[derive(Args)]
pub struct ReducedArgs {
    /// Model file written by `galerkin fluid train`.
    pub model: PathBuf,
    /// Frames to run (default: the replayed run's whole motion).
    #[arg(long)]
    pub frames: Option<usize>,
    /// The motion: replay:K replays training run K's reduced geometry and induced flux
    /// (runs numbered from 0 in the order given to `train`), starting from its initial state.
    #[arg(long, default_value = "replay:0")]
    pub motion: ReducedMotion,
    /// Snapshot directory to write, lifted to the full space (for `fluid render`).
    #[arg(long, default_value = "out/fluid-reduced")]
    pub out: PathBuf,
    /// Overwrite a directory that already holds snapshots.
    #[arg(long)]
    pub force: bool,
}

pub fn train(args: &TrainArgs) -> Result<()> {
    let start = Instant::now();
    let set = TrainingSet::open(&args.runs)?;
    let frames: usize = set.frames().iter().sum();
    println!(
        "fluid train: {} runs, {frames} frames, {}D mesh of {} cells and {} faces",
        args.runs.len(),
        set.mesh().dim(),
        set.mesh().cell_count(),
        set.topology().face_count()
    );
    let sizes =
        BasisSizes { energy: args.energy, m_f: args.m_f, m_u: args.m_u, m_g: args.m_g, m_h: args.m_h };
    let stages = ["f", "u", "g", "h", "d", "premultiply", "trajectories"];
    let bar = crate::progress_bar(stages.len() as u64, "training");
    let mut stage = |name: &str| {
        bar.set_message(format!("{name} ({:.0} s)", start.elapsed().as_secs_f64()));
        bar.set_position(stages.iter().position(|s| *s == name).unwrap_or(0) as u64);
    };
    let bases = FluidBases::build(&set, &sizes, &mut stage)?;
    let model = ReducedFluidModel::train(&set, bases, &sizes, &mut stage)?;
    bar.finish_and_clear();
    model.save(&args.out)?;
    for r in &model.provenance.bases {
        println!("  B_{:<2} {:>8} × {:<4} energy {:.6}  {}", r.name, r.full, r.columns, r.energy, r.note);
    }
    println!("trained in {:.1} s → {}", start.elapsed().as_secs_f64(), args.out.display());
    Ok(())
}

pub fn reduced(args: &ReducedArgs) -> Result<()> {
    let model = ReducedFluidModel::load(&args.model)?;
    let fluid = ReducedFluid::new(&model)?;
    let ReducedMotion::Replay(k) = args.motion;
    let available = model.trajectories.get(k).map_or(0, |t| t.g.shape()[0].saturating_sub(1));
    let frames = args.frames.unwrap_or(available);
    let bar = crate::progress_bar(frames as u64, "reduced steps");
    let run = run_reduced(&model, &fluid, args.motion, frames, &mut |_| bar.inc(1))?;
    bar.finish_and_clear();
    let mut step: Vec<f64> = run.reports.iter().map(|r| r.total_seconds()).collect();
    let (mu, mf, mg, mh) = fluid.dims();
    let first = &run.states[0];
    let last = &run.states[run.states.len() - 1];
    println!(
        "fluid reduced: {frames} frames (m_u {mu}, m_f {mf}, m_g {mg}, m_h {mh}), {:.3} ms per step (median); energy {:.5} → {:.5}",
        1e3 * galerkin::bench::median_f64(&mut step),
        fluid.energy(&first.u, &first.g),
        fluid.energy(&last.u, &last.g)
    );
    write_lifted(&model, &run, &args.out, args.force)?;
    println!("lifted to the full space → {}", args.out.display());
    Ok(())
}
