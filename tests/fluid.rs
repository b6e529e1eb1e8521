//! The full-space fluid of seed 000 §5 on the CPU: the tensors against their per-cell
//! evaluation, the conventions (uniform flow exactness, skew advection, dissipative
//! diffusion, swept volumes against volume change), the projection's properties, steps on a
//! moving mesh, scenes and snapshots.
//!
//! Tolerances: quantities computed by different orders of floating-point sums of O(1) terms
//! agree to ~1e-13 (we allow 1e-12 relative); the projection is conjugate gradients on the
//! hybridised face system converged to 1e-12 of the flux scale, so its velocities agree to
//! 1e-10 relative (the divergence bound).
#![allow(clippy::needless_range_loop)]

use galerkin::fluid::operators::{
    add_laplacian, advect, advection_tensor, divergence, flux_to_momentum_tensor, laplacian_tensor,
    uniform_flux, volume_tensor, CellOperators,
};
use galerkin::fluid::projection::Projection;
use galerkin::fluid::scene::FluidScene;
use galerkin::fluid::snapshots::{SnapshotMeta, SnapshotReader, SnapshotWriter};
use galerkin::fluid::{FluidError, FluidParams, FluidSolver, FluidState};
use galerkin::mesh::kuhn::kuhn_box;
use galerkin::mesh::{Periodic, SimplexMesh, Topology};
use galerkin::reduce::SnapshotSource;

/// A deterministic pseudo-random sequence in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// `mesh` with its interior vertices (off every side of the bounding box) moved by up to
/// `amount` of a cell.
fn jiggle(mesh: &SimplexMesh, amount: f64, seed: u64) -> Vec<f64> {
    let d = mesh.dim();
    let (lo, hi) = mesh.bounds();
    let mut rng = Lcg(seed);
    let mut g = mesh.g().to_vec();
    for v in 0..mesh.vertex_count() {
        let p = mesh.point(v);
        if (0..d).any(|k| (p[k] - lo[k]).abs() < 1e-12 || (p[k] - hi[k]).abs() < 1e-12) {
            continue;
        }
        for k in 0..d {
            g[d * v + k] += amount * rng.next();
        }
    }
    g
}

fn channel(dim: usize, n: usize) -> (SimplexMesh, Topology) {
    let counts = if dim == 2 { [2 * n, n, 0] } else { [2 * n, n, n] };
    let base = kuhn_box(dim, counts, [2.0, 1.0, 1.0]).expect("box");
    let h = 1.0 / n as f64;
    let mesh = base.with_g(jiggle(&base, 0.2 * h, 7), None).expect("jiggled");
    let topo = Topology::new(&mesh, Some(Periodic { axis: 0 })).expect("topology");
    (mesh, topo)
}

