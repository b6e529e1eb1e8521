//! The reduced radiosity (seed 000 §8.2–8.3) on the small two-room scene: with bases that
//! span the training data it reproduces the training configurations; its error at a
//! configuration it was not trained on falls as the basis caps rise; the learned visibility
//! returns a training configuration's own visibility.

use std::path::Path;
use std::time::Instant;

use galerkin::radiosity::reduced::relative_error;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, DesignSpace, TrainOptions};
use galerkin::radiosity::{full_radiosity, SceneSpec};

const SMALL: &str = include_str!("../scenes/radiosity/two_rooms_small.toml");

fn spec() -> SceneSpec {
    SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap()
}

/// The model's largest relative error (all faces) over the configurations it was trained on.
fn worst_training_error(
    spec: &SceneSpec,
    model: &galerkin::radiosity::reduced::ReducedRadiosity,
    configurations: &[galerkin::radiosity::train::Configuration],
) -> f64 {
    configurations
        .iter()
        .map(|c| {
            let (b, _) = model.evaluate(&DesignSpace::mesh(spec, &c.params).unwrap()).unwrap();
            relative_error(&b, &c.radiosity, &c.geometry.areas)
        })
        .fold(0.0f64, f64::max)
}

#[test]
fn reduced_radiosity_reproduces_training_and_improves_with_larger_bases() {
    let spec = spec();
    let samples = 12;
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), samples, 7);
    assert_eq!(params.len(), samples);
    // Centroid form factors throughout (the exact near field's test is below).
    let options = TrainOptions { samples, near_correction: None, ..TrainOptions::default() };
    let configurations = solve_configurations(&spec, &params, &options, &|_| {}).unwrap();
    let unseen = [1.3, 0.9, 1.25, 11.0];
    let full = full_radiosity(&spec, &unseen).unwrap();

    // Bases spanning every snapshot (all the energy, no cap).
    let t = Instant::now();
    let spanning = TrainOptions { energy: 1.0, cap: 1000, radiosity_cap: 2000, ..options };
    let (model, report) = train(&spec, &configurations, &spanning, &|_, _, _| {}).unwrap();
    eprintln!("spanning bases {:?} in {:?}", model.dimensions(), t.elapsed());
    eprintln!("{:?}", report.bases);
    let mut worst = 0.0f64;
    for c in &configurations {
        let mesh = DesignSpace::mesh(&spec, &c.params).unwrap();
        let (b, _) = model.evaluate(&mesh).unwrap();
        worst = worst.max(relative_error(&b, &c.radiosity, &c.geometry.areas));
        // The learned visibility returns the configuration's own reduced visibility.
        let ghat = model.model().project_input("g", &c.g).unwrap();
        let (_, x) = model.learned_visibility().predict(&ghat);
        let own = configurations.iter().position(|d| std::ptr::eq(d, c)).unwrap();
        assert!((x[own] - 1.0).abs() < 1e-6, "configuration {own}: weights {x:?}");
    }
    eprintln!("training configurations: worst relative error {worst:.2e}");
    // Every intermediate lies in its basis, so contractions and the Galerkin inverses are
    // exact; the one approximation left is the inverse square root (P ⊗ a)^(-1/2), whose
    // reduction does not commute with projection (§4.2): measured 1.14 % (0.72 % on the mesh
    // whose floors ran under the furniture; the size depends on the mesh).
    assert!(worst < 2e-2, "training configurations reproduced only to {worst}");

    // Error at an unseen configuration against the basis caps (energy 1.0: the cap decides).
    let mut errors = Vec::new();
    for cap in [3, 6, 12] {
        let capped = TrainOptions { energy: 1.0, cap, radiosity_cap: 2 * cap, ..options };
        let (model, _) = train(&spec, &configurations, &capped, &|_, _, _| {}).unwrap();
        let (b, _) = model.evaluate(&full.mesh).unwrap();
        errors.push(relative_error(&b, &full.radiosity, &full.geometry.areas));
    }
    eprintln!("unseen configuration, caps 3/6/12: {errors:?}");
    assert!(errors[2] < errors[0] && errors[1] < errors[0], "error does not fall with the cap: {errors:?}");
    assert!(errors[2] < 0.05, "{errors:?}");
}

