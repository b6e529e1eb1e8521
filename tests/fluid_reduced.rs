//! The reduced fluid of seed 000 §6 against the full solver it reduces: bases, the §6.2
//! tensors on lifted inputs, constraint reduction, energy, the reduced step's velocity
//! conversion against the core's composition, replayed motion, the model file and bad input.
//!
//! Tolerances: reduced tensors are premultiplied sums of O(1) terms over ~10⁴ entries and
//! are compared with the full expression on lifted inputs to 1e-10 relative (rounding is
//! ~1e-13); the boundary constraint residual is at most the SVD rank cut (1e-9) times the
//! coefficients' size; energies may grow by rounding only, 1e-12 relative.
#![allow(clippy::needless_range_loop)]

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use galerkin::fluid::operators::{add_laplacian, advect, divergence, CellOperators};
use galerkin::fluid::reduced::{
    bases::relative_divergence, run_reduced, BasisSizes, Exponential, FluidBases, FluxCombination,
    ReducedFluid, ReducedFluidModel, ReducedMotion, ReducedState, ReducedStepReport, TrainingSet,
};
use galerkin::fluid::FluidSolver;
use galerkin::mesh::{SimplexMesh, Topology};
use galerkin::reduce::{Basis, SingleRank};

use common::tunnel::tunnel_run;

struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn vec(&mut self, n: usize) -> Vec<f64> {
        (0..n).map(|_| self.next()).collect()
    }
}

fn norm(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum::<f64>().sqrt()
}

fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    norm(&d) / norm(b).max(1e-300)
}

/// Two waving-channel runs (different flows) in `dim` dimensions.
fn wavy_runs(dir: &Path, dim: usize) -> Vec<PathBuf> {
    common::wavy::two_runs(dir, dim)
}

fn train(runs: &[PathBuf], sizes: BasisSizes) -> (TrainingSet, ReducedFluidModel) {
    let set = TrainingSet::open(runs).expect("training set");
    let model = ReducedFluidModel::fit(&set, &sizes, &mut |_| {}).expect("model");
    (set, model)
}

fn basis<'a>(m: &'a ReducedFluidModel, n: &str) -> &'a Basis {
    m.basis(n).unwrap_or_else(|| panic!("basis {n}"))
}

/// `Bᵀ x`.
fn project(b: &Basis, x: &[f64]) -> Vec<f64> {
    b.project(x)
}

#[test]
fn bases_are_divergence_free_and_carry_the_mean_geometry() {
    let dir = tempfile::tempdir().expect("temp dir");
    let runs = vec![tunnel_run(dir.path(), 0.6, 30), tunnel_run(dir.path(), 1.4, 30)];
    let (set, model) = train(&runs, BasisSizes::default());
    let bf = basis(&model, "f");
    let div = relative_divergence(set.topology(), bf);
    assert!(div <= 1e-10, "‖div B_f‖/‖B_f‖ = {div:e}");
    for name in ["f", "u", "g"] {
        let e = basis(&model, name).orthonormality_error();
        assert!(e < 1e-12, "B_{name} is not orthonormal: {e:e}");
    }
    // The mean of the two static geometries is in span(B_g) exactly, and so is the medium
    // obstacle's geometry (the harmonic deformation is linear in the obstacle's scale).
    let g0 = set.runs()[0].frame("g", 0).unwrap();
    let g1 = set.runs()[1].frame("g", 0).unwrap();
    let mean: Vec<f64> = g0.iter().zip(&g1).map(|(a, b)| 0.5 * (a + b)).collect();
    let bg = basis(&model, "g");
    assert!(rel_diff(&bg.lift(&bg.project(&mean)), &mean) < 1e-13);
    let medium = tunnel_run(dir.path(), 1.0, 1);
    let gm = galerkin::fluid::snapshots::SnapshotReader::open(&medium).unwrap().frame("g", 0).unwrap();
    assert!(rel_diff(&bg.lift(&bg.project(&gm)), &gm) < 1e-12, "the medium obstacle is not in span(B_g)");
    // No motion: no B_h, no boundary flux, no B_d.
    assert!(model.basis("h").is_none() && model.basis("d").is_none());
}

