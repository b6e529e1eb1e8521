//! Greedy training of the reduced radiosity (issue 53): full solves placed where the model's
//! own error estimate ([`super::estimate`]) is worst, instead of the paper's fixed random
//! sample (seed 000 §9: 540 configurations).
//!
//! Start from every axis's extremes and the corners of the design space
//! ([`super::train::sample_parameters`] with as many samples as those), train, evaluate the
//! estimate over a candidate set (configurations drawn uniformly from the design space,
//! [`super::effectivity::random_parameters`], and the corners), solve the `batch` candidates
//! with the largest estimates in full, add them, train again — until the worst estimate over
//! the candidates is below the tolerance or the budget of full solves is spent. Each round
//! retrains from scratch (bases, premultiplication, correction, cross-validation), so a round
//! costs about one training of the samples so far; `batch` trades rounds against how well
//! each solve is placed.

use rayon::prelude::*;

use super::effectivity::{random_parameters, MAX_RANDOM};
use super::error::RadiosityError;
use super::reduced::ReducedRadiosity;
use super::train::{
    box_corners, sample_parameters, solve_configurations, train, Configuration, DesignSpace, Progress,
    TrainOptions, TrainingReport,
};

/// How greedy training proceeds.
#[derive(Clone, Debug, PartialEq)]
pub struct GreedyOptions {
    /// Stop once the worst estimated error over the candidates is below this (a fraction).
    pub tolerance: f64,
    /// Most full solves in all (the starting samples included).
    pub budget: usize,
    /// Random candidate configurations (the corners are added to them).
    pub candidates: usize,
    /// Full solves added per round.
    pub batch: usize,
    /// The candidates' seed.
    pub seed: u64,
}

impl Default for GreedyOptions {
    fn default() -> Self {
        Self { tolerance: 0.02, budget: 540, candidates: 2000, batch: 20, seed: 7 }
    }
}

impl GreedyOptions {
    /// Refuses options greedy training cannot use, naming the value: a tolerance that is not
    /// in (0, 1], a budget below the starting samples, no candidates or more than
    /// [`MAX_RANDOM`], a batch of zero.
    pub fn check(&self, starting: usize) -> Result<(), RadiosityError> {
        let bad = |m: String| RadiosityError::Mesh(format!("greedy training: {m}"));
        if !(self.tolerance > 0.0 && self.tolerance <= 1.0) {
            return Err(bad(format!(
                "the tolerance {} must be in (0, 1] (a relative error, e.g. 0.02)",
                self.tolerance
            )));
        }
        if self.budget < starting.max(2) {
            return Err(bad(format!(
                "a budget of {} full solves is less than the {} starting samples (every axis's extremes and the corners)",
                self.budget,
                starting.max(2)
            )));
        }
        if self.candidates == 0 || self.candidates > MAX_RANDOM {
            return Err(bad(format!("{} candidates: expected 1 to {MAX_RANDOM}", self.candidates)));
        }
        if self.batch == 0 {
            return Err(bad("a batch of 0 full solves per round".into()));
        }
        Ok(())
    }
}

