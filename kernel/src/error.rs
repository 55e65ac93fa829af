//! Errors raised while building a simulation or when a run fails.
//!
//! Construction refuses bad input before a step is taken; the step itself never panics and
//! reports a failure as [`KernelError::BlowUp`] naming the step and the likely cause.

use thiserror::Error;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum KernelError {
    /// A parameter outside its allowed range. `key` is a dotted path the caller can show.
    #[error("{key} = {value} is out of range: allowed {range} {unit}")]
    OutOfRange {
        key: String,
        value: f64,
        range: String,
        unit: String,
    },

    /// A law name that is not in the registry.
    #[error("unknown {slot} law '{name}'; known {slot} laws: {known}")]
    UnknownLaw {
        slot: String,
        name: String,
        known: String,
    },

    /// A parameter the chosen laws do not take.
    #[error("unknown key '{key}' in {context}; the chosen laws take: {allowed}")]
    UnknownKey {
        context: String,
        key: String,
        allowed: String,
    },

    /// A parameter a chosen law needs but was not given.
    #[error("missing key '{key}' in {context} (needed by law '{law}': {doc})")]
    MissingKey {
        context: String,
        key: String,
        law: String,
        doc: String,
    },

    /// Laws that cannot be combined, or other inconsistent input.
    #[error("{0}")]
    Invalid(String),

    /// Two particles overlap before the run starts.
    #[error(
        "particles {i} and {j} overlap by {overlap:.3e} m before the run starts (positions {pi:?} and {pj:?}); move them apart or shrink them"
    )]
    InitialOverlap {
        i: usize,
        j: usize,
        overlap: f64,
        pi: [f64; 3],
        pj: [f64; 3],
    },

    /// The run failed; `cause` says what most likely went wrong.
    #[error("run stopped at step {step} (t = {time:.6e} s): {what}. Likely cause: {cause}")]
    BlowUp {
        step: u64,
        time: f64,
        what: String,
        cause: String,
    },
}

pub type Result<T, E = KernelError> = std::result::Result<T, E>;