/// Each reduced tensor against its full-space expression on lifted random reduced inputs.
fn check_tensors(set: &TrainingSet, model: &ReducedFluidModel, seed: u64) {
    let (mesh, topo): (&SimplexMesh, &Topology) = (set.mesh(), set.topology());
    let fluid = ReducedFluid::new(model).expect("runtime");
    let (mu, mf, _, mh) = fluid.dims();
    let (bu, bf, bg) = (basis(model, "u"), basis(model, "f"), basis(model, "g"));
    let mut rng = Lcg(seed);
    let (u, f) = (rng.vec(mu), rng.vec(mf));
    // A geometry near the training ones: the mean (first column) plus a little of the rest.
    let mut g = project(bg, mesh.g());
    for x in g.iter_mut().skip(1) {
        *x += 0.01 * rng.next();
    }
    let (uf, ff, gf) = (bu.lift(&u), bf.lift(&f), bg.lift(&g));
    let h = rng.vec(mh);
    let hf = model.basis("h").map(|b| b.lift(&h)).unwrap_or_else(|| vec![0.0; topo.face_count()]);
    let d = mesh.dim();
    // K̂ û = B_uᵀ[(A⊗(f − h))u − (div h)u + μΔu].
    let k = fluid.rate_operator(&f, &h);
    let ours: Vec<f64> = (0..mu).map(|i| (0..mu).map(|j| k[(i, j)] * u[j]).sum()).collect();
    let rel: Vec<f64> = ff.iter().zip(&hf).map(|(a, b)| a - b).collect();
    let mut full = vec![0.0; uf.len()];
    advect(topo, &rel, &uf, &mut full);
    let vdot = divergence(topo, &hf);
    for c in 0..mesh.cell_count() {
        for a in 0..d {
            full[d * c + a] -= vdot[c] * uf[d * c + a];
        }
    }
    add_laplacian(topo, &uf, model.viscosity, &mut full);
    let want = project(bu, &full);
    // The step holds Â and Â_h in f32 (each value rounded to 6e-8 relative; measured 2e-8 on
    // K̂û): 1e-6 still fails on any wrong term of the tensors.
    assert!(rel_diff(&ours, &want) < 1e-6, "Â, Â_h, Δ̂: {:e}", rel_diff(&ours, &want));
    // V̂(ĝ) û = B_uᵀ V(g) u and (P̂ ⊗ ĝ) f̂ = B_uᵀ (P ⊗ g) f.
    let v = fluid.volume_matrix(&g);
    let ours: Vec<f64> = (0..mu).map(|i| (0..mu).map(|j| v[(i, j)] * u[j]).sum()).collect();
    let vols = mesh.volumes_at(&gf);
    let vu: Vec<f64> = uf.iter().enumerate().map(|(i, x)| vols[i / d] * x).collect();
    assert!(rel_diff(&ours, &project(bu, &vu)) < 1e-10, "V̂");
    let p = fluid.flux_to_momentum(&g);
    let ours: Vec<f64> = (0..mu).map(|i| (0..mf).map(|j| p[(i, j)] * f[j]).sum()).collect();
    let ops = CellOperators::new(mesh, topo, &gf);
    let want = project(bu, &ops.flux_to_momentum(topo, &ff));
    assert!(rel_diff(&ours, &want) < 1e-10, "P̂: {:e}", rel_diff(&ours, &want));
    // D̂ f̂ = B_dᵀ D B_f f̂, D̂_h ĥ = B_dᵀ D B_h ĥ.
    if let Some(bd) = model.basis("d") {
        let md = bd.reduced_dim();
        let boundary = topo.boundary_faces();
        for (name, x, xf) in [("D", &f, &ff), ("Dh", &h, &hf)] {
            let Some(t) = model.tensor(name) else { continue };
            let n = x.len();
            let ours: Vec<f64> = (0..md).map(|i| (0..n).map(|j| t.data()[i * n + j] * x[j]).sum()).collect();
            let df: Vec<f64> = boundary.iter().map(|&b| xf[b as usize]).collect();
            assert!(rel_diff(&ours, &bd.project(&df)) < 1e-10, "{name}");
        }
    }
    // The core model's composition V̂⁻¹(P̂ ⊗ ĝ) f̂ equals the fast path.
    let mut inputs: BTreeMap<&str, &[f64]> = BTreeMap::new();
    inputs.insert("f", &f);
    inputs.insert("g", &g);
    let core = model.core.evaluate(&inputs).expect("core evaluation");
    let fast = fluid.flux_to_velocity(&f, &g).expect("fast path");
    assert!(rel_diff(&fast, core.data()) < 1e-10, "velocity conversion vs the core");
}

#[test]
fn reduced_tensors_equal_the_full_expressions_on_lifted_inputs_2d_and_3d() {
    let dir = tempfile::tempdir().expect("temp dir");
    for dim in [2, 3] {
        let runs = wavy_runs(dir.path(), dim);
        let (set, model) = train(&runs, BasisSizes::default());
        assert!(model.basis("h").is_some(), "{dim}D: the waving wall induces flux");
        assert!(model.basis("d").is_some(), "{dim}D: the waving wall carries boundary flux");
        check_tensors(&set, &model, 3 + dim as u64);
    }
    let runs = vec![tunnel_run(dir.path(), 0.6, 10), tunnel_run(dir.path(), 1.4, 10)];
    let (set, model) = train(&runs, BasisSizes::default());
    check_tensors(&set, &model, 11);
}

#[test]
fn the_reduced_constraint_holds_iff_the_full_one_does() {
    let dir = tempfile::tempdir().expect("temp dir");
    for dim in [2, 3] {
        let runs = wavy_runs(dir.path(), dim);
        let (set, model) = train(&runs, BasisSizes::default());
        let (bf, bh, bd) = (basis(&model, "f"), basis(&model, "h"), basis(&model, "d"));
        let (mf, mh, md) = (bf.reduced_dim(), bh.reduced_dim(), bd.reduced_dim());
        let (d, dh) = (model.tensor("D").unwrap(), model.tensor("Dh").unwrap());
        // [D̂, −D̂_h] z = 0 for z in its null space.
        let c = faer::Mat::from_fn(md, mf + mh, |i, j| {
            if j < mf {
                d.data()[i * mf + j]
            } else {
                -dh.data()[i * mh + j - mf]
            }
        });
        let svd = c.svd().unwrap();
        let s = svd.S().column_vector();
        let rank = (0..s.nrows()).filter(|&i| s[i] > 1e-10 * s[0]).count();
        let v = svd.V();
        let boundary = set.topology().boundary_faces();
        let mut rng = Lcg(29 + dim as u64);
        for _ in 0..5 {
            let y = rng.vec(mf + mh - rank);
            let z: Vec<f64> =
                (0..mf + mh).map(|i| (rank..mf + mh).map(|k| v[(i, k)] * y[k - rank]).sum()).collect();
            let (f, h) = (&z[..mf], &z[mf..]);
            let (ff, hf) = (bf.lift(f), bh.lift(h));
            let resid: Vec<f64> = boundary.iter().map(|&b| ff[b as usize] - hf[b as usize]).collect();
            assert!(norm(&resid) < 1e-8 * norm(&z), "{dim}D: ‖D(B_f f̂ − B_h ĥ)‖ = {:e}", norm(&resid));
        }
        // And a pair violating the reduced constraint violates the full one by as much.
        let (f, h) = (rng.vec(mf), rng.vec(mh));
        let reduced: Vec<f64> = (0..md)
            .map(|i| {
                (0..mf).map(|j| d.data()[i * mf + j] * f[j]).sum::<f64>()
                    - (0..mh).map(|j| dh.data()[i * mh + j] * h[j]).sum::<f64>()
            })
            .collect();
        let (ff, hf) = (bf.lift(&f), bh.lift(&h));
        let full: Vec<f64> = boundary.iter().map(|&b| ff[b as usize] - hf[b as usize]).collect();
        assert!(
            (norm(&reduced) - norm(&full)).abs() < 1e-8 * norm(&full),
            "{dim}D: B_d misses part of the range"
        );
    }
}

