//! Greedy training of the reduced radiosity (issue 53; `radiosity::greedy`) on the small
//! two-room scene: it starts from the extremes and corners, adds full solves where the
//! model's estimate is worst, and the worst estimate over the candidates falls with every
//! round; options it cannot use are refused naming the value.

use std::path::Path;

use galerkin::radiosity::greedy::{greedy_train, starting_samples};
use galerkin::radiosity::train::{box_corners, TrainOptions};
use galerkin::radiosity::SceneSpec;
use galerkin::reduce::greedy::{write_rounds, GreedyOptions};

const SMALL: &str = include_str!("../scenes/radiosity/two_rooms_small.toml");

fn spec() -> SceneSpec {
    SceneSpec::parse(SMALL, Path::new("two_rooms_small.toml")).unwrap()
}

/// Three rounds (24 starting solves: 8 extremes and 16 corners; then 8 more each, placed at the
/// 8 candidates of largest estimate): the worst estimate over 150 candidates falls strictly
/// from round to round, each round's solves are the ones before plus the batch, and the rounds'
/// table and plot are written.
#[test]
fn greedy_training_lowers_the_worst_estimate_with_every_round() {
    let spec = spec();
    let start = starting_samples(&spec.ranges(), &spec.defaults());
    assert_eq!(start.len(), 2 * 4 + 16, "every axis's extremes and the box's corners");
    for c in box_corners(&spec.ranges()) {
        assert!(start.contains(&c), "corner {c:?} among the starting samples");
    }
    let options = TrainOptions::default();
    let greedy = GreedyOptions { tolerance: 1e-4, budget: 40, candidates: 150, batch: 8, seed: 5 };
    let g = greedy_train(&spec, &options, &greedy, &|_, _, _| {}).unwrap();
    let solves: Vec<usize> = g.rounds.iter().map(|r| r.solves).collect();
    assert_eq!(solves, [24, 32, 40], "the budget spent in batches");
    assert_eq!(g.configurations.len(), 40);
    for (k, r) in g.rounds.iter().enumerate() {
        eprintln!(
            "round {}: {} solves, worst estimate {:.3} % at {:.3?}, median {:.3} %, {} unstable, {:.1} s",
            k + 1,
            r.solves,
            100.0 * r.worst_estimate,
            r.worst_at,
            100.0 * r.median_estimate,
            r.unstable,
            r.seconds
        );
    }
    for pair in g.rounds.windows(2) {
        assert!(
            pair[1].worst_estimate < pair[0].worst_estimate,
            "the worst estimate rose from {} to {} ({} → {} solves)",
            pair[0].worst_estimate,
            pair[1].worst_estimate,
            pair[0].solves,
            pair[1].solves
        );
    }
    // The solves added are candidates, inside the design space and not starting samples.
    for c in &g.configurations[24..] {
        assert!(!start.contains(&c.params));
        assert!(c.params.iter().zip(spec.ranges()).all(|(v, r)| *v >= r[0] && *v <= r[1]));
    }
    assert_eq!(g.model.cross_validation().map(|v| v.samples()), Some(40));
    let dir = tempfile::Builder::new().prefix("galerkin-greedy-").tempdir().unwrap();
    let (csv, plot) =
        write_rounds(dir.path(), &["w".into(), "s".into(), "d".into(), "t".into()], &g.rounds).unwrap();
    assert_eq!(std::fs::read_to_string(csv).unwrap().lines().count(), 1 + 3);
    assert!(plot.exists());
}

/// A tolerance that is not in (0, 1], a budget below the starting samples, no candidates, a
/// batch of zero: refused before anything is solved, naming the value.
#[test]
fn greedy_options_it_cannot_use_are_refused() {
    let spec = spec();
    let options = TrainOptions::default();
    let ok = GreedyOptions::default();
    for (bad, named) in [
        (GreedyOptions { tolerance: 0.0, ..ok.clone() }, "tolerance 0"),
        (GreedyOptions { tolerance: -0.1, ..ok.clone() }, "tolerance -0.1"),
        (GreedyOptions { tolerance: f64::NAN, ..ok.clone() }, "tolerance NaN"),
        (GreedyOptions { budget: 0, ..ok.clone() }, "budget of 0"),
        (GreedyOptions { budget: 20, ..ok.clone() }, "budget of 20"),
        (GreedyOptions { candidates: 0, ..ok.clone() }, "0 candidates"),
        (GreedyOptions { batch: 0, ..ok.clone() }, "batch of 0"),
    ] {
        let clock = std::time::Instant::now();
        let e = greedy_train(&spec, &options, &bad, &|_, _, _| {}).err().expect("refused").to_string();
        assert!(e.contains(named), "{e}");
        assert!(clock.elapsed().as_secs_f64() < 2.0, "refused before solving");
    }
}
