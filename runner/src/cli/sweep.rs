//! `tilth sweep plan|run|status|slurm` (and `worker`, the array task of a lab command's
//! `--slurm`); the work is in `sweep::commands`.

use crate::sweep::commands::{self, PlanArgs, RunArgs, SlurmArgs, StatusArgs, WorkerArgs};
use crate::text::Ended;
use anyhow::Result;
use clap::Subcommand;
use std::io::Write;

#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Print the runs a sweep file expands into (coded and real values), running nothing.
    Plan(PlanArgs),
    /// Run a sweep: runs pinned to cores, one MCAP file each; re-running resumes it.
    Run(RunArgs),
    /// Merge the manifests of a sweep directory (all shards) into one status table.
    Status(StatusArgs),
    /// Write an sbatch script that runs the sweep as a Slurm job array.
    Slurm(SlurmArgs),
    /// One Slurm array task's share of the runs a lab command's `--slurm` wrote to each
    /// `DIR/plan.json` (the array's script calls it).
    #[command(hide = true)]
    Worker(WorkerArgs),
}

pub fn sweep(cmd: &SweepCommand, out: &mut dyn Write) -> Result<()> {
    let text = match cmd {
        SweepCommand::Plan(args) => commands::plan(args)?,
        SweepCommand::Status(args) => commands::status(args)?,
        SweepCommand::Slurm(args) => commands::slurm(args)?,
        SweepCommand::Worker(args) => return commands::worker(args),
        SweepCommand::Run(args) => {
            // The table is printed whether or not every run finished.
            let Ended { text, end } = commands::run(args)?;
            out.write_all(text.as_bytes())?;
            return end;
        }
    };
    out.write_all(text.as_bytes())?;
    Ok(())
}
