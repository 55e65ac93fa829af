//! The one error type of the reducers.

use thiserror::Error;

/// A run that cannot be reduced. Each message is one sentence that names the file (or the
/// part of the analysis) and what is wrong with it, so it can be shown to the user as is.
///
/// The causes are part of each message, not error sources, so that a chain printer
/// (anyhow's `{:#}`) does not print them twice.
///
/// A truncated file is *not* an error: it is read up to its last complete chunk and the
/// result says `complete: false` (see [`super::Completeness`]).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReduceError {
    /// The file cannot be opened or read.
    #[error("{file}: cannot read: {cause}")]
    Io { file: String, cause: std::io::Error },

    /// The file does not start like an MCAP file (nothing in it can be read).
    #[error("{file}: not an MCAP file: {cause}")]
    NotMcap {
        file: String,
        cause: mcap::McapError,
    },

    /// A channel this reducer reads carries another schema than the contract says.
    #[error("{file}: topic {topic} carries {found:?} messages, expected {expected:?}")]
    Schema {
        file: String,
        topic: String,
        found: String,
        expected: &'static str,
    },

    /// A message that does not decode as its schema.
    #[error("{file}: topic {topic}: cannot decode a message: {cause}")]
    Decode {
        file: String,
        topic: String,
        cause: prost::DecodeError,
    },

    /// A point cloud whose fields or data do not match the `/particles` layout.
    #[error("{file}: /particles: {problem}")]
    CloudLayout { file: String, problem: String },

    /// A metadata record or key the reducer needs is missing.
    #[error("{file}: metadata record {record:?} has no key {key:?}")]
    MissingMetadata {
        file: String,
        record: String,
        key: String,
    },

    /// A metadata value that should be a finite number is not one.
    #[error("{file}: metadata {record}.{key} = {value:?} is not a finite number")]
    BadMetadata {
        file: String,
        record: String,
        key: String,
        value: String,
    },

    /// The file holds another experiment than the reducer reads.
    #[error("{file}: tilth.experiment type is {found:?}; this reducer reads {expected:?} runs")]
    WrongExperiment {
        file: String,
        expected: &'static str,
        found: String,
    },

    /// A topic the reducer needs has no message in the (readable part of the) file.
    #[error("{file}: no message on {topic}")]
    MissingTopic { file: String, topic: String },

    /// Too few usable data points for a fit or a peak.
    #[error("{what}: {have} usable points, need at least {need}")]
    TooFewPoints {
        what: String,
        have: usize,
        need: usize,
    },

    /// Data that cannot give an answer (all points at one abscissa, a non-positive area, ...).
    #[error("{0}")]
    Degenerate(String),

    /// Drawing a picture failed.
    #[error("cannot draw {what}: {problem}")]
    Plot { what: String, problem: String },

    /// An analysis error, with the file it came from.
    #[error("{file}: {inner}")]
    InFile {
        file: String,
        inner: Box<ReduceError>,
    },
}

impl ReduceError {
    /// Puts the file name in front of an analysis error that does not carry it yet.
    pub fn in_file(self, file: &str) -> ReduceError {
        match self {
            e @ (ReduceError::TooFewPoints { .. }
            | ReduceError::Degenerate(_)
            | ReduceError::Plot { .. }) => ReduceError::InFile {
                file: file.to_string(),
                inner: Box::new(e),
            },
            e => e,
        }
    }
}
