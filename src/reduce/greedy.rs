//! Greedy sampling of a design space (reduced-basis practice: pyMOR's `weak_greedy`, libROM's
//! greedy sampler) for any reduced model with an error estimate (issue 53): train, evaluate the
//! estimate over a candidate set, solve the worst candidates in full, train again — until the
//! worst estimate is below a tolerance or a budget of full solves is spent.
//!
//! The problem supplies its full solve, its training and its estimate ([`GreedyProblem`]); the
//! loop, its stopping rule and its record ([`GreedyRound`], [`write_rounds`]) are here, so that
//! radiosity and fluids share them. Each round retrains from scratch on every sample so far.

use std::path::{Path, PathBuf};

use super::effectivity::MAX_RANDOM;

/// How greedy sampling proceeds.
#[derive(Clone, Debug, PartialEq)]
pub struct GreedyOptions {
    /// Stop once the worst estimated error over the candidates is below this (a fraction).
    pub tolerance: f64,
    /// Most full solves in all (the starting samples included).
    pub budget: usize,
    /// Random candidate configurations (the problem may add its own, e.g. the box's corners).
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
    /// The reason these options cannot be used with `starting` samples, naming the value: a
    /// tolerance that is not in (0, 1], a budget below the starting samples (or below 2), no
    /// candidates or more than [`MAX_RANDOM`], a batch of zero.
    pub fn check(&self, starting: usize) -> Result<(), String> {
        if !(self.tolerance > 0.0 && self.tolerance <= 1.0) {
            return Err(format!(
                "the tolerance {} must be in (0, 1] (a relative error, e.g. 0.02)",
                self.tolerance
            ));
        }
        if self.budget < starting.max(2) {
            return Err(format!(
                "a budget of {} full solves is less than the {} starting samples",
                self.budget,
                starting.max(2)
            ));
        }
        if self.candidates == 0 || self.candidates > MAX_RANDOM {
            return Err(format!("{} candidates: expected 1 to {MAX_RANDOM}", self.candidates));
        }
        if self.batch == 0 {
            return Err("a batch of 0 full solves per round".into());
        }
        Ok(())
    }
}

/// What a problem supplies to [`greedy`].
pub trait GreedyProblem {
    /// A configuration solved in full.
    type Solved;
    /// A trained reduced model.
    type Model;
    /// The problem's error.
    type Error;
    /// Solves `params` in full, in order.
    fn solve(&self, params: &[Vec<f64>]) -> Result<Vec<Self::Solved>, Self::Error>;
    /// Trains a model on every sample solved so far.
    fn train(&self, solved: &[Self::Solved]) -> Result<Self::Model, Self::Error>;
    /// The model's estimated error at each candidate; `f64::INFINITY` where the model cannot
    /// be trusted at all (an unstable reduced operator).
    fn estimate(&self, model: &Self::Model, candidates: &[Vec<f64>]) -> Result<Vec<f64>, Self::Error>;
    /// Called after each round (progress, logs).
    fn round_done(&self, _round: &GreedyRound) {}
}

/// One round of greedy sampling.
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
    /// Candidates the model cannot be trusted at (an infinite estimate).
    pub unstable: usize,
    /// Seconds of the round (solves, training, the candidates' estimates).
    pub seconds: f64,
}

/// What [`greedy`] made.
pub struct Greedy<S, M> {
    /// The last round's model.
    pub model: M,
    /// Every configuration solved in full, in the order added.
    pub solved: Vec<S>,
    /// Their parameters.
    pub params: Vec<Vec<f64>>,
    /// The rounds.
    pub rounds: Vec<GreedyRound>,
}

/// Greedy sampling (see the module documentation) from the samples `start` over the
/// `candidates`. Options are checked first ([`GreedyOptions::check`]); `refuse` turns its
/// message into the problem's error.
pub fn greedy<P: GreedyProblem>(
    problem: &P,
    start: Vec<Vec<f64>>,
    mut candidates: Vec<Vec<f64>>,
    options: &GreedyOptions,
    refuse: impl Fn(String) -> P::Error,
) -> Result<Greedy<P::Solved, P::Model>, P::Error> {
    options.check(start.len()).map_err(&refuse)?;
    candidates.retain(|c| !start.contains(c));
    let mut params = start;
    let mut solved: Vec<P::Solved> = Vec::new();
    let mut rounds = Vec::new();
    loop {
        let clock = std::time::Instant::now();
        solved.extend(problem.solve(&params[solved.len()..])?);
        let model = problem.train(&solved)?;
        let estimates = problem.estimate(&model, &candidates)?;
        if estimates.len() != candidates.len() {
            return Err(refuse(format!("{} estimates for {} candidates", estimates.len(), candidates.len())));
        }
        let mut order: Vec<usize> = (0..candidates.len()).collect();
        order.sort_by(|&a, &b| estimates[b].total_cmp(&estimates[a]));
        let worst = order.first().map_or(0.0, |&k| estimates[k]);
        let mut sorted = estimates.clone();
        sorted.sort_by(f64::total_cmp);
        let round = GreedyRound {
            solves: solved.len(),
            worst_estimate: worst,
            worst_at: order.first().map_or_else(Vec::new, |&k| candidates[k].clone()),
            median_estimate: sorted.get(sorted.len() / 2).copied().unwrap_or(0.0),
            unstable: estimates.iter().filter(|e| e.is_infinite()).count(),
            seconds: clock.elapsed().as_secs_f64(),
        };
        problem.round_done(&round);
        rounds.push(round);
        let room = options.budget.saturating_sub(solved.len());
        if worst < options.tolerance || room == 0 || candidates.is_empty() {
            return Ok(Greedy { model, solved, params, rounds });
        }
        let mut chosen: Vec<usize> = order[..options.batch.min(room).min(candidates.len())].to_vec();
        chosen.sort_unstable_by(|a, b| b.cmp(a));
        for k in chosen {
            params.push(candidates.swap_remove(k));
        }
    }
}

/// Writes the rounds as `dir/greedy.csv` (solves, worst and median estimate, where the worst
/// is — one column per parameter `names` —, the candidates the model cannot be trusted at,
/// seconds) and `dir/greedy.png` (the worst and median estimate against the full solves);
/// returns the two paths.
pub fn write_rounds(
    dir: &Path,
    names: &[String],
    rounds: &[GreedyRound],
) -> Result<(PathBuf, PathBuf), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
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
        .map_err(|e| format!("{}: {e}", csv.display()))?;
    let plot = dir.join("greedy.png");
    let line = |label: &str, pick: fn(&GreedyRound) -> f64| crate::plot::Line {
        label: label.to_string(),
        points: rounds.iter().filter(|r| pick(r).is_finite()).map(|r| (r.solves as f64, pick(r))).collect(),
    };
    crate::plot::line_chart(
        &plot,
        "Greedy training: the model's estimated error over the candidates",
        "full solves trained on",
        "estimated relative error (%)",
        &[line("worst candidate", |r| r.worst_estimate), line("median candidate", |r| r.median_estimate)],
        &|v| format!("{:.1} %", 100.0 * v),
    )
    .map_err(|e| e.to_string())?;
    Ok((csv, plot))
}