/// One round of greedy training.
#[derive(Clone, Debug, PartialEq)]
pub struct GreedyRound {
    /// Full solves the round's model was trained on.
    pub solves: usize,
    /// The worst estimated error over the candidates.
    pub worst_estimate: f64,
    /// Where.
    pub worst_at: Vec<f64>,
    /// The median estimated error over the candidates.
    pub median_estimate: f64,
    /// Candidates whose reduced operator has a non-positive margin.
    pub unstable: usize,
    /// Seconds of the round (solves, training, the candidates' estimates).
    pub seconds: f64,
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

/// Every axis's two extremes (the others at their defaults) and every corner of the box, once
/// each: the samples greedy training starts from (the first ones [`sample_parameters`] takes).
pub fn starting_samples(ranges: &[[f64; 2]], defaults: &[f64]) -> Vec<Vec<f64>> {
    let corners = box_corners(ranges).len();
    let extremes_and_corners = 2 * ranges.len() + corners;
    let mut samples = sample_parameters(ranges, defaults, extremes_and_corners, 0);
    // Extremes that coincide with corners leave room for Latin-hypercube samples at the end,
    // which have no coordinate at an end of its range: drop them.
    let inside = |p: &[f64]| p.iter().zip(ranges).filter(|(v, r)| **v != r[0] && **v != r[1]).count();
    samples.retain(|p| ranges.is_empty() || inside(p) < ranges.len());
    samples
}

/// Greedy training of `space` (see the module documentation); `options` trains each round's
/// model (its `samples` is ignored), `progress` reports stages as [`train`] does plus
/// `"greedy"` (full solves so far, budget).
pub fn greedy_train(
    space: &dyn DesignSpace,
    options: &TrainOptions,
    greedy: &GreedyOptions,
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
    let mut params = starting_samples(&ranges, &space.defaults());
    greedy.check(params.len())?;
    let mut candidates = random_parameters(&ranges, greedy.candidates, greedy.seed);
    candidates.extend(box_corners(&ranges).into_iter().filter(|c| !params.contains(c)));
    let mut configurations: Vec<Configuration> = Vec::new();
    let mut rounds = Vec::new();
    loop {
        let clock = std::time::Instant::now();
        let fresh = &params[configurations.len()..];
        configurations.extend(solve_configurations(space, fresh, options, &|_| {})?);
        progress("greedy", configurations.len() as u64, greedy.budget as u64);
        let (model, report) = train(space, &configurations, options, progress)?;
        let estimates: Vec<(f64, f64)> = candidates
            .par_iter()
            .map(|p| {
                let (_, _, e) = model.evaluate_estimated(&space.mesh(p)?)?;
                // An unstable operator is as bad as an estimate can be.
                Ok((if e.margin > 0.0 { e.error } else { f64::INFINITY }, e.margin))
            })
            .collect::<Result<_, RadiosityError>>()?;
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        order.sort_by(|&a, &b| estimates[b].0.total_cmp(&estimates[a].0));
        let worst = order.first().map_or(0.0, |&k| estimates[k].0);
        let mut sorted: Vec<f64> = estimates.iter().map(|e| e.0).collect();
        sorted.sort_by(f64::total_cmp);
        rounds.push(GreedyRound {
            solves: configurations.len(),
            worst_estimate: worst,
            worst_at: order.first().map_or_else(Vec::new, |&k| candidates[k].clone()),
            median_estimate: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
            unstable: estimates.iter().filter(|e| !(e.1 > 0.0)).count(),
            seconds: clock.elapsed().as_secs_f64(),
        });
        tracing::info!(
            solves = configurations.len(),
            worst_estimate = worst,
            seconds = clock.elapsed().as_secs_f64(),
            "greedy training: a round"
        );
        let room = greedy.budget - configurations.len();
        if worst < greedy.tolerance || room == 0 || candidates.is_empty() {
            return Ok(Greedy { model, report, configurations, rounds });
        }
        let take = greedy.batch.min(room).min(candidates.len());
        let mut chosen: Vec<usize> = order[..take].to_vec();
        chosen.sort_unstable_by(|a, b| b.cmp(a));
        for k in chosen {
            params.push(candidates.swap_remove(k));
        }
    }
}

/// Writes the rounds as `dir/greedy.csv` (solves, worst and median estimate, where the worst
/// is, unstable candidates, seconds) and `dir/greedy.png` (the worst and median estimate
/// against the full solves); returns the two paths.
pub fn write_rounds(
    dir: &std::path::Path,
    names: &[String],
    rounds: &[GreedyRound],
) -> Result<(std::path::PathBuf, std::path::PathBuf), RadiosityError> {
    let fail =
        |path: &std::path::Path, e: String| RadiosityError::File { path: path.to_path_buf(), message: e };
    std::fs::create_dir_all(dir).map_err(|e| fail(dir, e.to_string()))?;
    let at: Vec<String> = names.iter().map(|n| format!("worst_at_{n}")).collect();
    let mut rows =
        vec![format!("solves,worst_estimate,median_estimate,{},unstable_candidates,seconds", at.join(","))];
    for r in rounds {
        let p: Vec<String> = r.worst_at.iter().map(f64::to_string).collect();
        rows.push(format!(
            "{},{:.6},{:.6},{},{},{:.3}",
            r.solves,
            r.worst_estimate,
            r.median_estimate,
            p.join(","),
            r.unstable,
            r.seconds
        ));
    }
    let csv = dir.join("greedy.csv");
    crate::atomic_file::write(&csv, (rows.join("\n") + "\n").as_bytes())
        .map_err(|e| fail(&csv, e.to_string()))?;
    let plot = dir.join("greedy.png");
    let line = |label: &str, pick: fn(&GreedyRound) -> f64| crate::plot::Line {
        label: label.to_string(),
        points: rounds.iter().filter(|r| pick(r).is_finite()).map(|r| (r.solves as f64, pick(r))).collect(),
    };
    crate::plot::line_chart(
        &plot,
        "Greedy training: the model's estimated error over the candidates",
        "full solves trained on",
        "estimated relative error, receiving surfaces (%)",
        &[line("worst candidate", |r| r.worst_estimate), line("median candidate", |r| r.median_estimate)],
        &|v| format!("{:.1} %", 100.0 * v),
    )
    .map_err(|e| fail(&plot, e.to_string()))?;
    Ok((csv, plot))
}