fn max_abs(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

fn energy(vols: &[f64], u: &[f64], d: usize) -> f64 {
    vols.iter().enumerate().map(|(c, v)| 0.5 * v * (0..d).map(|k| u[d * c + k].powi(2)).sum::<f64>()).sum()
}

#[test]
fn the_tensors_agree_with_the_per_cell_operators_in_2d_and_3d() {
    for dim in [2, 3] {
        let (mesh, topo) = channel(dim, if dim == 2 { 4 } else { 2 });
        let g = mesh.g().to_vec();
        let ops = CellOperators::new(&mesh, &topo, &g);
        let nc = mesh.cell_count();
        let mut rng = Lcg(3);
        let u: Vec<f64> = (0..dim * nc).map(|_| rng.next()).collect();
        let f: Vec<f64> = (0..topo.face_count()).map(|_| rng.next()).collect();
        // V ⊗ u ⊗ g … g = vol · u.
        let vt = volume_tensor(&mesh);
        let mut args: Vec<(usize, &[f64])> = vec![(1, &u)];
        for axis in 2..2 + dim {
            args.push((axis, &g));
        }
        let p = vt.contract_axes("V", &args).expect("contract V");
        for c in 0..nc {
            for k in 0..dim {
                let want = ops.volumes[c] * u[dim * c + k];
                assert!((p.data()[dim * c + k] - want).abs() < 1e-12, "{dim}D volume tensor, cell {c}");
            }
        }
        // (P ⊗₂ g) f.
        let pt = flux_to_momentum_tensor(&mesh, &topo);
        let pm = pt.contract_axes("P", &[(1, &f), (2, &g)]).expect("contract P");
        let direct = ops.flux_to_momentum(&topo, &f);
        assert!(pm.data().iter().zip(&direct).all(|(a, b)| (a - b).abs() < 1e-12), "{dim}D P");
        // (A ⊗₂ f) u.
        let at = advection_tensor(&topo);
        let am = at.contract_axes("A", &[(1, &u), (2, &f)]).expect("contract A");
        let mut direct = vec![0.0; dim * nc];
        advect(&topo, &f, &u, &mut direct);
        assert!(am.data().iter().zip(&direct).all(|(a, b)| (a - b).abs() < 1e-12), "{dim}D A");
        // Δ u.
        let lt = laplacian_tensor(&topo);
        let lm = lt.contract_axes("Δ", &[(1, &u)]).expect("contract Δ");
        let mut direct = vec![0.0; dim * nc];
        add_laplacian(&topo, &u, 1.0, &mut direct);
        assert!(lm.data().iter().zip(&direct).all(|(a, b)| (a - b).abs() < 1e-12), "{dim}D Δ");
        // Diffusion dissipates: uᵀΔu < 0 for a non-constant u.
        let dot: f64 = u.iter().zip(&direct).map(|(a, b)| a * b).sum();
        assert!(dot < 0.0, "{dim}D: uᵀΔu = {dot} must be negative (Eq. 9 with the dissipative sign)");
    }
}

#[test]
fn uniform_flow_is_reproduced_exactly_by_flux_to_velocity() {
    for dim in [2, 3] {
        let (mesh, topo) = channel(dim, if dim == 2 { 6 } else { 3 });
        let velocity = [0.7, -0.3, 0.45];
        let f = uniform_flux(&mesh, &topo, velocity);
        let ops = CellOperators::new(&mesh, &topo, mesh.g());
        let u = ops.flux_to_velocity(&topo, &f);
        for c in 0..mesh.cell_count() {
            for k in 0..dim {
                assert!(
                    (u[dim * c + k] - velocity[k]).abs() < 1e-12,
                    "{dim}D cell {c} axis {k}: {}",
                    u[dim * c + k]
                );
            }
        }
        // A uniform flux is divergence-free.
        assert!(max_abs(&divergence(&topo, &f)) < 1e-13);
    }
}

#[test]
fn advection_is_skew_for_divergence_free_fluxes() {
    let (mesh, topo) = channel(2, 8);
    let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time: 0.01 };
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), params).expect("solver");
    let mut rng = Lcg(11);
    let d = 2;
    let random: Vec<f64> = (0..d * mesh.cell_count()).map(|_| rng.next()).collect();
    let state = solver.initial_state(mesh.g().to_vec(), &random).expect("projected");
    let u: Vec<f64> = (0..d * mesh.cell_count()).map(|_| rng.next()).collect();
    let mut au = vec![0.0; u.len()];
    advect(&topo, &state.f, &u, &mut au);
    let skew: f64 = u.iter().zip(&au).map(|(a, b)| a * b).sum();
    let scale: f64 = state.f.iter().map(|f| f.abs()).sum::<f64>() * max_abs(&u).powi(2);
    assert!(skew.abs() < 1e-12 * scale, "uᵀ(A⊗f)u = {skew:e} (scale {scale:e})");
    // A flux with divergence is not skew: the conventions are what makes it vanish.
    let mut g = state.f.clone();
    g[0] += 1.0;
    advect(&topo, &g, &u, &mut au);
    let not_skew: f64 = u.iter().zip(&au).map(|(a, b)| a * b).sum();
    assert!(not_skew.abs() > 1e-6);
}

#[test]
fn induced_fluxes_sweep_exactly_the_change_of_cell_volumes() {
    for dim in [2, 3] {
        let (mesh, topo) = channel(dim, if dim == 2 { 6 } else { 2 });
        let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time: 0.25 };
        let solver = FluidSolver::new(mesh.clone(), topo, params).expect("solver");
        let g1 = jiggle(&mesh, 0.15 / 6.0, 99);
        let h = solver.induced_flux(mesh.g(), &g1);
        let div = divergence(solver.topology(), &h);
        let (v0, v1) = (mesh.volumes(), mesh.volumes_at(&g1));
        for c in 0..mesh.cell_count() {
            let dv = v1[c] - v0[c];
            assert!(
                (div[c] * 0.25 - dv).abs() < 1e-14,
                "{dim}D cell {c}: Σσh·Δt = {} vs ΔV = {dv}",
                div[c] * 0.25
            );
        }
        // Only interior vertices moved: no flux through the boundary.
        assert!(solver.topology().boundary_faces().iter().all(|&f| h[f as usize].abs() < 1e-15));
    }
}

