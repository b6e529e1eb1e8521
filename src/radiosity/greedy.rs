//! Greedy training of the reduced radiosity (issue 53): the reduction core's greedy sampling
//! ([`crate::reduce::greedy`]) with the radiosity's full solve, training and error estimate
//! ([`super::estimate`]), instead of the paper's fixed random sample (seed 000 §9: 540
//! configurations).
//!
//! It starts from every axis's extremes and the corners of the design space (the first samples
//! [`sample_parameters`] takes) and draws its candidates uniformly from the design space
//! ([`crate::reduce::effectivity::random_parameters`]), the corners added; a candidate whose
//! reduced operator has a non-positive margin counts as the worst there is.

use rayon::prelude::*;

use super::error::RadiosityError;
use super::reduced::ReducedRadiosity;
use super::train::{
    box_corners, sample_parameters, solve_configurations, train, Configuration, DesignSpace, Progress,
    TrainOptions, TrainingReport,
};
use crate::reduce::effectivity::random_parameters;
use crate::reduce::greedy::{greedy, GreedyOptions, GreedyProblem, GreedyRound};

/// Every axis's two extremes (the others at their defaults) and every corner of the box, once
/// each: the samples greedy training starts from (the first ones [`sample_parameters`] takes).
pub fn starting_samples(ranges: &[[f64; 2]], defaults: &[f64]) -> Vec<Vec<f64>> {
    let extremes_and_corners = 2 * ranges.len() + box_corners(ranges).len();
    let mut samples = sample_parameters(ranges, defaults, extremes_and_corners, 0);
    // Extremes that coincide with corners leave room for Latin-hypercube samples at the end,
    // which have no coordinate at an end of its range: drop them.
    let inside = |p: &[f64]| p.iter().zip(ranges).filter(|(v, r)| **v != r[0] && **v != r[1]).count();
    samples.retain(|p| ranges.is_empty() || inside(p) < ranges.len());
    samples
}

/// What greedy training made.
pub struct Greedy {
    /// The last round's model.
    pub model: ReducedRadiosity,
    /// Its training report.
    pub report: TrainingReport,
    /// Every configuration solved in full, in the order added.
    pub configurations: Vec<Configuration>,
    /// The rounds.
    pub rounds: Vec<GreedyRound>,
}

/// The radiosity as a greedy problem.
struct Rooms<'a> {
    space: &'a dyn DesignSpace,
    options: &'a TrainOptions,
    progress: Progress<'a>,
    budget: usize,
}

impl GreedyProblem for Rooms<'_> {
    type Solved = Configuration;
    type Model = (ReducedRadiosity, TrainingReport);
    type Error = RadiosityError;

    fn solve(&self, params: &[Vec<f64>]) -> Result<Vec<Configuration>, RadiosityError> {
        solve_configurations(self.space, params, self.options, &|_| {})
    }

    fn train(&self, solved: &[Configuration]) -> Result<Self::Model, RadiosityError> {
        (self.progress)("greedy", solved.len() as u64, self.budget as u64);
        train(self.space, solved, self.options, self.progress)
    }

    fn estimate(&self, model: &Self::Model, candidates: &[Vec<f64>]) -> Result<Vec<f64>, RadiosityError> {
        candidates
            .par_iter()
            .map(|p| {
                let (_, _, e) = model.0.evaluate_estimated(&self.space.mesh(p)?)?;
                Ok(if e.margin > 0.0 { e.error } else { f64::INFINITY })
            })
            .collect()
    }

    fn round_done(&self, r: &GreedyRound) {
        tracing::info!(
            solves = r.solves,
            worst_estimate = r.worst_estimate,
            median_estimate = r.median_estimate,
            seconds = r.seconds,
            "greedy training: a round"
        );
    }
}

/// Greedy training of `space` (see the module documentation); `options` trains each round's
/// model (its `samples` is not used), `progress` reports stages as [`train`] does plus
/// `"greedy"` (full solves so far, budget).
pub fn greedy_train(
    space: &dyn DesignSpace,
    options: &TrainOptions,
    greedy_options: &GreedyOptions,
    progress: Progress<'_>,
) -> Result<Greedy, RadiosityError> {
    options.check()?;
    options.check_lights(space.lights().mode)?;
    if !options.estimate {
        return Err(RadiosityError::Mesh(
            "greedy training places solves by the error estimate: train with it".into(),
        ));
    }
    let ranges = space.ranges();
    let start = starting_samples(&ranges, &space.defaults());
    let mut candidates = random_parameters(&ranges, greedy_options.candidates, greedy_options.seed);
    candidates.extend(box_corners(&ranges));
    let problem = Rooms { space, options, progress, budget: greedy_options.budget };
    let g = greedy(&problem, start, candidates, greedy_options, |m| {
        RadiosityError::Mesh(format!("greedy training: {m}"))
    })?;
    let (model, report) = g.model;
    Ok(Greedy { model, report, configurations: g.solved, rounds: g.rounds })
}
