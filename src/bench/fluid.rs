//! `galerkin fluid bench`: Table 1 of seed 000 on this machine — full-space seconds per step
//! (deformation, advection, projection) on the deforming cavity and the flying bird from 10³
//! to 3·10⁵ cells, next to the paper's, and particle advection on the CPU and the device.

use std::time::Instant;

use anyhow::Result;

use crate::fluid::gpu::GpuParticles;
use crate::fluid::particles::{advect_particles, seed_particles};
use crate::fluid::FluidSolver;
use crate::gpu::Gpu;
use crate::mesh::budget::CellBudget;
use crate::mesh::{SimplexMesh, Topology};

/// A line of Markdown through `emit`.
macro_rules! say {
    ($emit:expr, $($t:tt)*) => { $emit(&format!("{}\n", format_args!($($t)*))) };
}

/// Table 1 of seed 000: full-space seconds per step (deformation, advection, projection) and
/// particle advection, for the cavity (88,671 cells) and the eagle (300,217 cells).
const PAPER: [(&str, usize, f64, f64, f64); 2] =
    [("cavity", 88_671, 2.17, 18.4, 220.0), ("eagle", 300_217, 2.92, 18.9, 82.0)];
const PAPER_PARTICLES_S: f64 = 0.308;

/// One size of the benchmark: per-stage medians and what the particle pass needs.
struct BenchRow {
    cells: usize,
    td: f64,
    ta: f64,
    tp: f64,
    mesh: SimplexMesh,
    topo: Topology,
    state: crate::fluid::FluidState,
}

/// Steps `frames` frames (from `first + 1`) of a moving mesh whose geometry `geometry`
/// gives, printing one table row; `setup` started before the mesh was built.
fn bench_row(
    mesh: SimplexMesh,
    topo: Topology,
    frames: usize,
    first: usize,
    setup: Instant,
    mut geometry: impl FnMut(usize) -> Result<Vec<f64>>,
    emit: &mut dyn FnMut(&str),
) -> Result<BenchRow> {
    let params = crate::fluid::FluidParams { viscosity: 1e-3, forcing: [0.0; 3], frame_time: 0.02 };
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), params)?;
    let setup = setup.elapsed().as_secs_f64();
    let g0 = geometry(first)?;
    let mut state = solver.initial_state(g0, &vec![0.0; 3 * mesh.cell_count()])?;
    let (mut td, mut ta, mut tp) = (Vec::new(), Vec::new(), Vec::new());
    let (mut substeps, mut cg_steps) = (0, Vec::new());
    for frame in first + 1..=first + frames {
        let t = Instant::now();
        let g = geometry(frame)?;
        td.push(t.elapsed().as_secs_f64());
        let (next, report) = solver.step(&state, &g, frame)?;
        ta.push(report.advection_seconds);
        tp.push(report.projection_seconds);
        substeps = report.substeps;
        cg_steps.push(report.projection.cg_steps as f64);
        state = next;
    }
    let median = crate::bench::median_f64;
    let row = BenchRow {
        cells: mesh.cell_count(),
        td: median(&mut td),
        ta: median(&mut ta),
        tp: median(&mut tp),
        mesh,
        topo,
        state,
    };
    say!(
        emit,
        "| {} | {} | {} | {setup:.2} | {:.4} | {:.4} ({substeps}) | {:.3} ({:.0}) | {:.0} |",
        row.cells,
        row.topo.face_count(),
        row.mesh.vertex_count(),
        row.td,
        row.ta,
        row.tp,
        median(&mut cg_steps),
        solver.projection_memory_len() as f64 * 8.0 / 1e6
    );
    Ok(row)
}

/// The table's header.
const HEADER: &str = "| cells | faces | vertices | setup s | t_d s | t_a s (substeps) | t_p s (CG steps) | projection MB |\n|---:|---:|---:|---:|---:|---:|---:|---:|";

