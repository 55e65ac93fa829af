//! The one error type of the design module.

use thiserror::Error;

/// A design that cannot be built as asked. Each message is one plain sentence that names
/// the allowed range and what the sweep asked for, so it can be shown to the user as is.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DesignError {
    /// A full factorial design with no factor.
    #[error("a full factorial design takes at least 1 factor; this sweep has 0")]
    FactorialNoFactors,

    /// A factor of a full factorial design with fewer than 2 levels. `factor` is 1-based.
    #[error(
        "each factor of a full factorial design takes 2 or more levels; factor {factor} has {levels}"
    )]
    FactorialTooFewLevels { factor: usize, levels: usize },

    /// A full factorial design with more runs than [`super::MAX_FACTORIAL_RUNS`].
    /// `runs` saturates at `usize::MAX`.
    #[error("a full factorial design takes at most {max} runs; these levels make {runs}")]
    FactorialTooManyRuns { max: usize, runs: usize },

    /// A Plackett-Burman run count that has no generator here.
    #[error("a Plackett-Burman design has 8, 12, 16, 20 or 24 runs; this sweep asks for {runs}")]
    PlackettBurmanRuns { runs: usize },

    /// More (or fewer) factors than a Plackett-Burman design of `runs` runs can take.
    #[error(
        "{article} {runs}-run Plackett-Burman design takes 2 to {max} factors; this sweep has {factors}",
        article = if *.runs == 8 { "an" } else { "a" },
        max = .runs - 1
    )]
    PlackettBurmanFactors { runs: usize, factors: usize },

    /// More (or fewer) factors than the largest (smallest) Plackett-Burman design takes.
    #[error("a Plackett-Burman design takes 2 to 23 factors; this sweep has {factors}")]
    PlackettBurmanSize { factors: usize },

    /// A Box-Behnken design outside the tabulated 3 to 7 factors.
    #[error("a Box-Behnken design takes 3 to 7 factors; this sweep has {factors}")]
    BoxBehnkenFactors { factors: usize },

    /// A central composite design outside 2 to 8 factors.
    #[error("a central composite design takes 2 to 8 factors; this sweep has {factors}")]
    CentralCompositeFactors { factors: usize },

    /// A central composite axial distance that is not a finite positive number.
    #[error(
        "a central composite design's axial distance alpha must be a finite number above 0; this sweep has {alpha}"
    )]
    CentralCompositeAlpha { alpha: f64 },

    /// A Latin hypercube with no run or no factor.
    #[error(
        "a Latin hypercube takes at least 1 run and 1 factor; this sweep has {runs} runs and {factors} factors"
    )]
    LatinHypercubeSize { runs: usize, factors: usize },

    /// A Sobol' design with a run count outside what the generator supports.
    #[error("a Sobol design takes 1 to {max} runs; this sweep has {runs}")]
    SobolRuns { max: usize, runs: usize },

    /// A Sobol' design with more (or fewer) factors than the generator has dimensions.
    #[error("a Sobol design takes 1 to {max} factors; this sweep has {factors}")]
    SobolFactors { max: usize, factors: usize },

    /// A steepest-ascent direction and origin of different lengths.
    #[error(
        "a steepest-ascent path needs a direction and an origin with the same number of factors (1 or more); this sweep has {direction} and {origin}"
    )]
    SteepestAscentLengths { direction: usize, origin: usize },

    /// A steepest-ascent direction whose components are all zero.
    #[error(
        "a steepest-ascent direction needs at least 1 non-zero component; this sweep's is all zeros"
    )]
    SteepestAscentZeroDirection,

    /// A NaN or infinite value in a steepest-ascent direction or origin.
    #[error(
        "a steepest-ascent {what} takes finite numbers only; this sweep's has {value} at factor {factor}"
    )]
    SteepestAscentNotFinite {
        what: &'static str,
        factor: usize,
        value: f64,
    },

    /// A steepest-ascent step that is not a finite positive number.
    #[error(
        "a steepest-ascent step must be a finite number of coded units above 0; this sweep has {step}"
    )]
    SteepestAscentStep { step: f64 },
}