/// `M(g)` of the exact projection against a plain sum over cells of the flux modes'
/// velocities `V⁻¹P B_f e_j` (1e-10 of its largest entry: two summation orders); it exceeds
/// the Galerkin `P̂ᵀV̂⁻¹P̂` by a positive semidefinite matrix (each mode's velocity outside B_u).
fn exact_gram_is_the_full_one(model: &ReducedFluidModel, g_hat: &[f64]) {
    use galerkin::fluid::operators::CellOperators;
    use galerkin::fluid::reduced::exact_projection::ExactProjection;
    let exact = ExactProjection::new(model).unwrap();
    let m = exact.gram(g_hat).unwrap();
    let _ = exact.gram(g_hat).unwrap();
    assert_eq!(exact.computed(), 1, "the same geometry is computed once");
    let (mesh, topo) = model.mesh_and_topology().unwrap();
    let g = basis(model, "g").lift(g_hat);
    let ops = CellOperators::new(&mesh, &topo, &g);
    let (bf, d) = (basis(model, "f"), mesh.dim());
    let mf = bf.reduced_dim();
    let vel: Vec<Vec<f64>> = (0..mf)
        .map(|j| {
            let mut e = vec![0.0; mf];
            e[j] = 1.0;
            ops.flux_to_velocity(&topo, &bf.lift(&e))
        })
        .collect();
    let scale = (0..mf).map(|i| m[(i, i)].abs()).fold(0.0, f64::max);
    for i in 0..mf {
        for j in 0..mf {
            let plain: f64 = (0..mesh.cell_count())
                .map(|c| ops.volumes[c] * (0..d).map(|k| vel[i][d * c + k] * vel[j][d * c + k]).sum::<f64>())
                .sum();
            assert!((m[(i, j)] - plain).abs() <= 1e-10 * scale, "M[{i},{j}] {} vs {plain}", m[(i, j)]);
        }
    }
    let fluid = ReducedFluid::new(model).unwrap();
    let (l, p) = (fluid.volume_matrix(g_hat), fluid.flux_to_momentum(g_hat));
    use faer::linalg::solvers::Solve;
    let galerkin = p.transpose() * l.partial_piv_lu().solve(&p);
    let gap = &m - &galerkin;
    let gap = faer::Mat::from_fn(mf, mf, |i, j| 0.5 * (gap[(i, j)] + gap[(j, i)]));
    let eig = gap.self_adjoint_eigenvalues(faer::Side::Lower).unwrap();
    assert!(eig.iter().all(|&e| e >= -1e-9 * scale), "M − P̂ᵀV̂⁻¹P̂ has eigenvalue {:e}", eig[0]);
}

