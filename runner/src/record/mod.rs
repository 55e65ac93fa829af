//! Recording a run into an MCAP file that Foxglove and Rerun replay.
//!
//! The simulation thread takes cheap [`snapshot`]s at each channel's frame rate and hands them
//! over a bounded channel to one writer thread per run ([`writer`]), which encodes them with
//! Foxglove's well-known protobuf schemas ([`encode`]) and writes zstd chunks with the `mcap`
//! crate. The layout (topics, units, metadata) is described in `runner/MCAP.md`.

pub mod encode;
pub mod rates;
pub mod snapshot;
pub mod writer;

pub use crate::config::WallShape;
pub use rates::{FrameRates, RecordSection};
pub use snapshot::Record;
pub use writer::{Recorder, RecorderStats};
