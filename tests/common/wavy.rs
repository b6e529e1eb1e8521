//! A periodic channel whose wall at y = 1 waves, `δ(x, t) = a sin(2πx/L) sin(2πt/T)`, the
//! interior following linearly in y: the enclosed volume is constant (Σ sin over a period is
//! zero), cells change volume, the moving wall's faces carry induced flux. 2D or 3D, for
//! the reduced fluid's moving-mesh tests.

use std::f64::consts::PI;
use std::path::Path;

use galerkin::fluid::run::{simulate_with, RunSetup};
use galerkin::fluid::FluidParams;
use galerkin::mesh::kuhn::kuhn_box;
use galerkin::mesh::{Periodic, SimplexMesh, Topology};

/// The channel's base mesh and topology (periodic in x), `n` cells across.
pub fn channel(dim: usize, n: usize) -> (SimplexMesh, Topology) {
    let counts = if dim == 2 { [2 * n, n, 0] } else { [2 * n, n, n] };
    let mesh = kuhn_box(dim, counts, [2.0, 1.0, 1.0]).expect("box");
    let topo = Topology::new(&mesh, Some(Periodic { axis: 0 })).expect("topology");
    (mesh, topo)
}

/// The channel's geometry at frame `frame` with amplitude `a` and period `period` frames.
pub fn geometry(mesh: &SimplexMesh, a: f64, period: f64, frame: usize) -> Vec<f64> {
    let d = mesh.dim();
    let s = (2.0 * PI * frame as f64 / period).sin();
    let mut g = mesh.g().to_vec();
    for v in 0..mesh.vertex_count() {
        let p = mesh.point(v);
        g[d * v + 1] += p[1] * a * (2.0 * PI * p[0] / 2.0).sin() * s;
    }
    g
}

/// Simulates `frames` frames of the waving channel (flow from `u0` per axis) into `out`.
pub fn simulate(dim: usize, n: usize, a: f64, period: f64, u0: [f64; 3], frames: usize, out: &Path) {
    let (mesh, topology) = channel(dim, n);
    let initial_velocity: Vec<f64> = (0..mesh.cell_count()).flat_map(|_| u0[..dim].to_vec()).collect();
    let setup = RunSetup {
        mesh: mesh.clone(),
        topology,
        params: FluidParams { viscosity: 1e-3, forcing: [0.0; 3], frame_time: 0.02 },
        initial_velocity,
        periodic_axis: Some(0),
    };
    simulate_with(
        &setup,
        frames,
        &mut |k| Ok(geometry(&mesh, a, period, k)),
        out,
        true,
        &mut |_, _, _, _| {},
    )
    .expect("simulated");
}

/// Two waving-channel runs (different flows) in `dim` dimensions, 30 frames each, written
/// below `dir`: the training set of the reduced fluid's moving-mesh tests.
pub fn two_runs(dir: &Path, dim: usize) -> Vec<std::path::PathBuf> {
    let n = if dim == 2 { 8 } else { 3 };
    [[1.0, 0.0, 0.0], [0.5, 0.2, 0.1]]
        .iter()
        .enumerate()
        .map(|(k, u0)| {
            let out = dir.join(format!("wavy{dim}-{k}"));
            simulate(dim, n, 0.08, 20.0, *u0, 30, &out);
            out
        })
        .collect()
}
