//! Sweeps: a sweep file expanded into runs ([`plan`]), run on pinned cores with one MCAP
//! file each ([`execute`]), resumable through a manifest ([`manifest`]), and sharded over
//! Slurm job arrays ([`slurm`]).

pub mod design;
pub mod file;
pub mod plan;
pub mod target;

pub use plan::{Plan, PlannedRun};