/// Sky lighting (§9's second way): the direct light is computed at run time outside the
/// model, from the current geometry and the face–opening visibility blended with Eq. 17's
/// weights. With spanning bases a training configuration comes back to within the reduction's
/// own error, and the model survives a save and load unchanged.
#[test]
fn sky_lit_reduced_radiosity_reproduces_training_and_round_trips() {
    let mut spec = spec();
    spec.lights.mode = galerkin::radiosity::LightMode::Sky;
    let samples = 8;
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), samples, 3);
    let options = TrainOptions {
        samples,
        energy: 1.0,
        cap: 1000,
        radiosity_cap: 2000,
        near_correction: None,
        ..TrainOptions::default()
    };
    let configurations = solve_configurations(&spec, &params, &options, &|_| {}).unwrap();
    // The exact near field is refused with the sky (its direct light is outside the model).
    let exact = TrainOptions { near_correction: Some(4.0), ..options };
    let Err(refused) = train(&spec, &configurations, &exact, &|_, _, _| {}) else {
        panic!("the exact near field was accepted with sky lighting");
    };
    assert!(refused.to_string().contains("sky lighting"), "{refused}");
    assert!(
        configurations[0].emission.iter().filter(|e| e[0] > 0.0).count() > 100,
        "the sky lights the rooms"
    );
    let (model, _) = train(&spec, &configurations, &options, &|_, _, _| {}).unwrap();
    assert_eq!(model.light_mode(), galerkin::radiosity::LightMode::Sky);
    let worst = worst_training_error(&spec, &model, &configurations);
    eprintln!("sky, training configurations: worst relative error {worst:.2e}");
    // As for area lights: exact but for the reduced inverse square root (measured 1.1 %).
    assert!(worst < 2e-2, "{worst}");
    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    let dir = scratch.path().to_path_buf();
    model.save(&dir).unwrap();
    let back = galerkin::radiosity::reduced::ReducedRadiosity::load(&dir).unwrap();
    let mesh = DesignSpace::mesh(&spec, &[1.3, 0.9, 1.25, 11.0]).unwrap();
    assert_eq!(model.evaluate(&mesh).unwrap().0, back.evaluate(&mesh).unwrap().0);
}

/// The geometry basis keeps every mode of the vertex positions (issue 28: the paper's 0.999
/// dropped some): with default options, every training configuration's vertices and an
/// unseen configuration's come back from B_g to 1e-12 m (measured: 8e-14), although the other
/// quantities' bases are truncated at 0.999 of their energy; with 0.999 on the geometry too,
/// the unseen configuration loses more than 0.1 mm (measured: 2.7 cm).
#[test]
fn the_geometry_basis_reproduces_every_configuration_exactly() {
    let spec = spec();
    let samples = 16;
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), samples, 11);
    let options = TrainOptions { samples, ..TrainOptions::default() };
    let configurations = solve_configurations(&spec, &params, &options, &|_| {}).unwrap();
    let (model, report) = train(&spec, &configurations, &options, &|_, _, _| {}).unwrap();
    let bg = model.model().basis("g").expect("a geometry basis");
    let (_, _, kept, _) = report.bases.iter().find(|b| b.0 == "g").expect("g in the report");
    // [1, w, s, d, tan θ, s·tan θ, d·tan θ]: at least six modes about the mean.
    assert!(*kept >= 6, "{:?}", report.bases);
    let unseen = [1.3, 0.9, 1.25, 11.0];
    let worst = |g: &[f64]| {
        let back = bg.lift(&bg.project(g));
        back.iter().zip(g).map(|(a, b)| (a - b).abs()).fold(0.0f64, f64::max)
    };
    for (k, conf) in configurations.iter().enumerate() {
        assert!(worst(&conf.g) < 1e-12, "configuration {k}: {:.2e} m", worst(&conf.g));
    }
    let g = spec.mesh(&unseen).unwrap().g();
    assert!(worst(&g) < 1e-12, "unseen: {:.2e} m", worst(&g));
    // With the paper's threshold on the geometry too, it is not exact.
    let paper = TrainOptions { geometry_energy: 0.999, ..options };
    let (truncated, _) = train(&spec, &configurations, &paper, &|_, _, _| {}).unwrap();
    let bt = truncated.model().basis("g").expect("a geometry basis");
    let lost = bt.lift(&bt.project(&g)).iter().zip(&g).map(|(a, b)| (a - b).abs()).fold(0.0f64, f64::max);
    assert!(lost > 1e-4, "the truncated basis lost only {lost:.2e} m");
}