#[test]
fn the_projection_reproduces_uniform_flow_is_idempotent_and_never_adds_energy() {
    let (mesh, topo) = channel(2, 8);
    let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time: 0.01 };
    let mut solver = FluidSolver::new(mesh.clone(), topo, params).expect("solver");
    let d = 2;
    let nc = mesh.cell_count();
    let uniform: Vec<f64> = (0..nc).flat_map(|_| [1.0, 0.0]).collect();
    let s = solver.initial_state(mesh.g().to_vec(), &uniform).expect("projected");
    assert!(
        s.u.iter().zip(&uniform).all(|(a, b)| (a - b).abs() < 1e-10),
        "uniform flow along the walls survives"
    );
    let vols = mesh.volumes();
    let mut rng = Lcg(5);
    for trial in 0..3 {
        let u: Vec<f64> = (0..d * nc).map(|_| rng.next()).collect();
        let s1 = solver.initial_state(mesh.g().to_vec(), &u).expect("projection 1");
        let s2 = solver.initial_state(mesh.g().to_vec(), &s1.u).expect("projection 2");
        let diff = s1.u.iter().zip(&s2.u).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(diff < 1e-10 * max_abs(&s1.u), "trial {trial}: projection not idempotent ({diff:e})");
        let (e0, e1) = (energy(&vols, &u, d), energy(&vols, &s1.u, d));
        assert!(e1 <= e0 * (1.0 + 1e-12), "trial {trial}: energy {e0} → {e1}");
        let div = divergence(solver.topology(), &s1.f);
        let scale = s1.f.iter().map(|f| f.abs()).fold(0.0, f64::max);
        assert!(max_abs(&div) <= 1e-10 * scale, "trial {trial}: divergence {:e}", max_abs(&div));
        let walls: f64 = solver.topology().boundary_faces().iter().map(|&f| s1.f[f as usize].abs()).sum();
        assert!(walls <= 1e-10 * scale, "no flux through the walls");
    }
}