/// Per-stage times of the full-space step on the deforming cavity and on the flying bird at
/// sizes from 10³ to 3·10⁵ cells (`quick`: three small ones), medians of `frames` frames, next
/// to Table 1, and particle advection on the CPU and on `gpu`, as Markdown through `emit`.
pub fn report(gpu: &Gpu, quick: bool, frames: usize, emit: &mut dyn FnMut(&str)) -> Result<()> {
    use crate::fluid::bird::BirdSpec;
    use crate::fluid::cavity::{training_run, Cavity, CavitySpec};
    use crate::fluid::embedded::{Embedded, EmbeddedSpec};
    let spacings: &[f64] = if quick { &[0.3, 0.2, 0.14] } else { &[0.4, 0.2, 0.135, 0.09, 0.0605] };
    let bird_spacings: &[f64] = if quick { &[0.25] } else { &[0.25, 0.2, 0.14, 0.1025] };
    let frames = frames.max(2);
    say!(emit, "device: {} ({})", gpu.caps().device_name, gpu.caps().driver);
    say!(emit, "");
    say!(emit, "The deforming cavity, training run 0 (frames 1.., the first small cavity compressing):");
    say!(emit, "\n{HEADER}");
    let mut rows = Vec::new();
    for &h in spacings {
        let spec = CavitySpec { spacing: h, tunnel_radius: 0.16f64.max(1.1 * h), ..CavitySpec::default() };
        let t0 = Instant::now();
        let mut cavity = Cavity::new(&spec, &CellBudget::machine())?;
        let (mesh, topo) = (cavity.mesh.clone(), cavity.topology.clone());
        let amounts = training_run(0).unwrap_or([0.3, 0.0, 0.0]);
        let geometry = |frame: usize| -> Result<Vec<f64>> {
            Ok(cavity.geometry(Cavity::compression(amounts, frame, 20), frame)?)
        };
        rows.push(bench_row(mesh, topo, frames, 0, t0, geometry, emit)?);
    }
    say!(emit, "");
    say!(emit, "The flying bird (box [-1.4, 1.4] × [-1.8, 1.8] × [-1.3, 1.3], frames 8.., wings beating):");
    say!(emit, "\n{HEADER}");
    let mut bird_rows = Vec::new();
    let animation = BirdSpec::default().animation();
    for &h in bird_spacings {
        let spec = EmbeddedSpec { lo: [-1.4, -1.8, -1.3], hi: [1.4, 1.8, 1.3], spacing: h, base_frame: 0 };
        let t0 = Instant::now();
        let mut domain = Embedded::new(animation.clone(), &spec, &CellBudget::machine())?;
        let (mesh, topo) = (domain.mesh.clone(), domain.topology.clone());
        bird_rows.push(bench_row(mesh, topo, frames, 8, t0, |frame| Ok(domain.geometry(frame)?), emit)?);
    }
    say!(emit, "");
    say!(emit, "Against Table 1 (the paper's times over ours at the nearest size; goal ≥ 10×):");
    say!(emit, "");
    say!(emit, "| paper row | paper cells | our cells | t_d ratio | t_a ratio | t_p ratio |");
    say!(emit, "|---|---:|---:|---:|---:|---:|");
    for ((name, cells, pd, pa, pp), ours) in PAPER.into_iter().zip([&rows, &bird_rows]) {
        if let Some(r) = ours.iter().min_by_key(|r| (r.cells as i64 - cells as i64).abs()) {
            let c = r.cells;
            say!(
                emit,
                "| {name} | {cells} | {c} | {:.0}× | {:.0}× | {:.0}× |",
                pd / r.td,
                pa / r.ta,
                pp / r.tp
            );
        }
    }
    // Particles: 10,000 in the cavity nearest the paper's size, one frame of 10 substeps.
    if let Some(BenchRow { mesh, topo, state, .. }) =
        rows.iter().min_by_key(|r| (r.cells as i64 - 88_671).abs())
    {
        let seeds = seed_particles(mesh, 10_000);
        let mut cpu_times = Vec::new();
        let mut dev_times = Vec::new();
        let mut device = GpuParticles::new(gpu, mesh, topo, &seeds)?;
        for _ in 0..3 {
            let mut p = seeds.clone();
            let t = Instant::now();
            advect_particles(mesh, topo, &state.g, &state.g, &state.f, 0.02, 10, &mut p);
            cpu_times.push(t.elapsed().as_secs_f64());
            device.upload(gpu, &seeds)?;
            let t = Instant::now();
            device.advect(gpu, mesh, &state.g, &state.g, &state.f, 0.02, 10)?;
            dev_times.push(t.elapsed().as_secs_f64());
        }
        let (c, d) = (crate::bench::median_f64(&mut cpu_times), crate::bench::median_f64(&mut dev_times));
        say!(emit, "");
        say!(
            emit,
            "Particles: 10,000 in {} cells, one frame of 10 Euler substeps: CPU {c:.4} s, device {d:.4} s (paper t_pa {PAPER_PARTICLES_S} s: {:.0}× and {:.0}×)",
            mesh.cell_count(),
            PAPER_PARTICLES_S / c,
            PAPER_PARTICLES_S / d
        );
    }
    drop((rows, bird_rows));
    Ok(())
}
