//! The small periodic tunnel simulated for a few frames: training runs for the fluid tests.

use std::path::{Path, PathBuf};

use galerkin::fluid::reduced::example::small_tunnel;

/// The small tunnel at an obstacle scale, simulated for `frames` frames into `dir`.
pub fn tunnel_run(dir: &Path, scale: f64, frames: usize) -> PathBuf {
    let mut scene = small_tunnel(scale).expect("scene");
    let out = dir.join(format!("tunnel-{scale}"));
    galerkin::fluid::run::simulate_run(&mut scene, frames, &out, true, &mut |_, _, _, _| {}).expect("run");
    out
}
