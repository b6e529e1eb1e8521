//! Random configurations drawn from a seed unrelated to training, solved in full and reduced,
//! and the error estimate's effectivity over them (issue 53; [`super::estimate`]).
//!
//! The effectivity of an estimate is `estimate ÷ true error`: 1 is exact, below 1 an
//! underestimate (the dangerous side), above 1 an overestimate. The goal it is held to is the
//! band `[0.5, 10]` on every configuration checked: never under by more than 2×, never over by
//! more than 10×.

use super::compare::FrameError;
use super::train::splitmix;

/// The lower end of the effectivity band the estimate is held to.
pub const EFFECTIVITY_LOW: f64 = 0.5;
/// The upper end.
pub const EFFECTIVITY_HIGH: f64 = 10.0;

/// Most random configurations one comparison solves.
pub const MAX_RANDOM: usize = 100_000;

/// `count` configurations drawn uniformly from the box `ranges` with the SplitMix64 sequence
/// of `seed` (independent of training's Latin hypercube, which uses its own seed).
pub fn random_parameters(ranges: &[[f64; 2]], count: usize, seed: u64) -> Vec<Vec<f64>> {
    // Decorrelated from a training run given the same number as its seed.
    let mut state = seed ^ 0xD1B5_4A32_D192_ED03;
    (0..count).map(|_| ranges.iter().map(|r| r[0] + splitmix(&mut state) * (r[1] - r[0])).collect()).collect()
}

/// The estimate's effectivity over a set of configurations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Effectivity {
    /// Configurations with a finite effectivity (a true error above zero and an estimate).
    pub count: usize,
    /// The smallest effectivity.
    pub min: f64,
    /// The median.
    pub median: f64,
    /// The largest.
    pub max: f64,
    /// How many fall below [`EFFECTIVITY_LOW`].
    pub under: usize,
    /// How many fall above [`EFFECTIVITY_HIGH`].
    pub over: usize,
}

impl Effectivity {
    /// Over `errors` (receiving surfaces); `None` where no configuration has a finite one.
    pub fn of<'a>(errors: impl IntoIterator<Item = &'a FrameError>) -> Option<Self> {
        let mut values: Vec<f64> =
            errors.into_iter().map(FrameError::effectivity).filter(|v| v.is_finite()).collect();
        if values.is_empty() {
            return None;
        }
        values.sort_by(f64::total_cmp);
        let count = values.len();
        Some(Self {
            count,
            min: values[0],
            median: values[count / 2],
            max: values[count - 1],
            under: values.iter().filter(|&&v| v < EFFECTIVITY_LOW).count(),
            over: values.iter().filter(|&&v| v > EFFECTIVITY_HIGH).count(),
        })
    }

    /// Whether every configuration lies in the band.
    pub fn in_band(&self) -> bool {
        self.under == 0 && self.over == 0
    }
}

impl std::fmt::Display for Effectivity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "effectivity (estimate ÷ true error) over {}: min {:.2}, median {:.2}, max {:.2}; {} below {EFFECTIVITY_LOW}, {} above {EFFECTIVITY_HIGH}",
            self.count, self.min, self.median, self.max, self.under, self.over
        )
    }
}