/// Eq. 10 solved plainly, densely and separately from the hybridised multigrid solve: the
/// flux minimising `½ fᵀKf − (Pᵀu)ᵀf` (K = PᵀV⁻¹P from the levers) over `C f = c` (every cell's
/// divergence zero, every wall face's flux h), as a particular solution plus the null space
/// of C from eigendecompositions.
fn dense_projection_reference(topo: &Topology, ops: &CellOperators, u: &[f64], h: &[f64]) -> Vec<f64> {
    use galerkin::tensor::{solve, symmetric_eigen, Tensor};
    let d = topo.dim();
    let (nf, nc) = (topo.face_count(), topo.cell_count());
    let mut k = vec![0.0; nf * nf];
    let mut b = vec![0.0; nf];
    for c in 0..nc {
        for l1 in 0..=d {
            let f1 = topo.cell_face(c, l1);
            b[f1] += (0..d).map(|i| ops.lever(c, l1, i) * u[d * c + i]).sum::<f64>();
            for l2 in 0..=d {
                let f2 = topo.cell_face(c, l2);
                k[f1 * nf + f2] +=
                    (0..d).map(|i| ops.lever(c, l1, i) * ops.lever(c, l2, i)).sum::<f64>() / ops.volumes[c];
            }
        }
    }
    let walls = topo.boundary_faces();
    let rows = nc + walls.len();
    let mut cm = vec![0.0; rows * nf];
    let mut rhs = vec![0.0; rows];
    for c in 0..nc {
        for l in 0..=d {
            cm[c * nf + topo.cell_face(c, l)] += topo.sign(c, l);
        }
    }
    for (i, &f) in walls.iter().enumerate() {
        cm[(nc + i) * nf + f as usize] = 1.0;
        rhs[nc + i] = h[i];
    }
    let gram = |a: &[f64], n: usize, m: usize, outer: bool| -> Tensor {
        // outer: a aᵀ (n × n, a is n × m); else aᵀ a (m × m).
        let size = if outer { n } else { m };
        let mut g = vec![0.0; size * size];
        for i in 0..size {
            for j in 0..size {
                g[i * size + j] = if outer {
                    (0..m).map(|t| a[i * m + t] * a[j * m + t]).sum()
                } else {
                    (0..n).map(|t| a[t * m + i] * a[t * m + j]).sum()
                };
            }
        }
        Tensor::from_vec(&[size, size], g).expect("square")
    };
    // Particular solution f_p = Cᵀ (C Cᵀ)⁺ c.
    let (lam, vecs) = symmetric_eigen("C Cᵀ", &gram(&cm, rows, nf, true)).expect("eigen");
    let top = lam.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut y = vec![0.0; rows];
    for (j, &l) in lam.iter().enumerate() {
        if l > 1e-10 * top {
            let proj: f64 = (0..rows).map(|i| vecs.data()[i * rows + j] * rhs[i]).sum::<f64>() / l;
            for i in 0..rows {
                y[i] += proj * vecs.data()[i * rows + j];
            }
        }
    }
    let fp: Vec<f64> = (0..nf).map(|f| (0..rows).map(|r| cm[r * nf + f] * y[r]).sum()).collect();
    // Null space of C, and the reduced normal equations on it.
    let (lam, vecs) = symmetric_eigen("CᵀC", &gram(&cm, rows, nf, false)).expect("eigen");
    let top = lam.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let null: Vec<usize> = (0..nf).filter(|&j| lam[j] <= 1e-10 * top).collect();
    let nn = null.len();
    let col = |j: usize, f: usize| vecs.data()[f * nf + null[j]];
    let kf: Vec<f64> = (0..nf).map(|i| (0..nf).map(|j| k[i * nf + j] * fp[j]).sum()).collect();
    let mut red = vec![0.0; nn * nn];
    let mut red_rhs = vec![0.0; nn];
    for a in 0..nn {
        let ka: Vec<f64> = (0..nf).map(|i| (0..nf).map(|j| k[i * nf + j] * col(a, j)).sum()).collect();
        for bb in 0..nn {
            red[bb * nn + a] = (0..nf).map(|f| col(bb, f) * ka[f]).sum();
        }
        red_rhs[a] = (0..nf).map(|f| col(a, f) * (b[f] - kf[f])).sum();
    }
    let z = solve("NᵀKN", &Tensor::from_vec(&[nn, nn], red).expect("square"), &red_rhs).expect("definite");
    (0..nf).map(|f| fp[f] + (0..nn).map(|a| col(a, f) * z[a]).sum::<f64>()).collect()
}

#[test]
fn the_projection_matches_a_dense_reference_in_2d_and_3d() {
    // Small jiggled boxes, periodic along x, random velocities and (on the 3D one) wall
    // fluxes with zero net volume. The multigrid solve stops at 1e-12 of the flux scale and
    // the reference's eigendecompositions lose a few digits to conditioning (~1e3 here), so
    // 1e-9 relative leaves a wide margin while a wrong sign or a missing term fails by O(1).
    for (dim, counts) in [(2, [6, 3, 0]), (3, [3, 2, 2])] {
        let base = kuhn_box(dim, counts, [2.0, 1.0, 1.0]).expect("box");
        let mesh = base.with_g(jiggle(&base, 0.08, 3), None).expect("jiggled");
        let topo = Topology::new(&mesh, Some(Periodic { axis: 0 })).expect("topology");
        let ops = CellOperators::new(&mesh, &topo, mesh.g());
        let mut rng = Lcg(11 + dim as u64);
        let u: Vec<f64> = (0..dim * mesh.cell_count()).map(|_| rng.next()).collect();
        let walls = topo.boundary_faces();
        let mut h: Vec<f64> =
            if dim == 3 { walls.iter().map(|_| 0.3 * rng.next()).collect() } else { vec![0.0; walls.len()] };
        // Zero net outward flux: remove the mean outward flux from every wall face.
        let sign = |f: u32| {
            topo.sign(topo.face_cells(f as usize)[0] as usize, topo.face_local(f as usize)[0] as usize)
        };
        let net: f64 = walls.iter().zip(&h).map(|(&f, v)| sign(f) * v).sum::<f64>() / walls.len() as f64;
        for (&f, v) in walls.iter().zip(h.iter_mut()) {
            *v -= sign(f) * net;
        }
        let mut projection = Projection::new(&topo).expect("projection");
        let (flux, report) = projection.project(&topo, &ops, &u, &h, 0).expect("projected");
        let reference = dense_projection_reference(&topo, &ops, &u, &h);
        let scale = max_abs(&reference);
        let err = flux.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(
            err <= 1e-9 * scale,
            "{dim}D: flux differs from the dense reference by {err:e} (scale {scale:e})"
        );
        assert!(report.relative_divergence < 1e-11, "{dim}D: divergence {:e}", report.relative_divergence);
        assert!(scale > 0.1, "{dim}D: a nontrivial flux");
    }
}