/// The exact near field inside the model (issue 28, `radiosity::near_correction`): trained
/// with the correction, spanning bases bring every training configuration's corrected
/// radiosity back as the centroid model brings back its own (within 2 %: the reduced inverse
/// square root, §4.2); at a configuration it was not trained on, against the full solve with
/// the exact near field over the receiving surfaces, the corrected model is at least five times
/// as close as the centroid model (measured: 1.8 % against 21.3 %, the centroid form factors'
/// bias); the model survives a save and load, Q and all.
#[test]
fn the_near_field_correction_brings_the_model_to_the_exact_full_solve() {
    use galerkin::radiosity::near_field::{FormFactorMethod, DEFAULT_REACH};
    let spec = spec();
    let samples = 12;
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), samples, 7);
    let exact_options =
        TrainOptions { samples, energy: 1.0, cap: 1000, radiosity_cap: 2000, ..TrainOptions::default() };
    assert_eq!(exact_options.near_correction, Some(DEFAULT_REACH), "the default");
    let spanning = TrainOptions { near_correction: None, ..exact_options };
    let configurations = solve_configurations(&spec, &params, &exact_options, &|_| {}).unwrap();
    assert!(configurations.iter().all(|c| c.near_correction.len() > 1000), "near pairs corrected");
    let (model, _) = train(&spec, &configurations, &exact_options, &|_, _, _| {}).unwrap();
    assert!(model.has_near_correction());
    let worst = worst_training_error(&spec, &model, &configurations);
    eprintln!("exact near field, training configurations: worst relative error {worst:.2e}");
    assert!(worst < 2e-2, "training configurations reproduced only to {worst}");

    let centroid_configurations = solve_configurations(&spec, &params, &spanning, &|_| {}).unwrap();
    let (centroid, _) = train(&spec, &centroid_configurations, &spanning, &|_, _, _| {}).unwrap();
    assert!(!centroid.has_near_correction());
    let unseen = [1.3, 0.9, 1.25, 11.0];
    let mesh = spec.mesh(&unseen).unwrap();
    let truth = galerkin::radiosity::full_radiosity_with(
        mesh.clone(),
        &spec.lights,
        FormFactorMethod::ExactNear { reach: DEFAULT_REACH },
    )
    .unwrap();
    // Over the receiving surfaces (the openings' radiosity is their own emission).
    let receiving: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.kind[i].is_opening()).collect();
    let error = |m: &galerkin::radiosity::reduced::ReducedRadiosity| {
        let b = m.evaluate(&mesh).unwrap().0;
        galerkin::radiosity::compare::relative_error_over(
            &b,
            &truth.radiosity,
            &truth.geometry.areas,
            &receiving,
        )
    };
    let (with, without) = (error(&model), error(&centroid));
    eprintln!(
        "unseen configuration against the exact full solve: corrected {with:.4}, centroid {without:.4}"
    );
    assert!(with < 0.2 * without, "corrected {with}, centroid {without}");

    let scratch = tempfile::Builder::new().prefix("galerkin-").tempdir().expect("a scratch directory");
    model.save(scratch.path()).unwrap();
    let back = galerkin::radiosity::reduced::ReducedRadiosity::load(scratch.path()).unwrap();
    assert!(back.has_near_correction());
    assert_eq!(model.evaluate(&mesh).unwrap().0, back.evaluate(&mesh).unwrap().0);

    check_reduced_operator(&spec, &model, &params[0]);
}