#[test]
fn advection_and_projection_never_increase_the_energy() {
    let dir = tempfile::tempdir().expect("temp dir");
    let runs = vec![tunnel_run(dir.path(), 0.6, 30), tunnel_run(dir.path(), 1.4, 30)];
    let (_, static_model) = train(&runs, BasisSizes::default());
    let wavy = wavy_runs(dir.path(), 2);
    let (_, wavy_model) = train(&wavy, BasisSizes::default());
    for (model, combination) in
        [(&static_model, FluxCombination::Separate), (&wavy_model, FluxCombination::ProjectedOntoFlux)]
    {
        let mut fluid = ReducedFluid::new(model).unwrap();
        fluid.combination = combination;
        // The projection is narrowed to the flux directions B_u sees (what follows checks
        // that the narrowed projection keeps the energy argument); the fractions are those of
        // N ≤ M, in [0, 1] to rounding.
        let seen = fluid.seen_flux().expect("a trained model narrows its projection");
        assert!(seen.kept >= 1 && seen.kept <= seen.of(), "{seen:?}");
        assert!(seen.fractions.iter().all(|&x| (-1e-9..=1.0 + 1e-9).contains(&x)), "{:?}", seen.fractions);
        let exact = ReducedFluid::new(model).unwrap().with_exact_projection(model).unwrap();
        let (mu, mf, _, mh) = fluid.dims();
        let g = model.trajectories[0].g.data()[..model.dim_of("g")].to_vec();
        exact_gram_is_the_full_one(model, &g);
        let mut rng = Lcg(5);
        for exponential in [Exponential::Krylov(1e-12), Exponential::Pade] {
            fluid.exponential = exponential;
            for times in [1.0, 10.0, 100.0] {
                let (u, f) = (rng.vec(mu), rng.vec(mf));
                let h = rng.vec(mh);
                let e0 = fluid.energy(&u, &g);
                let mut report = ReducedStepReport::default();
                let dt = times * fluid.frame_time();
                let u1 = fluid.advect(&u, &f, &g, &h, dt, &mut report).unwrap();
                let e1 = fluid.energy(&u1, &g);
                assert!(e1 <= e0 * (1.0 + 1e-12), "{combination:?} {exponential:?} Δt ×{times}: {e0} → {e1}");
                // The projection with no induced flux is a V̂-orthogonal projection.
                let zero = vec![0.0; mh];
                let (u2, _) = fluid.project(&u1, &g, &zero, &mut report).unwrap();
                let e2 = fluid.energy(&u2, &g);
                assert!(e2 <= e1 * (1.0 + 1e-12), "projection: {e1} → {e2}");
                // So is it with the normal matrix from the full space, M(g) ≥ P̂ᵀV̂⁻¹P̂
                // (exact_projection's energy argument).
                let (u3, _) = exact.project(&u1, &g, &zero, &mut report).unwrap();
                let e3 = fluid.energy(&u3, &g);
                assert!(e3 <= e1 * (1.0 + 1e-12), "exact projection: {e1} → {e3}");
            }
        }
        // The Krylov exponential (L⁻¹K̂L⁻ᵀ applied through triangular solves, never formed)
        // and Padé 13 (on the formed matrix) agree to 1e-10 of ‖û‖: the Krylov tolerance is
        // 1e-12 and the triangular solves lose at most a few digits to L's conditioning
        // (measured 5e-16 and 8e-14 on these two models).
        let (u, f, h) = (rng.vec(mu), rng.vec(mf), rng.vec(mh));
        let mut advected = Vec::new();
        for exponential in [Exponential::Krylov(1e-12), Exponential::Pade] {
            fluid.exponential = exponential;
            let mut report = ReducedStepReport::default();
            advected.push(fluid.advect(&u, &f, &g, &h, 10.0 * fluid.frame_time(), &mut report).unwrap());
        }
        let diff = rel_diff(&advected[0], &advected[1]);
        assert!(diff < 1e-10, "{combination:?}: Krylov and Padé differ by {diff:e}");
    }
}

#[test]
fn a_replayed_reduced_run_follows_its_training_run_and_replays_its_induced_flux() {
    let dir = tempfile::tempdir().expect("temp dir");
    let runs = wavy_runs(dir.path(), 2);
    let sizes = BasisSizes { energy: 1.0 - 1e-10, ..BasisSizes::default() };
    let (set, model) = train(&runs, sizes);
    let fluid = ReducedFluid::new(&model).unwrap();
    let frames = 29;
    let run = run_reduced(&model, &fluid, ReducedMotion::Replay(1), frames, &mut |_| {}).unwrap();
    let reader = &set.runs()[1];
    let (bu, bg, bh) = (basis(&model, "u"), basis(&model, "g"), basis(&model, "h"));
    let solver = FluidSolver::new(set.mesh().clone(), set.topology().clone(), *set.params()).unwrap();
    for t in 1..=frames {
        // The replayed ĥ lifts to the full induced flux of the lifted geometry's motion.
        let (g0, g1) = (bg.lift(&run.states[t - 1].g), bg.lift(&run.states[t].g));
        let h_full = solver.induced_flux(&g0, &g1);
        let h_replayed = bh.lift(&run.h[t]);
        assert!(rel_diff(&h_replayed, &h_full) < 1e-6, "frame {t}: ĥ {:e}", rel_diff(&h_replayed, &h_full));
        // The reduced velocity stays near the training run's (the bases hold 1 − 1e-10 of it).
        let u_true = reader.frame("u", t).unwrap();
        // (Truncation is not what limits this: the advected velocity u' before the projection
        // is no snapshot quantity and leaves span(B_u); measured ≤ 3.3 % over these frames.)
        let err = rel_diff(&bu.lift(&run.states[t].u), &u_true);
        assert!(err < 0.05, "frame {t}: reduced velocity off by {err:e}");
    }
    assert!(run.reports.iter().all(|r| r.constraint_residual < 1e-9), "the boundary constraint is not met");
    // Fig. 2's combination (ĥ projected onto B_f, no −V̇u term) measured once against ours on
    // the same moving mesh: the mean relative velocity error over the replay.
    let mean_error = |combination: FluxCombination| {
        let mut fluid = ReducedFluid::new(&model).unwrap();
        fluid.combination = combination;
        let run = run_reduced(&model, &fluid, ReducedMotion::Replay(1), frames, &mut |_| {}).unwrap();
        (1..=frames)
            .map(|t| rel_diff(&bu.lift(&run.states[t].u), &reader.frame("u", t).unwrap()))
            .sum::<f64>()
            / frames as f64
    };
    let (separate, projected) =
        (mean_error(FluxCombination::Separate), mean_error(FluxCombination::ProjectedOntoFlux));
    eprintln!("mean velocity error over the replay: separate Â_h {separate:.3e}, Fig. 2's projection {projected:.3e}");
    assert!(separate < projected, "the solver's own combination should follow the solver better");
}

