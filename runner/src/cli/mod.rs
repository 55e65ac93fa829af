//! The command-line surface: the `tilth` commands and their arguments. Each command calls
//! one library function and prints what it returns (`sweep` and `rsm` have subcommands,
//! `bench` its benchmarks, in files of their own).

use crate::study::{calibrate, check, compare, diagnose, fit, next, project_report, reduce, synth};
mod bench;
mod laws;
mod rsm;
mod sweep;

use crate::sweep::single;
use crate::text::Ended;
use anyhow::Result;
use clap::{Parser, Subcommand};
use std::io::Write;

/// tilth: a deterministic DEM workbench for calibrating soil models.
#[derive(Debug, Parser)]
#[command(name = "tilth", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene file (TOML) and print a summary; without FILE, run the embedded demo.
    Run(single::RunArgs),
    /// List every contact law: slot, parameters with units, ranges and defaults.
    Laws,
    /// Parameter sweeps: plan, run (pinned cores, one MCAP per run, resumable), status, Slurm.
    Sweep {
        #[command(subcommand)]
        command: sweep::SweepCommand,
    },
    /// Reduce run MCAP files to the study's numbers: repose angle, peak shear force, UCS,
    /// slide angle on the tilting plate.
    Reduce(reduce::ReduceArgs),
    /// Simulate every measured condition of a data file and compare (compare.json/csv/md).
    Compare(compare::CompareArgs),
    /// Check a measurement file: every row (and, with --model, its ranges), and whether its
    /// direct shear and UCS rows can come from one material at all.
    Check(check::CheckArgs),
    /// Which candidate effect ([candidates] in the model file) explains the residuals: a
    /// score test per candidate after what the free parameters absorb.
    Diagnose(diagnose::DiagnoseArgs),
    /// Which measurement would tell apart the candidates a diagnosis could not: ranks a
    /// menu of tests and conditions by how likely each is to settle the case (Box and
    /// Hill); writes conditions.csv.
    Next(next::NextArgs),
    /// Every compare run of a project as a history: errors per model version, the plots
    /// side by side, one offline HTML page.
    Report(project_report::ReportArgs),
    /// Make a measurement file from a truth model plus noise (to test a model against data
    /// whose missing effect is known).
    Synth(synth::SynthArgs),
    /// Fit free model parameters to one test's measurements: surface runs, solve, refine
    /// with direct runs, uncertainty; writes a calibrated model file.
    Calibrate(calibrate::CalibrateArgs),
    /// Fit free parameters (and candidate strengths) to every measured row at once:
    /// Levenberg-Marquardt on simulations; writes the fitted model file.
    Fit(fit::FitArgs),
    /// Response surfaces on tables of runs: fit with ANOVA, solve for targets, steepest ascent.
    Rsm {
        #[command(subcommand)]
        command: rsm::RsmCommand,
    },
    /// Speed benchmarks.
    Bench {
        #[command(subcommand)]
        which: bench::Bench,
    },
}

/// Runs the parsed command, writing results to `out` (progress and warnings go to stderr).
pub fn execute(cli: Cli, out: &mut dyn Write) -> Result<()> {
    match cli.command {
        Command::Run(args) => {
            // A run's files are reported whether or not it finished.
            let Ended { text, end } = single::run(&args)?;
            print(out, text)?;
            end
        }
        Command::Laws => laws::laws(out),
        Command::Bench { which } => bench::bench(&which, out),
        Command::Sweep { command } => sweep::sweep(&command, out),
        Command::Reduce(args) => print(out, reduce::reduce(&args)?),
        Command::Compare(args) => print(out, compare::compare(&args)?),
        Command::Check(args) => print(out, check::check(&args)?),
        Command::Rsm { command } => print(out, rsm::rsm(&command)?),
        Command::Calibrate(args) => print(out, calibrate::calibrate(&args)?),
        Command::Synth(args) => print(out, synth::synth(&args)?),
        Command::Report(args) => print(out, project_report::report(&args)?),
        Command::Diagnose(args) => print(out, diagnose::diagnose(&args)?),
        Command::Next(args) => print(out, next::next(&args)?),
        Command::Fit(args) => print(out, fit::fit(&args)?),
    }
}

/// Writes a library function's summary to stdout.
fn print(out: &mut dyn Write, text: String) -> Result<()> {
    out.write_all(text.as_bytes())?;
    Ok(())
}
