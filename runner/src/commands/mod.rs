//! The subcommands.

pub mod bench;
pub mod laws;
pub mod report;
pub mod run;
pub mod sweep;