#[test]
fn the_model_file_round_trips_and_refuses_another_mesh() {
    let dir = tempfile::tempdir().expect("temp dir");
    let runs = wavy_runs(dir.path(), 2);
    let (_, model) = train(&runs, BasisSizes::default());
    let path = dir.path().join("model.safetensors");
    model.save(&path).unwrap();
    let back = ReducedFluidModel::load(&path).unwrap();
    for name in ["A", "Ah", "L", "P", "V", "D", "Dh"] {
        assert_eq!(back.tensor(name), model.tensor(name), "tensor {name}");
    }
    for name in ["u", "f", "g", "h", "d"] {
        assert_eq!(back.basis(name), model.basis(name), "basis {name}");
    }
    assert_eq!(back.trajectories, model.trajectories);
    assert_eq!(back.provenance, model.provenance);
    assert!(model.flux_grams.is_some(), "training measures the flux velocity Gram matrices");
    assert_eq!(back.flux_grams, model.flux_grams);
    // Another mesh is refused, naming both.
    let (mesh, topo) = common::wavy::channel(2, 6);
    let other = galerkin::fluid::reduced::MeshFingerprint::of(&mesh, &topo, Some(0));
    let err = back.check_mesh(&other).unwrap_err().to_string();
    assert!(err.contains(&other.cells_hash) && err.contains(&model.provenance.mesh.cells_hash), "{err}");
    // A truncated file is refused naming it.
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    let err = ReducedFluidModel::load(&path).unwrap_err().to_string();
    assert!(err.contains("model.safetensors"), "{err}");
}

#[test]
fn bad_training_input_is_refused_naming_the_run_frame_or_basis() {
    let dir = tempfile::tempdir().expect("temp dir");
    let tunnel = tunnel_run(dir.path(), 1.0, 5);
    let wavy = wavy_runs(dir.path(), 2);
    // Runs from different meshes.
    let err = TrainingSet::open(&[tunnel.clone(), wavy[0].clone()]).unwrap_err().to_string();
    assert!(err.contains("wavy2-0") && err.contains("tunnel-1"), "{err}");
    // A basis larger than the snapshots: B_u merges 6 velocity and 6 momentum snapshots (and
    // with mid-step velocities 5 more, one per frame but the last).
    let set = TrainingSet::open(std::slice::from_ref(&tunnel)).unwrap();
    let sizes = BasisSizes { m_u: Some(13), ..BasisSizes::default() };
    let err = FluidBases::build(&set, &sizes, &mut |_| {}, &SingleRank).unwrap_err().to_string();
    assert!(err.contains("basis u") && err.contains("12 snapshots"), "{err}");
    let sizes = BasisSizes { m_u: Some(18), mid_step: true, ..BasisSizes::default() };
    let err = FluidBases::build(&set, &sizes, &mut |_| {}, &SingleRank).unwrap_err().to_string();
    assert!(err.contains("basis u") && err.contains("17 snapshots"), "{err}");
    let sizes = BasisSizes { m_f: Some(7), ..BasisSizes::default() };
    let err = FluidBases::build(&set, &sizes, &mut |_| {}, &SingleRank).unwrap_err().to_string();
    assert!(err.contains("basis f") && err.contains("6 snapshots"), "{err}");
    // NaN in a snapshot: the run, frame and row are named.
    let u_path = tunnel.join("u.f64");
    let mut bytes = std::fs::read(&u_path).unwrap();
    let len = bytes.len() / 6; // six frames
    bytes[3 * len + 16..3 * len + 24].copy_from_slice(&f64::NAN.to_le_bytes());
    std::fs::write(&u_path, bytes).unwrap();
    let set = TrainingSet::open(std::slice::from_ref(&tunnel)).unwrap();
    let err =
        FluidBases::build(&set, &BasisSizes::default(), &mut |_| {}, &SingleRank).unwrap_err().to_string();
    assert!(err.contains("tunnel-1") && err.contains("frame 3") && err.contains("row 2"), "{err}");
    // A geometry basis under which a training frame's cells collapse: every other frame of a
    // copy of a run turned half a turn about the channel's centre (volumes kept), so the mean
    // geometry — all a one-column B_g holds — is the centre point.
    let turned = dir.path().join("turned");
    std::fs::create_dir_all(&turned).unwrap();
    // 30 of the 31 frames, so that as many are turned as not and the mean is the centre point.
    for q in ["u", "p", "f", "h"] {
        let bytes = std::fs::read(wavy[0].join(format!("{q}.f64"))).unwrap();
        std::fs::write(turned.join(format!("{q}.f64")), &bytes[..bytes.len() / 31 * 30]).unwrap();
    }
    std::fs::copy(wavy[0].join("mesh.json"), turned.join("mesh.json")).unwrap();
    let header = std::fs::read_to_string(wavy[0].join("snapshots.json")).unwrap();
    assert!(header.contains("\"frames\": 31"), "{header}");
    std::fs::write(turned.join("snapshots.json"), header.replace("\"frames\": 31", "\"frames\": 30"))
        .unwrap();
    let g_bytes = std::fs::read(wavy[0].join("g.f64")).unwrap();
    let mut g: Vec<f64> =
        g_bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().unwrap())).collect();
    let frame_len = g.len() / 31;
    for k in (1..31).step_by(2) {
        for x in g[k * frame_len..(k + 1) * frame_len].chunks_exact_mut(2) {
            x[0] = 2.0 - x[0];
            x[1] = 1.0 - x[1];
        }
    }
    g.truncate(30 * frame_len);
    std::fs::write(turned.join("g.f64"), g.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>())
        .unwrap();
    let set = TrainingSet::open(std::slice::from_ref(&turned)).unwrap();
    let sizes = BasisSizes { m_g: Some(1), ..BasisSizes::default() };
    // Every cell collapses to the centre (the mean of a frame and its turned copy): the basis
    // report counts the folded cells, and the model is refused at its reduced volume matrix,
    // naming the run and frame.
    let bases = FluidBases::build(&set, &sizes, &mut |_| {}, &SingleRank).expect("the bases");
    let g_note = &bases.reports.iter().find(|r| r.name == "g").expect("basis g").note;
    assert!(g_note.contains("folds cells in 30 frames") && g_note.contains("turned frame"), "{g_note}");
    let err =
        ReducedFluidModel::train(&set, bases, &sizes, &mut |_| {}, &SingleRank).unwrap_err().to_string();
    assert!(
        err.contains("training run 0") && err.contains("frame 0") && err.contains("not positive definite"),
        "{err}"
    );
    // A reduced state of the wrong length.
    let (_, model) = train(&wavy, BasisSizes::default());
    let fluid = ReducedFluid::new(&model).unwrap();
    let (mu, mf, mg, mh) = fluid.dims();
    let s = ReducedState { u: vec![0.0; mu + 1], f: vec![0.0; mf], g: vec![0.0; mg] };
    assert!(fluid.step(&s, &vec![0.0; mg], &vec![0.0; mh]).is_err());
    // A degenerate reduced geometry (ĝ = 0: every volume zero) is refused, not NaN.
    let s = ReducedState { u: vec![0.0; mu], f: vec![0.0; mf], g: vec![0.0; mg] };
    let err = fluid.step(&s, &vec![0.0; mg], &vec![0.0; mh]).unwrap_err().to_string();
    assert!(err.contains("not positive definite"), "{err}");
}

