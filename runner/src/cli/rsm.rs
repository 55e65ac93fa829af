//! `tilth rsm fit|solve|path|next`: response surfaces on tables of runs (the work is in
//! `study::rsm`).

use crate::study::rsm::{self, FitArgs, NextArgs, PathArgs, SolveArgs};
use anyhow::Result;
use clap::Subcommand;

#[derive(Debug, Subcommand)]
pub enum RsmCommand {
    /// Fit a linear, 2FI or quadratic model and print its ANOVA (Type III), R^2, adjusted
    /// and predicted R^2, adequate precision, and the equation in coded and real units.
    Fit(FitArgs),
    /// Every setting whose predicted response hits a target (one per condition): a ridge
    /// when one target cannot separate the factors, and a statement saying so.
    Solve(SolveArgs),
    /// The path of steepest ascent (or descent) from a first-order fit, as a table and as the
    /// `[design]` block of a sweep file.
    Path(PathArgs),
    /// The best run of a path that was run (closest to the targets) and the next design's
    /// ranges around it.
    Next(NextArgs),
}

/// The summary of the `rsm` subcommand, for the CLI to print.
pub fn rsm(cmd: &RsmCommand) -> Result<String> {
    match cmd {
        RsmCommand::Fit(a) => rsm::fit(a),
        RsmCommand::Solve(a) => rsm::solve(a),
        RsmCommand::Path(a) => rsm::path(a),
        RsmCommand::Next(a) => rsm::next(a),
    }
}
