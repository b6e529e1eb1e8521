//! A reduced run: the reduced step driven by a motion, and its frames lifted to the full space
//! as a snapshot directory (so `galerkin fluid render` and the viewer show it).
//!
//! Motions: [`ReducedMotion::Replay`] replays training run K's reduced geometry and induced
//! flux (§6.2: "we store values of ĥ along deformation trajectories that we will use at
//! runtime and replay these trajectories"); its frame t → t + 1 uses `ĝ_{t+1}` and `ĥ_{t+1}`
//! of that run (a snapshot's h is the flux of the motion that ends at its frame).

use std::path::Path;

use crate::fluid::snapshots::{SnapshotMeta, SnapshotWriter};
use crate::fluid::FluidError;
use crate::mesh::SimplexMesh;
use crate::reduce::Basis;

use super::cavity_motion::CompressionSchedule;
use super::model::{ReducedFluidModel, Trajectory};
use super::step::{ReducedFluid, ReducedState, ReducedStepReport};

/// Where a reduced run's motion comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReducedMotion {
    /// Training run K's reduced geometry and induced flux, frame by frame.
    Replay(usize),
    /// Training run K's reduced geometry, the induced flux computed from each pair of frames
    /// by the reduced induced-flux tensor ([`super::induced`]) — what a motion never simulated
    /// would use.
    Computed(usize),
}

impl ReducedMotion {
    /// The training run whose geometry the motion follows.
    pub fn run(self) -> usize {
        match self {
            ReducedMotion::Replay(k) | ReducedMotion::Computed(k) => k,
        }
    }
}

/// `replay:K` or `computed:K`, as `--motion` spells it (errors name the motion asked for).
impl std::fmt::Display for ReducedMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReducedMotion::Replay(k) => write!(f, "replay:{k}"),
            ReducedMotion::Computed(k) => write!(f, "computed:{k}"),
        }
    }
}

impl std::str::FromStr for ReducedMotion {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.split_once(':') {
            Some(("replay", k)) => {
                k.trim().parse().map(ReducedMotion::Replay).map_err(|e| format!("replay:{k}: {e}"))
            }
            Some(("computed", k)) => {
                k.trim().parse().map(ReducedMotion::Computed).map_err(|e| format!("computed:{k}: {e}"))
            }
            _ => Err(format!("{s}: expected replay:K or computed:K (K a training run, from 0)")),
        }
    }
}

/// A reduced run's frames: the initial state, then one per step, with each step's ĥ and report.
#[derive(Clone, Debug)]
pub struct ReducedRun {
    /// States, frame 0 first.
    pub states: Vec<ReducedState>,
    /// ĥ of each frame (zero for frame 0).
    pub h: Vec<Vec<f64>>,
    /// Each step's report.
    pub reports: Vec<ReducedStepReport>,
}

impl ReducedRun {
    /// The median step's seconds (Table 1's t_s).
    pub fn median_step_seconds(&self) -> f64 {
        let mut step: Vec<f64> = self.reports.iter().map(|r| r.total_seconds()).collect();
        crate::bench::median_f64(&mut step)
    }
}

/// Runs `frames` reduced steps of `model` under `motion` from the motion's initial state;
/// `on_frame(k)` is called after each.
pub fn run_reduced(
    model: &ReducedFluidModel,
    fluid: &ReducedFluid,
    motion: ReducedMotion,
    frames: usize,
    on_frame: &mut dyn FnMut(usize),
) -> Result<ReducedRun, FluidError> {
    let what = motion.to_string();
    let traj = trajectory(model, motion.run(), &what)?;
    follow(fluid, traj, matches!(motion, ReducedMotion::Replay(_)), frames, &what, on_frame)
}