/// The reduced operator `M̂` of `model` at a training configuration `p`: it is what the model
/// inverts (`M̂ b̂ = ê` for the b̂ the chain returns for any ê), and with bases spanning the
/// training data it is the exact operator projected on `B_b`, `B_bᵀ (I − ρF) B_b` with the
/// exact near field — their smallest eigenvalue real parts (the operator margin) agree.
fn check_reduced_operator(
    spec: &SceneSpec,
    model: &galerkin::radiosity::reduced::ReducedRadiosity,
    p: &[f64],
) {
    use std::collections::BTreeMap;
    let mesh = spec.mesh(p).unwrap();
    let core = model.model();
    let m = model.reduced_operator(&mesh).unwrap();
    let mb = core.reduced_dim("b").unwrap();
    assert_eq!(m.shape(), &[mb, mb]);
    let ghat = core.project_input("g", &mesh.g()).unwrap();
    let (vhat, x) = model.learned_visibility().predict(&ghat);
    let e: Vec<f64> = (0..mb).map(|i| 1.0 + 0.37 * i as f64 - 0.01 * (i * i) as f64).collect();
    let inputs: BTreeMap<&str, &[f64]> =
        [("g", &ghat[..]), ("v", &vhat[..]), ("e", &e[..]), ("x", &x[..])].into();
    let bhat = core.evaluate(&inputs).unwrap();
    let back: Vec<f64> =
        (0..mb).map(|i| (0..mb).map(|j| m.data()[i * mb + j] * bhat.data()[j]).sum()).collect();
    let norm = e.iter().map(|v| v * v).sum::<f64>().sqrt();
    let residual = back.iter().zip(&e).map(|(a, b)| (a - b) * (a - b)).sum::<f64>().sqrt() / norm;
    // A solve of an m_b × m_b system with condition ~10: rounding, 1e-12.
    assert!(residual < 1e-12, "M̂ b̂ − ê: {residual:e} of ê");

    // The exact operator on B_b, channel by channel (rows c·n + i of B_b).
    let (f, _) = galerkin::radiosity::near_field::form_factors_exact_near(
        &mesh,
        galerkin::radiosity::near_field::DEFAULT_REACH,
    );
    let n = mesh.len();
    let basis = core.basis("b").unwrap().matrix();
    let b = basis.data();
    let mut projected = vec![0.0; mb * mb];
    for c in 0..3 {
        for i in 0..n {
            let (row, rho) = (f.row(i), mesh.albedo[i][c]);
            for k in 0..mb {
                let fb: f64 = (0..n).map(|j| row[j] * b[(c * n + j) * mb + k]).sum();
                let applied = b[(c * n + i) * mb + k] - rho * fb;
                for l in 0..mb {
                    projected[l * mb + k] += b[(c * n + i) * mb + l] * applied;
                }
            }
        }
    }
    let exact = faer::Mat::<f64>::from_fn(mb, mb, |i, j| projected[i * mb + j]);
    let exact_margin = exact.eigenvalues().unwrap().iter().map(|z| z.re).fold(f64::INFINITY, f64::min);
    let margin = model.operator_margin(&mesh).unwrap();
    eprintln!(
        "operator margin at a training configuration: reduced {margin:.6}, exact projected {exact_margin:.6}"
    );
    // The chain reproduces the training configurations' radiosity to 2 % (above: the reduced
    // inverse square root's non-commutation, §4.2); the operator's eigenvalue within 2 % too.
    assert!(
        exact_margin > 0.0 && (margin - exact_margin).abs() < 0.02 * exact_margin,
        "{margin} vs {exact_margin}"
    );
}
