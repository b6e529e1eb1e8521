//! The reduced radiosity's error estimate (issue 53; `radiosity::estimate`): the estimated
//! evaluation gives the model's composition's radiosity, the cross-validation is what it says
//! (a training sample left out of Eq. 17, its floor, the samples' spacing), the model keeps it
//! through a save and load, and on configurations drawn at random from a seed unrelated to
//! training the estimate lies within the effectivity band `[0.5, 10]` of the true error against
//! the exact full solve.

use std::path::Path;

use galerkin::radiosity::compare::relative_error_over;
use galerkin::radiosity::estimate::{sample_spacing, CrossValidation};
use galerkin::radiosity::near_field::{FormFactorMethod, DEFAULT_REACH};
use galerkin::radiosity::reduced::ReducedRadiosity;
use galerkin::radiosity::train::{sample_parameters, solve_configurations, train, DesignSpace, TrainOptions};
use galerkin::radiosity::SceneSpec;
use galerkin::reduce::effectivity::{random_parameters, EFFECTIVITY_HIGH, EFFECTIVITY_LOW};
use galerkin::tensor::Tensor;

const SMALL: &str = include_str!("../scenes/radiosity/two_rooms_small.toml");

/// The estimate of one configuration from the stored series, summed plainly.
fn plain_estimate(v: &CrossValidation, ghat: &[f64], x: &[f64], geometry: &Tensor) -> f64 {
    let (m, t) = (geometry.shape()[0], geometry.shape()[1]);
    let mut sum = 0.0;
    for (s, &weight) in x.iter().enumerate().take(t) {
        let d: f64 = (0..m).map(|i| (ghat[i] - geometry.data()[i * t + s]).powi(2)).sum::<f64>().sqrt();
        sum += weight * (v.floor[s] + v.left_out[s] * (d / v.spacing[s]).sqrt().min(2.0));
    }
    sum
}

/// The small two-room scene trained with 40 samples (the defaults: the exact near field, the
/// operator correction, the estimate). The estimated evaluation's radiosity is the model's
/// composition's (formed through the chain's expression and once from `p̂`: 1e-10); its estimate
/// is the stored series blended plainly (1e-12); Eq. 17 without a sample gives it no weight and
/// still sums to 1; left out, most samples are farther from the model than their floor; the
/// model keeps the series through a save
/// and load; and at 12 configurations drawn from a seed unrelated to training every estimate
/// lies in the effectivity band [0.5, 10] against the exact full solve (receiving surfaces).
#[test]
fn the_estimate_bounds_the_true_error_on_random_configurations() {
    let spec = SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap();
    let samples = 40;
    let options = TrainOptions { samples, ..TrainOptions::default() };
    let params = sample_parameters(&spec.ranges(), &spec.defaults(), samples, 3);
    let configurations = solve_configurations(&spec, &params, &options, &|_| {}).unwrap();
    let (model, _) = train(&spec, &configurations, &options, &|_, _, _| {}).unwrap();
    let v = model.cross_validation().expect("training made the estimate").clone();
    let geometry = model.learned_visibility().geometry().clone();
    assert_eq!(v.samples(), samples);
    assert_eq!(v.spacing, sample_spacing(&geometry));
    assert!(v.spacing.iter().all(|h| *h > 0.0), "distinct samples: {:?}", v.spacing);
    // Left out, a sample is farther from the model than its own floor.
    let above = v.left_out.iter().zip(&v.floor).filter(|(e, f)| e > f).count();
    assert!(above > samples / 2, "left-out errors {:?}, floors {:?}", v.left_out, v.floor);

    // Eq. 17 with a sample left out, as the cross-validation solves it.
    let t = 17;
    let c = &configurations[t];
    let mesh = DesignSpace::mesh(&spec, &c.params).unwrap();
    let receiving: Vec<usize> = (0..mesh.len()).filter(|&i| !mesh.kind[i].is_opening()).collect();
    let ghat = model.model().project_input("g", &c.g).unwrap();
    assert_eq!(model.learned_visibility().predict(&ghat).1[t], 1.0, "a sample's own weight");
    let (_, x) = model.learned_visibility().predict_without(&ghat, Some(t));
    assert_eq!(x[t], 0.0);
    assert!((x.iter().sum::<f64>() - 1.0).abs() < 1e-12);

    let dir = tempfile::Builder::new().prefix("galerkin-estimate-").tempdir().unwrap();
    model.save(dir.path()).unwrap();
    let back = ReducedRadiosity::load(dir.path()).unwrap();
    assert_eq!(back.cross_validation(), Some(&v));

    let mut rows = Vec::new();
    for p in random_parameters(&spec.ranges(), 12, 90_210) {
        let mesh = DesignSpace::mesh(&spec, &p).unwrap();
        let (plain, _) = model.evaluate(&mesh).unwrap();
        let (b, _, estimate) = model.evaluate_estimated(&mesh).unwrap();
        let areas = mesh.geometry().areas;
        let all: Vec<usize> = (0..mesh.len()).collect();
        let same = relative_error_over(&b, &plain, &areas, &all);
        assert!(same < 1e-10, "the estimated evaluation's radiosity is {same:e} off the composition's");
        let ghat = model.model().project_input("g", &mesh.g()).unwrap();
        let (_, x) = model.learned_visibility().predict(&ghat);
        let want = plain_estimate(&v, &ghat, &x, &geometry);
        assert!((estimate.error - want).abs() <= 1e-12 * want, "{} against {want}", estimate.error);
        assert_eq!(back.evaluate_estimated(&mesh).unwrap().2, estimate, "the loaded model's estimate");
        let truth = galerkin::radiosity::full_radiosity_with(
            mesh.clone(),
            &spec.lights,
            FormFactorMethod::ExactNear { reach: DEFAULT_REACH },
        )
        .unwrap();
        let error = relative_error_over(&b, &truth.radiosity, &truth.geometry.areas, &receiving);
        assert!(estimate.margin > 0.0 && estimate.stability > 0.0, "{estimate:?}");
        rows.push((p, error, estimate.error));
    }
    for (p, error, estimated) in &rows {
        eprintln!(
            "{p:.3?}: true {:.3} %, estimated {:.3} %, effectivity {:.2}",
            100.0 * error,
            100.0 * estimated,
            estimated / error
        );
    }
    for (p, error, estimated) in &rows {
        let effectivity = estimated / error;
        assert!(
            (EFFECTIVITY_LOW..=EFFECTIVITY_HIGH).contains(&effectivity),
            "at {p:?}: estimated {estimated}, true {error}: effectivity {effectivity} outside [{EFFECTIVITY_LOW}, {EFFECTIVITY_HIGH}]"
        );
    }
}