/// Runs `frames` reduced steps along `traj` — a training run's motion, or a recorded run's
/// ([`Trajectory::recorded`]: a held-out obstacle, a driven cavity) — from its initial state:
/// frame t's ĝ is the trajectory's, its ĥ the trajectory's too when `replay_h`, otherwise from
/// the reduced induced-flux tensor. `what` names the motion in errors.
pub fn follow(
    fluid: &ReducedFluid,
    traj: &Trajectory,
    replay_h: bool,
    frames: usize,
    what: &str,
    on_frame: &mut dyn FnMut(usize),
) -> Result<ReducedRun, FluidError> {
    let available = traj.frames();
    if frames > available {
        return Err(FluidError::State(format!("{what}: {frames} frames asked, the motion has {available}")));
    }
    let (mg, mh) = (traj.g.shape()[1], traj.h.shape()[1]);
    let row = |t: &crate::tensor::Tensor, m: usize, i: usize| t.data()[i * m..(i + 1) * m].to_vec();
    let start = ReducedState { u: traj.u0.clone(), f: traj.f0.clone(), g: row(&traj.g, mg, 0) };
    let replay = |t: usize| -> Option<Vec<f64>> { replay_h.then(|| row(&traj.h, mh, t)) };
    step_through(fluid, start, frames, &mut |t| Ok((row(&traj.g, mg, t), replay(t))), on_frame)
}

/// Most a paced replay may speed up or slow down a training motion.
pub const PACE_RANGE: (f64, f64) = (1.0 / 64.0, 64.0);

/// Runs `frames` reduced steps following training run K's motion `pace` times as fast (0.5:
/// half speed, 2: twice; seed 000 §7.2's bird "can be sped up or slowed down"): frame t's ĝ is
/// the run's reduced geometry at training frame `t·pace`, linear between its frames — exactly
/// the projection of the linearly interpolated full geometries, B_g being linear — and ĥ comes
/// from the reduced induced-flux tensor, since the replayed ĥ belongs to the run's own pace.
/// From the run's initial state; `t·pace` may not pass the run's last frame.
pub fn run_paced(
    model: &ReducedFluidModel,
    fluid: &ReducedFluid,
    run: usize,
    pace: f64,
    frames: usize,
    on_frame: &mut dyn FnMut(usize),
) -> Result<ReducedRun, FluidError> {
    if !(pace.is_finite() && (PACE_RANGE.0..=PACE_RANGE.1).contains(&pace)) {
        return Err(FluidError::State(format!(
            "pace {pace}: give a factor from {} to {}",
            PACE_RANGE.0, PACE_RANGE.1
        )));
    }
    let traj = trajectory(model, run, &format!("run {run}"))?;
    let available = traj.g.shape()[0].saturating_sub(1);
    let end = frames as f64 * pace;
    if end > available as f64 + 1e-9 {
        return Err(FluidError::State(format!(
            "run {run} at pace {pace}: {frames} frames reach its frame {end:.1}, it has {available}; give at most {} frames",
            (available as f64 / pace + 1e-9).floor()
        )));
    }
    let mg = traj.g.shape()[1];
    let row = |i: usize| &traj.g.data()[i * mg..(i + 1) * mg];
    let at = |t: usize| -> Vec<f64> {
        let s = (t as f64 * pace).min(available as f64);
        let i = (s.floor() as usize).min(available.saturating_sub(1));
        let w = s - i as f64;
        if available == 0 {
            return row(0).to_vec();
        }
        row(i).iter().zip(row(i + 1)).map(|(a, b)| (1.0 - w) * a + w * b).collect()
    };
    let start = ReducedState { u: traj.u0.clone(), f: traj.f0.clone(), g: at(0) };
    step_through(fluid, start, frames, &mut |t| Ok((at(t), None)), on_frame)
}

/// Runs `frames` reduced steps of the cavity model `model` driven by `schedule` (its
/// compressions per frame, [`super::cavity_motion`]) from rest: each frame's ĝ from the
/// cavity's motion model, its ĥ from the reduced induced-flux tensor — a motion no training run
/// needs to have made.
pub fn run_driven(
    model: &ReducedFluidModel,
    fluid: &ReducedFluid,
    schedule: &CompressionSchedule,
    frames: usize,
    on_frame: &mut dyn FnMut(usize),
) -> Result<ReducedRun, FluidError> {
    let motion = model.cavity.as_ref().ok_or_else(|| {
        FluidError::State("the model has no cavity motion model (train it from a cavity scene)".into())
    })?;
    let g0 = motion.geometry(schedule.at(0))?;
    let (mu, mf) = (model.dim_of("u"), model.dim_of("f"));
    let start = ReducedState { u: vec![0.0; mu], f: vec![0.0; mf], g: g0 };
    step_through(fluid, start, frames, &mut |t| Ok((motion.geometry(schedule.at(t))?, None)), on_frame)
}

