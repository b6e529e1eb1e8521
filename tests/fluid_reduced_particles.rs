//! Marker particles from the reduced state (seed 000 §6.5, Eq. 13): the CPU f64 reference
//! (`ReducedParticles`, which evaluates only the `B_g` rows of the vertices and the `B_f` rows
//! of the faces of the cells a particle visits) against particles advected in the lifted full
//! state, and the device pass in reduced mode against that reference — in 2D and 3D, on the
//! waving channel whose mesh moves every frame, with `B_f` split over two storage bindings.

mod common;

use std::path::Path;

use galerkin::fluid::gpu::GpuParticles;
use galerkin::fluid::particles::{advect_particles, seed_particles, Particle};
use galerkin::fluid::reduced::particles::ReducedParticles;
use galerkin::fluid::reduced::{
    run_reduced, BasisSizes, ReducedFluid, ReducedFluidModel, ReducedMotion, ReducedRun, TrainingSet,
};
use galerkin::fluid::FluidError;

/// Frames of the replay the particles ride through.
const FRAMES: usize = 20;
/// The channel's period along x.
const PERIOD: f64 = 2.0;

/// A model of two waving-channel runs in `dim` dimensions and its replay of run 1.
fn model_and_run(dir: &Path, dim: usize) -> (ReducedFluidModel, ReducedRun) {
    let runs = common::wavy::two_runs(dir, dim);
    let set = TrainingSet::open(&runs).expect("training set");
    let sizes = BasisSizes { energy: 1.0 - 1e-8, ..BasisSizes::default() };
    let model = ReducedFluidModel::fit(&set, &sizes, &mut |_| {}).expect("model");
    let fluid = ReducedFluid::new(&model).expect("reduced fluid");
    let run = run_reduced(&model, &fluid, ReducedMotion::Replay(1), FRAMES, &mut |_| {}).expect("replay");
    (model, run)
}

/// Distance between two positions, the x axis periodic.
fn distance(a: &Particle, b: &Particle, dim: usize) -> f64 {
    (0..dim)
        .map(|k| {
            let d = (a.position[k] - b.position[k]).abs();
            if k == 0 {
                d.min((d - PERIOD).abs())
            } else {
                d
            }
        })
        .fold(0.0, f64::max)
}

#[test]
fn reduced_particles_follow_particles_in_the_lifted_full_state_2d_and_3d() {
    let dir = tempfile::tempdir().expect("temp dir");
    for dim in [2, 3] {
        let (model, run) = model_and_run(dir.path(), dim);
        let particles = ReducedParticles::new(&model).expect("particles");
        let (bg, bf) = (model.basis("g").unwrap(), model.basis("f").unwrap());
        let start = seed_particles(particles.mesh(), 400);
        let (mut reduced, mut full) = (start.clone(), start);
        let dt = model.frame_time;
        let mut moved = 0.0f64;
        for t in 1..=FRAMES {
            let (s0, s1) = (&run.states[t - 1], &run.states[t]);
            let report = particles.advect(&s0.g, &s1.g, &s1.f, dt, 10, &mut reduced).expect("reduced advect");
            let lifted = (bg.lift(&s0.g), bg.lift(&s1.g), bf.lift(&s1.f));
            let before = full.clone();
            advect_particles(
                particles.mesh(),
                particles.topology(),
                &lifted.0,
                &lifted.1,
                &lifted.2,
                dt,
                10,
                &mut full,
            );
            moved = moved.max(before.iter().zip(&full).map(|(a, b)| distance(a, b, dim)).fold(0.0, f64::max));
            assert!(report.walked > 0, "{dim}D frame {t}: the walk ran");
        }
        let worst = reduced.iter().zip(&full).map(|(a, b)| distance(a, b, dim)).fold(0.0f64, f64::max);
        let same_cell = reduced.iter().zip(&full).filter(|(a, b)| a.cell == b.cell).count();
        eprintln!("{dim}D: worst distance {worst:.2e} after {FRAMES} frames (particles moved up to {moved:.2e} a frame)");
        // The same arithmetic in another order — Σ_j B_ij (ĝ0_j + t(ĝ1_j − ĝ0_j)) against the
        // lifted g0 + t(g1 − g0) — differs by rounding, ~1e-15 of the coordinates per
        // evaluation, over 200 substeps: 1e-10 (measured ~1e-15). A particle would have to come
        // within that of a face to take another cell.
        assert!(worst < 1e-10, "{dim}D: reduced particles off the lifted state's by {worst}");
        assert_eq!(same_cell, reduced.len(), "{dim}D: every particle in the same cell");
        assert!(moved > 1e-3, "{dim}D: the flow moved the particles ({moved})");
    }
}