/// With complete bases (B_u = I, B_f every divergence-free flux, B_h = I) the reduced step is
/// the full step with the exponential integrated exactly: compared with a plain full-space
/// reference — `exp(Δt V⁻¹(g_t) K)` as a dense matrix, then the full solver's projection — to
/// the projection's conjugate-gradient tolerance (1e-12 of the flux scale; we allow 1e-8).
#[test]
fn with_complete_bases_the_reduced_step_is_the_full_step_with_an_exact_exponential() {
    use galerkin::fluid::projection::Projection;
    use galerkin::fluid::reduced::bases::constraint_basis;
    use galerkin::tensor::{expm, Tensor};
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("wavy-complete");
    common::wavy::simulate(2, 4, 0.08, 20.0, [1.0, 0.3, 0.0], 12, &out);
    let set = TrainingSet::open(std::slice::from_ref(&out)).unwrap();
    let (mesh, topo) = (set.mesh(), set.topology());
    let (nc, nf, d) = (mesh.cell_count(), topo.face_count(), mesh.dim());
    // B_f: the null space of the divergence (right singular vectors of zero singular value).
    let div = faer::Mat::from_fn(nc, nf, |c, f| {
        (0..=d).filter(|&l| topo.cell_face(c, l) == f).map(|l| topo.sign(c, l)).sum::<f64>()
    });
    let svd = div.svd().unwrap();
    let s = svd.S().column_vector();
    let rank = (0..s.nrows()).filter(|&i| s[i] > 1e-10 * s[0]).count();
    let v = svd.V();
    let m = nf - rank;
    let bf = Basis::new(
        "f",
        Tensor::from_vec(&[nf, m], (0..nf * m).map(|k| v[(k / m, rank + k % m)]).collect()).unwrap(),
        1e-10,
    )
    .unwrap();
    let bu = Basis::identity(d * nc);
    let bh = Basis::identity(nf);
    let sizes = BasisSizes { energy: 1.0, ..BasisSizes::default() };
    let pca_bases = FluidBases::build(&set, &sizes, &mut |_| {}, &SingleRank).unwrap();
    let bd = constraint_basis(topo, &bf, Some(&bh)).unwrap();
    let bases =
        FluidBases { f: bf.clone(), u: bu, g: pca_bases.g.clone(), h: Some(bh), d: bd, reports: vec![] };
    let model = ReducedFluidModel::train(&set, bases, &sizes, &mut |_| {}, &SingleRank).unwrap();
    let fluid = ReducedFluid::new(&model).unwrap();
    let reader = &set.runs()[0];
    let params = *set.params();
    let mut projection = Projection::new(topo).unwrap();
    for t in [3usize, 8] {
        let (u, f, g0, g1) = (
            reader.frame("u", t).unwrap(),
            reader.frame("f", t).unwrap(),
            reader.frame("g", t).unwrap(),
            reader.frame("g", t + 1).unwrap(),
        );
        let h = reader.frame("h", t + 1).unwrap();
        // The reduced step.
        let bg = basis(&model, "g");
        let state = ReducedState { u: u.clone(), f: bf.project(&f), g: bg.project(&g0) };
        let (next, _) = fluid.step(&state, &bg.project(&g1), &h).unwrap();
        // The full reference: K as a dense matrix column by column, exp, projection.
        let n = d * nc;
        let vols = mesh.volumes_at(&g0);
        let rel: Vec<f64> = f.iter().zip(&h).map(|(a, b)| a - b).collect();
        let vdot = divergence(topo, &h);
        let mut rate = vec![0.0; n * n];
        for j in 0..n {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let mut col = vec![0.0; n];
            advect(topo, &rel, &e, &mut col);
            add_laplacian(topo, &e, params.viscosity, &mut col);
            for i in 0..n {
                col[i] -= vdot[i / d] * e[i];
                rate[i * n + j] = params.frame_time * col[i] / vols[i / d];
            }
        }
        let ex = expm("reference", &Tensor::from_vec(&[n, n], rate).unwrap()).unwrap();
        let u1: Vec<f64> = (0..n).map(|i| (0..n).map(|j| ex.get(&[i, j]) * u[j]).sum()).collect();
        let ops = CellOperators::new(mesh, topo, &g1);
        let hb: Vec<f64> = topo.boundary_faces().iter().map(|&b| h[b as usize]).collect();
        let (f1, _) = projection.project(topo, &ops, &u1, &hb, t + 1).unwrap();
        let want = ops.flux_to_velocity(topo, &f1);
        let err = rel_diff(&next.u, &want);
        assert!(err < 1e-8, "frame {t}: complete-basis reduced step vs the exact full step: {err:e}");
        let ferr = rel_diff(&bf.lift(&next.f), &f1);
        assert!(ferr < 1e-8, "frame {t}: fluxes {ferr:e}");
    }
}