/// Training run `k`'s trajectory in `model`, or an error naming the motion asked for (`what`,
/// e.g. `computed:7`) and the runs the model has.
pub fn trajectory<'a>(
    model: &'a ReducedFluidModel,
    k: usize,
    what: &str,
) -> Result<&'a Trajectory, FluidError> {
    model.trajectories.get(k).ok_or_else(|| {
        FluidError::State(format!(
            "{what}: the model has training runs 0 to {}",
            model.trajectories.len().saturating_sub(1)
        ))
    })
}

/// A frame's ĝ and, when replayed, its ĥ.
type FrameMotion = (Vec<f64>, Option<Vec<f64>>);

/// The reduced steps from `start`: `motion(t)` gives frame t's ĝ and, when replayed, its ĥ
/// (otherwise ĥ comes from the reduced induced-flux tensor).
fn step_through(
    fluid: &ReducedFluid,
    start: ReducedState,
    frames: usize,
    motion: &mut dyn FnMut(usize) -> Result<FrameMotion, FluidError>,
    on_frame: &mut dyn FnMut(usize),
) -> Result<ReducedRun, FluidError> {
    let (_, _, _, mh) = fluid.dims();
    let mut state = start;
    let mut run = ReducedRun { states: vec![state.clone()], h: vec![vec![0.0; mh]], reports: Vec::new() };
    for t in 0..frames {
        let (g1, replayed) = motion(t + 1)?;
        let h1 = match replayed {
            Some(h) => h,
            None if mh == 0 => Vec::new(),
            None => fluid.induced_flux(&state.g, &g1).ok_or_else(|| {
                FluidError::State(
                    "a computed motion: the model has no induced-flux tensor H (retrain it)".into(),
                )
            })?,
        };
        let (next, report) = fluid.step(&state, &g1, &h1).map_err(|e| match e {
            FluidError::State(m) => FluidError::State(format!("reduced frame {}: {m}", t + 1)),
            other => other,
        })?;
        state = next;
        run.states.push(state.clone());
        run.h.push(h1);
        run.reports.push(report);
        on_frame(t + 1);
    }
    Ok(run)
}

/// Writes a reduced run lifted to the full space (`u = B_u û`, `f = B_f f̂`, `g = B_g ĝ`,
/// `h = B_h ĥ`, `p = V(g) u`) as a snapshot directory.
pub fn write_lifted(
    model: &ReducedFluidModel,
    run: &ReducedRun,
    dir: &Path,
    overwrite: bool,
) -> Result<(), FluidError> {
    let basis =
        |n: &str| model.basis(n).ok_or_else(|| FluidError::State(format!("the model has no basis {n}")));
    let (bu, bf, bg) = (basis("u")?, basis("f")?, basis("g")?);
    let bh: Option<&Basis> = model.basis("h");
    let (_, topo) = model.mesh_and_topology()?;
    let mesh = SimplexMesh::new(model.dim, bg.lift(&run.states[0].g), model.cells.clone())?;
    let fp = &model.provenance.mesh;
    let mut meta = SnapshotMeta::new(&mesh, &topo, model.frame_time, fp.periodic_axis);
    meta.viscosity = Some(model.viscosity);
    meta.forcing = Some([0.0; 3]);
    let mut writer = SnapshotWriter::create(dir, meta, mesh.cells(), overwrite)?;
    let d = model.dim;
    for (s, h) in run.states.iter().zip(&run.h) {
        let g = bg.lift(&s.g);
        let u = bu.lift(&s.u);
        let vols = mesh.volumes_at(&g);
        let p: Vec<f64> = u.iter().enumerate().map(|(i, v)| vols[i / d] * v).collect();
        let h = match bh {
            Some(b) => b.lift(h),
            None => vec![0.0; topo.face_count()],
        };
        writer.push(&u, &p, &bf.lift(&s.f), &g, &h)?;
    }
    Ok(())
}
