//! Sweeps: a sweep file expanded into runs ([`plan`]), run on pinned cores with one MCAP
//! file each ([`execute`]), resumable through a manifest ([`manifest`]), and sharded over
//! Slurm job arrays ([`slurm`]; the lab commands' runs: [`slurm_wait`]); [`commands`] are the
//! `tilth sweep` subcommands, [`single`] is `tilth run`,
//! [`bench`] the speed benchmarks.

pub mod bench;
pub mod bench_lab;
pub mod commands;
pub mod design;
pub mod execute;
pub mod file;
pub mod job;
pub mod manifest;
pub mod plan;
pub mod report;
pub mod single;
pub mod slurm;
pub mod slurm_wait;

pub use plan::{Plan, PlannedRun};