#[test]
fn uniform_flow_stays_uniform_on_a_moving_mesh_and_energy_never_grows() {
    // The −V̇u term and the exact swept volumes: a moving interior must not disturb a
    // uniform flow (seed 000 §5.4: "velocities do not translate simply because their
    // discretization element moves through space").
    let (mesh, topo) = channel(2, 6);
    let params = FluidParams { viscosity: 2e-3, forcing: [0.0; 3], frame_time: 0.05 };
    let mut solver = FluidSolver::new(mesh.clone(), topo, params).expect("solver");
    let nc = mesh.cell_count();
    let uniform: Vec<f64> = (0..nc).flat_map(|_| [0.8, 0.0]).collect();
    let mut state = solver.initial_state(mesh.g().to_vec(), &uniform).expect("start");
    for frame in 1..=6 {
        let g = jiggle(&mesh, 0.15 / 6.0, frame as u64);
        let (next, report) = solver.step(&state, &g, frame).expect("step");
        let err = next.u.iter().zip(&uniform).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(err < 1e-9, "frame {frame}: uniform flow disturbed by {err:e}");
        assert!(report.projection.relative_divergence < 1e-10);
        assert!(max_abs(&report.h) > 1e-3, "the mesh really moves");
        state = next;
    }
    // A random divergence-free flow on a static mesh, no viscosity: RK4 and the projection
    // may only lose energy.
    let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time: 0.05 };
    let mut solver = FluidSolver::new(mesh.clone(), solver.topology().clone(), params).expect("solver");
    let mut rng = Lcg(17);
    let u: Vec<f64> = (0..2 * nc).map(|_| rng.next()).collect();
    let mut state: FluidState = solver.initial_state(mesh.g().to_vec(), &u).expect("start");
    let mut e = solver.energy(&state);
    let e0 = e;
    for frame in 1..=10 {
        let (next, _) = solver.step(&state, mesh.g(), frame).expect("step");
        let e1 = solver.energy(&next);
        assert!(e1 <= e * (1.0 + 1e-12), "frame {frame}: energy grew {e} → {e1}");
        state = next;
        e = e1;
    }
    assert!(e > 0.1 * e0, "not all dissipated: {e0} → {e}");
}

#[test]
fn a_net_change_of_volume_is_refused_naming_the_frame() {
    // Moving a wall outward grows the domain: no incompressible flow fits.
    let base = kuhn_box(2, [4, 4, 0], [1.0, 1.0, 0.0]).expect("box");
    let topo = Topology::new(&base, None).expect("topology");
    let params = FluidParams { viscosity: 0.0, forcing: [0.0; 3], frame_time: 0.1 };
    let mut solver = FluidSolver::new(base.clone(), topo, params).expect("solver");
    let state = solver.initial_state(base.g().to_vec(), &vec![0.0; 2 * base.cell_count()]).expect("rest");
    let mut g = base.g().to_vec();
    for v in 0..base.vertex_count() {
        g[2 * v + 1] *= 1.1;
    }
    match solver.step(&state, &g, 3) {
        Err(FluidError::VolumeChange { frame: 3, .. }) => {}
        other => panic!("expected a refused volume change in frame 3, got {other:?}"),
    }
}

