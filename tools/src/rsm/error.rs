//! The one error type of the response-surface tools.

use thiserror::Error;

/// A table or request that cannot be fitted or solved. Each message is one sentence naming the
/// file, column or row and what is allowed, so it can be shown to the user as is.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum RsmError {
    /// The file cannot be read or is not a CSV table.
    #[error("{file}: cannot read: {cause}")]
    Read { file: String, cause: String },

    /// A column that the request names is not in the table.
    #[error("{file}: no column {name:?} (columns: {available})")]
    NoColumn {
        file: String,
        name: String,
        available: String,
    },

    /// A cell of a factor or the response is empty.
    #[error(
        "{file}: line {line}: {column} is missing; every run needs a value (drop the row or fill it)"
    )]
    Missing {
        file: String,
        line: usize,
        column: String,
    },

    /// A cell is not a number.
    #[error("{file}: line {line}: {column} = {value:?} is not a number")]
    NotNumber {
        file: String,
        line: usize,
        column: String,
        value: String,
    },

    /// A factor takes one value only: it has no effect that could be estimated.
    #[error(
        "{file}: factor column {column} is constant ({value}) in every run: it cannot be a factor (drop it from --factors)"
    )]
    Constant {
        file: String,
        column: String,
        value: f64,
    },

    /// Fewer runs than model terms (plus one for the error estimate).
    #[error(
        "{file}: {runs} runs are too few for the {model} model of {factors} factors: it has {terms} coefficients, so at least {need} runs are needed (use a smaller model or more runs)"
    )]
    TooFewRuns {
        file: String,
        runs: usize,
        model: String,
        factors: usize,
        terms: usize,
        need: usize,
    },

    /// The design cannot tell a term apart from the terms before it.
    #[error(
        "{file}: term {term} is aliased with the terms before it: this design cannot estimate it (use a smaller model, e.g. linear for a screening design)"
    )]
    Aliased { file: String, term: String },

    /// A request that makes no sense (unknown factor in a setting, a range that is empty...).
    #[error("{0}")]
    Request(String),

    /// Drawing a picture failed.
    #[error("cannot draw {what}: {problem}")]
    Plot { what: String, problem: String },
}