/// The induced-flux tensor reproduces the solver's induced flux (2D and 3D, random motions),
/// and its reduction gives `B_hᵀ h(B_g ĝ_t, B_g ĝ_{t+1})` for any reduced motion; a run driven
/// by the computed ĥ follows the replayed one. Tolerances: polarization combines O(1) values
/// of a cubic, so the tensor agrees to ~1e-14 of the flux scale (we allow 1e-11); the reduced
/// form is a premultiplication of it (1e-10).
#[test]
fn the_induced_flux_tensor_reproduces_the_solver_and_drives_motions() {
    use galerkin::fluid::reduced::induced::induced_flux_tensor;
    let dir = tempfile::tempdir().expect("temp dir");
    for dim in [2, 3] {
        let (mesh, topo) = common::wavy::channel(dim, if dim == 2 { 4 } else { 2 });
        let params = galerkin::fluid::FluidParams { viscosity: 1e-3, forcing: [0.0; 3], frame_time: 0.02 };
        let solver = FluidSolver::new(mesh.clone(), topo.clone(), params).unwrap();
        let h = induced_flux_tensor(&mesh, &topo, params.frame_time);
        let mut rng = Lcg(41 + dim as u64);
        let g0: Vec<f64> = mesh.g().iter().map(|x| x + 0.02 * rng.next()).collect();
        let g1: Vec<f64> = g0.iter().map(|x| x + 0.01 * rng.next()).collect();
        let gamma: Vec<f64> = g0.iter().chain(&g1).copied().collect();
        let args: Vec<(usize, &[f64])> = (1..=dim).map(|a| (a, gamma.as_slice())).collect();
        let ours = h.contract_axes("H", &args).unwrap();
        let want = solver.induced_flux(&g0, &g1);
        let scale = want.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let err = ours.data().iter().zip(&want).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(err < 1e-11 * scale, "{dim}D: induced-flux tensor off by {err:e} of {scale:e}");
        // Reduced.
        let runs = wavy_runs(dir.path(), dim);
        let (set, model) = train(&runs, BasisSizes::default());
        let fluid = ReducedFluid::new(&model).unwrap();
        let (bg, bh) = (basis(&model, "g"), basis(&model, "h"));
        let full = FluidSolver::new(set.mesh().clone(), set.topology().clone(), *set.params()).unwrap();
        for _ in 0..3 {
            let gh0: Vec<f64> = bg.project(set.mesh().g()).iter().map(|x| x + 0.01 * rng.next()).collect();
            let gh1: Vec<f64> = gh0.iter().map(|x| x + 0.005 * rng.next()).collect();
            let ours = fluid.induced_flux(&gh0, &gh1).expect("the model has H");
            let want = bh.project(&full.induced_flux(&bg.lift(&gh0), &bg.lift(&gh1)));
            assert!(rel_diff(&ours, &want) < 1e-10, "{dim}D: Ĥ {:e}", rel_diff(&ours, &want));
        }
        // A run driven by the computed ĥ follows the replay of the same geometry.
        let replay = run_reduced(&model, &fluid, ReducedMotion::Replay(0), 20, &mut |_| {}).unwrap();
        let computed = run_reduced(&model, &fluid, ReducedMotion::Computed(0), 20, &mut |_| {}).unwrap();
        let bu = basis(&model, "u");
        for t in [5, 20] {
            let err = rel_diff(&bu.lift(&computed.states[t].u), &bu.lift(&replay.states[t].u));
            assert!(err < 1e-6, "{dim}D frame {t}: computed against replayed {err:e}");
        }
    }
}