#[test]
fn tunnel_scenes_load_and_bad_keys_name_their_line() {
    let text = std::fs::read_to_string("scenes/fluid/tunnel_small.toml").expect("scene");
    let scene = FluidScene::parse(&text, std::path::Path::new("tunnel_small.toml")).expect("loads");
    assert!(scene.mesh.cell_count() > 200);
    let bad = text.replace("viscosity = ", "viscosity = -");
    let err = FluidScene::parse(&bad, std::path::Path::new("bad.toml"))
        .expect_err("negative viscosity")
        .to_string();
    let line = bad.lines().position(|l| l.starts_with("viscosity")).expect("key") + 1;
    assert!(err.contains(&format!("bad.toml:{line}:")), "{err}");
    let unknown = text.replace("[flow]", "[flow]\nspeed = 3");
    assert!(FluidScene::parse(&unknown, std::path::Path::new("u.toml")).is_err());
}

#[test]
fn snapshots_stream_back_by_frame_and_by_rows() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let (mesh, topo) = channel(2, 3);
    let meta = SnapshotMeta::new(&mesh, &topo, 0.1, Some(0));
    let mut w = SnapshotWriter::create(&dir, meta.clone(), mesh.cells(), false).expect("create");
    let (nu, nf, ng) = (2 * mesh.cell_count(), topo.face_count(), mesh.g().len());
    for k in 0..4 {
        let u: Vec<f64> = (0..nu).map(|i| (k * 1000 + i) as f64).collect();
        let f: Vec<f64> = (0..nf).map(|i| -((k * 1000 + i) as f64)).collect();
        w.push(&u, &u, &f, &mesh.g()[..ng], &f).expect("push");
    }
    assert!(w.push(&[1.0], &[1.0], &[1.0], &[1.0], &[1.0]).is_err(), "wrong lengths refused");
    assert!(SnapshotWriter::create(&dir, meta.clone(), mesh.cells(), false).is_err(), "no silent overwrite");
    // A second writer of the same directory while this one lives (two `fluid simulate --force`
    // at once) is refused before it truncates anything; after this one is gone it may.
    let e = SnapshotWriter::create(&dir, meta.clone(), mesh.cells(), true).expect_err("a second writer");
    assert!(e.to_string().contains("another run is writing"), "{e}");
    drop(w);
    let r = SnapshotReader::open(&dir).expect("open");
    assert_eq!(r.meta().frames, 4, "the refused writer truncated the run");
    drop(r);
    let second =
        SnapshotWriter::create(&scratch.path().join("other"), meta, mesh.cells(), true).expect("free");
    drop(second);
    let r = SnapshotReader::open(&dir).expect("open");
    assert_eq!(r.meta().frames, 4);
    assert_eq!(r.frame("u", 2).expect("frame")[5], 2005.0);
    let mut src = r.source("f").expect("source");
    assert_eq!((src.dim(), src.count()), (nf, 4));
    let rows = src.rows(3..6).expect("rows");
    assert_eq!(rows.get(&[1, 3]), -3004.0);
    assert!(r.frame("u", 9).is_err() && r.frame("q", 0).is_err());
}

