//! The subcommands.

pub mod bench;
pub mod calibrate;
pub mod calibrate_report;
pub mod compare;
pub mod diagnose;
pub mod laws;
pub mod measurements;
pub mod project_report;
pub mod reduce;
pub mod report;
pub mod rsm;
pub mod rsm_plot;
pub mod rsm_print;
pub mod run;
pub mod sweep;
pub mod synth;
