//! The subcommands.

pub mod bench;
pub mod laws;
pub mod reduce;
pub mod run;
pub mod sweep;
