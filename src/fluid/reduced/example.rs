//! The small tunnel used wherever a reduced model is wanted quickly (the demo, the energy
//! benchmark, tests): `scenes/fluid/tunnel_small.toml`, built in, at the obstacle scales the
//! §7.1 study trains on (0.6 and 1.4).

use std::path::{Path, PathBuf};

use crate::fluid::run::{simulate_run, RunSummary};
use crate::fluid::scene::FluidScene;
use crate::fluid::FluidError;

/// The obstacle scales of the training runs (§7.1: small and large obstacles).
pub const TRAINING_SCALES: [f64; 2] = [0.6, 1.4];

/// `scenes/fluid/tunnel_small.toml` (built in) with its obstacle at `scale`.
pub fn small_tunnel(scale: f64) -> Result<FluidScene, FluidError> {
    let text = include_str!("../../../scenes/fluid/tunnel_small.toml")
        .replace("scale = 1.0", &format!("scale = {scale}"));
    FluidScene::parse(&text, Path::new("scenes/fluid/tunnel_small.toml"))
}

/// The small tunnel simulated for `frames` frames at each of [`TRAINING_SCALES`] into
/// `dir/tunnel-<scale>`: the run directories and their summaries.
pub fn small_tunnel_runs(dir: &Path, frames: usize) -> Result<(Vec<PathBuf>, Vec<RunSummary>), FluidError> {
    let (mut runs, mut summaries) = (Vec::new(), Vec::new());
    for scale in TRAINING_SCALES {
        let mut scene = small_tunnel(scale)?;
        let out = dir.join(format!("tunnel-{scale}"));
        summaries.push(simulate_run(&mut scene, frames, &out, true, &mut |_, _, _, _| {})?);
        runs.push(out);
    }
    Ok((runs, summaries))
}