/// The unseen-velocity indicator's form `σ(f̂)² = f̂ᵀ(M − N)f̂` (measured on one geometry) is
/// the squared energy-norm distance of the flux's full-space velocity `u_f = V⁻¹P B_f f̂` from
/// its V-orthogonal projection onto `B_u`, computed here plainly: `u_f` cell by cell, the
/// projection by solving `(B_uᵀVB_u) c = B_uᵀV u_f` with a dense LU. Tolerance 1e-8 of
/// `‖u_f‖²_V`: the form subtracts two Gram matrices of that size, each summed over cells in
/// another order, and `N` goes through a Cholesky of `V̂` (condition ~10⁴ here).
#[test]
fn the_unseen_velocity_is_the_flux_velocity_outside_the_velocity_basis() {
    use faer::linalg::solvers::Solve;
    use galerkin::fluid::reduced::exact_projection::FluxVelocityGrams;
    use galerkin::fluid::reduced::unseen::{UnseenIndicator, UnseenVelocity};
    let dir = tempfile::tempdir().expect("temp dir");
    let runs = vec![tunnel_run(dir.path(), 0.6, 20), tunnel_run(dir.path(), 1.4, 20)];
    let sizes = BasisSizes { m_u: Some(6), m_f: Some(8), ..BasisSizes::default() };
    let (_, model) = train(&runs, sizes);
    let (mesh, topo) = model.mesh_and_topology().unwrap();
    let g_hat = model.trajectories[1].g.data()[..model.dim_of("g")].to_vec();
    let g = basis(&model, "g").lift(&g_hat);
    let grams = FluxVelocityGrams::measure(&model, &[("run 1, frame 0".into(), g.clone())]).unwrap();
    let form = UnseenVelocity::new(&grams).unwrap();
    let ops = CellOperators::new(&mesh, &topo, &g);
    let (bu, bf, d) = (basis(&model, "u"), basis(&model, "f"), mesh.dim());
    let mu = bu.reduced_dim();
    let energy = |u: &[f64]| -> f64 {
        (0..mesh.cell_count())
            .map(|c| ops.volumes[c] * (0..d).map(|k| u[d * c + k].powi(2)).sum::<f64>())
            .sum()
    };
    let inner = |a: &[f64], b: &[f64]| -> f64 {
        (0..mesh.cell_count())
            .map(|c| ops.volumes[c] * (0..d).map(|k| a[d * c + k] * b[d * c + k]).sum::<f64>())
            .sum()
    };
    let columns: Vec<Vec<f64>> = (0..mu)
        .map(|j| {
            let mut e = vec![0.0; mu];
            e[j] = 1.0;
            bu.lift(&e)
        })
        .collect();
    let vhat = faer::Mat::from_fn(mu, mu, |i, j| inner(&columns[i], &columns[j]));
    let mut rng = Lcg(17);
    let mut largest = 0.0f64;
    for _ in 0..4 {
        let f = rng.vec(bf.reduced_dim());
        let uf = ops.flux_to_velocity(&topo, &bf.lift(&f));
        let rhs = faer::Mat::from_fn(mu, 1, |i, _| inner(&columns[i], &uf));
        let c = vhat.partial_piv_lu().solve(&rhs);
        let projected = bu.lift(&(0..mu).map(|i| c[(i, 0)]).collect::<Vec<_>>());
        let outside: Vec<f64> = uf.iter().zip(&projected).map(|(a, b)| a - b).collect();
        let (plain, whole) = (energy(&outside), energy(&uf));
        let sigma = form.sigma(&f);
        assert!(
            (sigma * sigma - plain).abs() <= 1e-8 * whole,
            "σ² {:e} vs plain {plain:e} (‖u_f‖² {whole:e})",
            sigma * sigma
        );
        largest = largest.max(plain / whole);
    }
    assert!(largest > 1e-6, "with 6 velocity modes some flux velocity lies outside B_u ({largest:e})");

    // The running estimate: (σ(f̂_t) + Σ σ(f̂_k − f̂_{k−1}), carried terms damped) / ‖u‖_V,
    // with ‖u‖_V = sqrt(2E).
    let mut indicator = UnseenIndicator::with_form(form.clone());
    let (f0, f1) = (rng.vec(bf.reduced_dim()), rng.vec(bf.reduced_dim()));
    let first = indicator.observe(&f0, 2.0, 1.0, 0).unwrap();
    assert!((first.estimate - form.sigma(&f0) / 2.0).abs() <= 1e-15 * first.estimate.max(1.0));
    let second = indicator.observe(&f1, 8.0, 0.5, 1).unwrap();
    let delta: Vec<f64> = f1.iter().zip(&f0).map(|(a, b)| a - b).collect();
    let want = (form.sigma(&f1) + form.sigma(&delta)) / 4.0; // nothing carried yet to damp
    assert!((second.estimate - want).abs() <= 1e-14 * want, "{} vs {want}", second.estimate);
    // The next step carries the errors so far (σ(f̂_1 − f̂_0)) shrunk by the damping.
    let third = indicator.observe(&f1, 8.0, 0.5, 2).unwrap();
    let want = (form.sigma(&f1) + 0.5 * form.sigma(&delta)) / 4.0;
    assert!((third.estimate - want).abs() <= 1e-14 * want, "{} vs {want}", third.estimate);
    assert!(indicator.observe(&f1[1..], 8.0, 1.0, 3).is_err(), "a flux of another size is refused");

    // The damping: the square root of the energy fraction the step's advection and diffusion
    // kept, at most 1, and 1 where the step reports no energy.
    use galerkin::fluid::reduced::indicator::damping;
    let report = |energy: [f64; 3]| ReducedStepReport { energy, ..ReducedStepReport::default() };
    assert_eq!(damping(&report([4.0, 1.0, 3.0])), 0.5);
    assert_eq!(damping(&report([1.0, 2.0, 3.0])), 1.0);
    assert_eq!(damping(&report([0.0, 0.0, 0.0])), 1.0);

    // A model trained before the Gram matrices were measured is refused, naming the way out.
    let mut old = model;
    old.flux_grams = None;
    let err = UnseenIndicator::new(&old).unwrap_err().to_string();
    assert!(err.contains("--indicator-every"), "{err}");
}