#[test]
fn the_device_pass_on_the_reduced_state_follows_its_cpu_reference() {
    let dir = tempfile::tempdir().expect("temp dir");
    for dim in [2, 3] {
        let (model, run) = model_and_run(dir.path(), dim);
        let reference = ReducedParticles::new(&model).expect("particles");
        let b_f_bytes = 4 * reference.flux_basis().data().len() as u64;
        // One binding a little over half of B_f, enough for every other buffer: the pass
        // splits B_f over its two bindings.
        let (_, _, _, grid_start, grid_cells) = reference.grid().parts();
        let others = [
            4 * grid_start.len() as u64,
            4 * grid_cells.len() as u64,
            4 * reference.geometry_basis().data().len() as u64,
            4 * 4 * reference.mesh().cell_count() as u64,
        ];
        let binding = others.into_iter().fold(b_f_bytes * 6 / 10, u64::max).div_ceil(256) * 256;
        assert!(binding < b_f_bytes, "{dim}D: B_f ({b_f_bytes} bytes) fits one binding of {binding}");
        for limit in [None, Some(binding)] {
            let gpu = common::gpu_with(|d| d.max_binding_bytes = limit);
            // 500 particles: their buffer (8 kB) fits the small binding too.
            let mut particles = seed_particles(reference.mesh(), 500);
            let mut device = GpuParticles::new_reduced(&gpu, &reference, &particles).expect("upload");
            let dt = model.frame_time;
            let (mut close, mut total, mut worst, mut fastest) = (0usize, 0usize, 0.0f64, 0.0f64);
            for t in 1..=FRAMES {
                let (s0, s1) = (&run.states[t - 1], &run.states[t]);
                device.upload(&gpu, &particles).expect("same start");
                let mut cpu = particles.clone();
                reference.advect(&s0.g, &s1.g, &s1.f, dt, 10, &mut cpu).expect("reference");
                device.advect_reduced(&gpu, &s0.g, &s1.g, &s1.f, dt, 10).expect("device advect");
                let on_device = device.download(&gpu).expect("download");
                for ((c, g), p) in cpu.iter().zip(&on_device).zip(&particles) {
                    let e = distance(c, g, dim);
                    total += 1;
                    close += usize::from(e < 1e-5);
                    worst = worst.max(e);
                    fastest = fastest.max(distance(c, p, dim));
                }
                particles = cpu;
            }
            eprintln!(
                "{dim}D, binding {limit:?}: {close} of {total} device particles within 1e-5 of the CPU; worst {worst:.2e} (one frame's largest travel {fastest:.2e})"
            );
            // f32 against f64 over 10 substeps: positions round at ~1e-7, the reduced sums of
            // m terms at ~m·6e-8 relative: 1e-5. A particle within f32 rounding of a face may
            // take the neighbour's velocity for a substep: at most 1 %, and off by no more
            // than one frame's travel.
            assert!(close * 100 >= total * 99, "{dim}D: {close} of {total} close");
            assert!(worst <= fastest.max(1e-5), "{dim}D: worst {worst} beyond a frame's travel {fastest}");
        }
    }
}

#[test]
fn bad_reduced_frames_and_particles_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (model, run) = model_and_run(dir.path(), 2);
    let mut particles = ReducedParticles::new(&model).expect("particles");
    let s = &run.states[1];
    let mut p = seed_particles(particles.mesh(), 10);
    let short = &s.g[..s.g.len() - 1];
    let e = particles.advect(short, &s.g, &s.f, 0.02, 10, &mut p).unwrap_err();
    assert!(matches!(&e, FluidError::State(m) if m.contains("ĝ of")), "{e}");
    p[3].cell = u32::MAX;
    let e = particles.advect(&s.g, &s.g, &s.f, 0.02, 10, &mut p).unwrap_err();
    assert!(matches!(&e, FluidError::State(m) if m.contains("particle 3")), "{e}");
    // The training motions are covered; a geometry twice as large is not, until the boxes grow.
    assert!(run.states.iter().all(|st| particles.covers(&st.g)));
    let doubled: Vec<f64> = s.g.iter().map(|x| 2.0 * x).collect();
    assert!(!particles.covers(&doubled));
    particles.widen(&doubled);
    assert!(particles.covers(&doubled));
    // A B_f larger than two storage bindings is refused before anything is uploaded.
    let gpu = common::gpu_with(|d| d.max_binding_bytes = Some(256));
    let start = seed_particles(particles.mesh(), 10);
    let e = GpuParticles::new_reduced(&gpu, &particles, &start).err().expect("refused");
    assert!(matches!(&e, FluidError::State(m) if m.contains("two storage bindings")), "{e}");
}