#[test]
fn the_cavity_keeps_its_volume_and_every_training_run_stays_valid() {
    use galerkin::fluid::cavity::{training_run, Cavity, TRAINING_RUNS};
    use galerkin::mesh::volume::enclosed_volume;
    let mut scene = FluidScene::load(std::path::Path::new("scenes/fluid/cavity_small.toml")).expect("scene");
    let galerkin::fluid::scene::Motion::Cavity { cavity, .. } = &mut scene.motion else {
        panic!("a cavity scene");
    };
    let rest = cavity.rest_volume();
    let frames = 12;
    for run in 0..TRAINING_RUNS {
        let amounts = training_run(run).expect("run");
        // The deepest frame of every run: valid cells, the rest volume to 1e-12.
        let a = Cavity::compression(amounts, frames / 2, frames);
        let g = cavity.geometry(a, frames / 2).unwrap_or_else(|e| panic!("run {run}: {e}"));
        let m = cavity.mesh.with_g(g, None).expect("valid");
        let total: f64 = m.volumes().iter().sum();
        assert!((total - rest).abs() < 1e-12 * rest, "run {run}: volume {total} vs {rest}");
        let enclosed = enclosed_volume(&m, &cavity.topology, m.g());
        assert!((enclosed - total).abs() < 1e-12 * rest);
        // Every cell keeps at least the compressed cavity's own volume ratio (1 − a)³: the map
        // is a radial scaling whose Jacobian is at least that (its discrete cells within 10 %).
        let deepest = a.iter().copied().fold(0.0f64, f64::max);
        let smallest =
            m.volumes().iter().zip(cavity.mesh.volumes()).map(|(v, v0)| v / v0).fold(f64::INFINITY, f64::min);
        assert!(
            smallest >= 0.9 * (1.0 - deepest).powi(3),
            "run {run}: a cell keeps {smallest:.3} of its volume under compression {deepest}"
        );
        // The compressed cavity really is smaller.
        let i = (0..3).find(|&i| amounts[i] > 0.0).expect("one compressed");
        let c = cavity.spec().small_centres()[i];
        let r0 = cavity
            .surface
            .iter()
            .map(|&v| dist3(cavity.mesh.point(v as usize), c))
            .fold(f64::INFINITY, f64::min);
        let r1 = cavity.surface.iter().map(|&v| dist3(m.point(v as usize), c)).fold(f64::INFINITY, f64::min);
        assert!(r1 < r0 * (1.0 - 0.5 * a[i]), "run {run}: cavity {i} not compressed ({r0} → {r1})");
    }
    assert!(training_run(TRAINING_RUNS).is_none());
    // Simulate a few frames of run 0: compression pushes fluid out, divergence-free.
    let mut solver =
        FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    for frame in 1..=3 {
        let g = scene.geometry(frame).expect("geometry");
        let (next, report) = solver.step(&state, &g, frame).expect("step");
        assert!(report.projection.relative_divergence < 1e-10);
        // No flux relative to the moving wall.
        for &f in solver.topology().boundary_faces() {
            assert!((next.f[f as usize] - report.h[f as usize]).abs() < 1e-9 * max_abs(&report.h));
        }
        state = next;
    }
    assert!(solver.energy(&state) > 1e-6, "the compression moves the fluid");
    // The deepest training run (0.6) simulates through its whole compression and re-inflation.
    scene.set_run(12).expect("run 12");
    let mut solver =
        FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    for frame in 1..=scene.frames {
        let g = scene.geometry(frame).expect("geometry");
        let (next, report) =
            solver.step(&state, &g, frame).unwrap_or_else(|e| panic!("run 12 frame {frame}: {e}"));
        assert!(report.projection.relative_divergence < 1e-10, "run 12 frame {frame}");
        state = next;
    }
    // Bad cavities are refused naming the key.
    let text = std::fs::read_to_string("scenes/fluid/cavity_small.toml").expect("scene");
    for (from, to, key) in [
        ("run = 0", "run = 14", "run"),
        ("tunnel_radius = 0.22", "tunnel_radius = 0.5", "tunnel_radius"),
        ("initial_velocity = [0.0, 0.0, 0.0]", "initial_velocity = [0.0, 0.0]", "initial_velocity"),
    ] {
        let bad = text.replace(from, to);
        let err = FluidScene::parse(&bad, std::path::Path::new("c.toml")).expect_err(key).to_string();
        let line = bad.lines().position(|l| l.starts_with(key)).expect("key") + 1;
        assert!(err.contains(&format!("c.toml:{line}:")), "{key}: {err}");
    }
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[test]
fn a_users_gmsh_mesh_runs_as_a_periodic_scene() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let (mesh, _) = channel(3, 2);
    std::fs::write(dir.join("channel.msh"), galerkin::mesh::gmsh::write_msh(&mesh, true)).expect("write msh");
    let scene_text = "[mesh]\nfile = \"channel.msh\"\nperiodic_axis = 0\n[flow]\ninitial_velocity = [0.5, 0.0, 0.0]\nviscosity = 1e-3\nframe_time = 0.05\nframes = 3\n";
    std::fs::write(dir.join("scene.toml"), scene_text).expect("write scene");
    let mut scene = FluidScene::load(&dir.join("scene.toml")).expect("scene");
    assert_eq!(scene.mesh.cell_count(), mesh.cell_count());
    let mut solver =
        FluidSolver::new(scene.mesh.clone(), scene.topology.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(scene.mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    for frame in 1..=2 {
        let g = scene.geometry(frame).expect("static");
        state = solver.step(&state, &g, frame).expect("step").0;
    }
    let err =
        state.u.chunks(3).map(|u| (u[0] - 0.5).abs().max(u[1].abs()).max(u[2].abs())).fold(0.0, f64::max);
    assert!(err < 1e-9, "uniform flow through the periodic channel: {err}");
    // A missing mesh file names the scene line of `file`.
    std::fs::write(dir.join("bad.toml"), scene_text.replace("channel.msh", "nope.msh")).expect("write");
    let e = FluidScene::load(&dir.join("bad.toml")).expect_err("missing").to_string();
    assert!(e.contains("bad.toml:2:") && e.contains("nope.msh"), "{e}");
}

#[test]
fn the_streaming_pca_reads_velocity_snapshots_from_disk() {
    use galerkin::reduce::{pca, Truncation};
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let scene = FluidScene::load(std::path::Path::new("scenes/fluid/tunnel_small.toml")).expect("scene");
    let (mesh, topo) = (&scene.mesh, &scene.topology);
    let mut solver = FluidSolver::new(mesh.clone(), topo.clone(), scene.params).expect("solver");
    let mut state = solver.initial_state(mesh.g().to_vec(), &scene.initial_velocity).expect("start");
    let meta = SnapshotMeta::new(mesh, topo, scene.params.frame_time, Some(0));
    let mut w = SnapshotWriter::create(&dir, meta, mesh.cells(), false).expect("create");
    let mut frames = Vec::new();
    for frame in 0..12 {
        if frame > 0 {
            state = solver.step(&state, mesh.g(), frame).expect("step").0;
        }
        let zeros = vec![0.0; topo.face_count()];
        w.push(&state.u, &state.u, &state.f, &state.g, &zeros).expect("push");
        frames.push(state.u.clone());
    }
    let reader = SnapshotReader::open(&dir).expect("open");
    let mut source = reader.source("u").expect("u");
    let basis =
        pca("u", &mut source, Truncation { energy: 0.999999, max_modes: 12, centred: false }).expect("pca");
    assert!(basis.basis.reduced_dim() >= 2 && basis.basis.reduced_dim() <= 12);
    // Every frame is captured to the energy left out.
    for (k, u) in frames.iter().enumerate() {
        let back = basis.basis.lift(&basis.basis.project(u));
        let err: f64 = u.iter().zip(&back).map(|(a, b)| (a - b).powi(2)).sum::<f64>();
        let norm: f64 = u.iter().map(|a| a * a).sum::<f64>();
        assert!(err <= 1e-4 * norm, "frame {k}: relative error² {}", err / norm);
    }
}

/// A snapshot frame after the first with a NaN, or with a cell folded over, is refused when it
/// is read, naming the file, the frame and the value or cell (only frame 0 used to be checked).
#[test]
fn bad_frames_after_the_first_are_refused_naming_the_frame() {
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    let (mesh, topo) = channel(2, 3);
    let meta = SnapshotMeta::new(&mesh, &topo, 0.1, Some(0));
    let mut w = SnapshotWriter::create(&dir, meta, mesh.cells(), false).expect("create");
    let (nu, nf) = (2 * mesh.cell_count(), topo.face_count());
    let (u, f) = (vec![0.5; nu], vec![0.0; nf]);
    let g = mesh.g().to_vec();
    w.push(&u, &u, &f, &g, &f).expect("frame 0");
    let mut nan = u.clone();
    nan[3] = f64::NAN;
    w.push(&nan, &u, &f, &g, &f).expect("frame 1");
    // Frame 2: the first cell's first two corners swap places, so it is inverted.
    let c = &mesh.cells()[..3];
    let mut folded = g.clone();
    for axis in 0..2 {
        folded.swap(2 * c[0] as usize + axis, 2 * c[1] as usize + axis);
    }
    w.push(&u, &u, &f, &folded, &f).expect("frame 2");
    drop(w);
    let r = SnapshotReader::open(&dir).expect("open");
    assert!(r.frame("u", 0).is_ok() && r.mesh_at(0).is_ok());
    let e = r.frame("u", 1).expect_err("a NaN").to_string();
    assert!(e.contains("u.f64") && e.contains("frame 1") && e.contains("value 3"), "{e}");
    let e = r.mesh_at(2).expect_err("a folded cell").to_string();
    assert!(e.contains("g.f64") && e.contains("frame 2") && e.contains("inverted"), "{e}");
}
