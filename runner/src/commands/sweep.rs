//! `tilth sweep plan|run|status|slurm`.

use crate::sweep::Plan;
use anyhow::Result;
use clap::{Args, Subcommand};
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Print the runs a sweep file expands into (coded and real values), running nothing.
    Plan(PlanArgs),
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Sweep file (TOML); the embedded demo (sweeps/demo.toml) when omitted.
    pub file: Option<PathBuf>,
    /// Print `{runs: [{id, coded, values, seed, ...}], ...}` as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn sweep(cmd: &SweepCommand, out: &mut dyn Write) -> Result<()> {
    match cmd {
        SweepCommand::Plan(args) => {
            let plan = Plan::load(args.file.as_deref())?;
            if args.json {
                serde_json::to_writer_pretty(&mut *out, &plan.to_json())?;
                writeln!(out)?;
            } else {
                plan.write_table(out)?;
            }
            Ok(())
        }
    }
}
