//! Validating an error estimate (issue 53): configurations drawn at random from a design
//! space with a seed unrelated to training, and the estimate's effectivity over them.
//!
//! The effectivity of an estimate is `estimate ÷ true error`: 1 is exact, below 1 an
//! underestimate (the dangerous side), above 1 an overestimate. The goal it is held to is the
//! band `[0.5, 10]` on every configuration checked: never under by more than 2×, never over by
//! more than 10×.

/// The lower end of the effectivity band an estimate is held to.
pub const EFFECTIVITY_LOW: f64 = 0.5;
/// The upper end.
pub const EFFECTIVITY_HIGH: f64 = 10.0;

/// Most random configurations one validation (or one greedy candidate set) draws.
pub const MAX_RANDOM: usize = 100_000;

/// A uniform number in [0, 1) from the SplitMix64 sequence at `state` (advanced): the one
/// generator of the design-space samplers.
pub fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// `count` configurations drawn uniformly from the box `ranges` with the SplitMix64 sequence
/// of `seed`, decorrelated from a Latin hypercube given the same number as its seed.
pub fn random_parameters(ranges: &[[f64; 2]], count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut state = seed ^ 0xD1B5_4A32_D192_ED03;
    (0..count).map(|_| ranges.iter().map(|r| r[0] + splitmix(&mut state) * (r[1] - r[0])).collect()).collect()
}

/// An estimate's effectivity over a set of configurations.
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
    /// Over `(estimate, true error)` pairs; `None` where no pair has a finite ratio.
    pub fn of(pairs: impl IntoIterator<Item = (f64, f64)>) -> Option<Self> {
        let mut values: Vec<f64> = pairs.into_iter().map(|(e, t)| e / t).filter(|v| v.is_finite()).collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn random_parameters_stay_in_the_box_and_depend_on_the_seed() {
        let ranges = [[0.5, 2.0], [-3.0, -1.0]];
        let a = random_parameters(&ranges, 500, 1);
        assert!(a.iter().all(|p| p[0] >= 0.5 && p[0] < 2.0 && p[1] >= -3.0 && p[1] < -1.0));
        assert_eq!(a, random_parameters(&ranges, 500, 1));
        assert_ne!(a, random_parameters(&ranges, 500, 2));
        // Spread over the box: every quarter of each axis is hit.
        for (axis, r) in ranges.iter().enumerate() {
            for q in 0..4 {
                let lo = r[0] + (r[1] - r[0]) * q as f64 / 4.0;
                let hi = r[0] + (r[1] - r[0]) * (q + 1) as f64 / 4.0;
                assert!(a.iter().any(|p| p[axis] >= lo && p[axis] < hi), "axis {axis} quarter {q}");
            }
        }
    }

    #[test]
    fn effectivity_counts_the_band() {
        let e = Effectivity::of([(1.0, 1.0), (0.2, 1.0), (30.0, 2.0), (3.0, 0.0), (f64::NAN, 1.0)]).unwrap();
        assert_eq!((e.count, e.under, e.over), (3, 1, 1));
        assert_eq!((e.min, e.median, e.max), (0.2, 1.0, 15.0));
        assert!(!e.in_band());
        assert!(Effectivity::of([(f64::NAN, 1.0)]).is_none());
    }
}
