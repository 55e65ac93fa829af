//! The `tilth sweep plan|run|status|slurm|worker` subcommands as library calls: each takes
//! its parsed arguments and returns the text to print (progress goes to stderr).

use super::execute::{self, Options, SweepEnd};
use super::job::Status;
use super::{Plan, slurm, slurm_wait};
use crate::text::{Ended, summary};
use anyhow::{Context, Result, anyhow};
use clap::Args;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct WorkerArgs {
    /// The directories holding each plan's `plan.json`.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Cores to use (the array's script passes the task's).
    #[arg(long)]
    pub cores: Option<usize>,
}

#[derive(Debug, Args)]
pub struct PlanArgs {
    /// Sweep file (TOML); the embedded demo (sweeps/demo.toml) when omitted.
    pub file: Option<PathBuf>,
    /// Print `{runs: [{id, coded, values, seed, ...}], ...}` as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Sweep file (TOML); the embedded demo (sweeps/demo.toml) when omitted.
    pub file: Option<PathBuf>,
    /// Output directory (default `runs/<sweep name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Cores to use (default: every core this process may use).
    #[arg(long)]
    pub cores: Option<usize>,
    /// Run only every N-th run, starting at I (0-based): `--shard 1/4`. Inside a Slurm array
    /// task it defaults to the task's index and the array's size.
    #[arg(long, value_parser = parse_shard)]
    pub shard: Option<(usize, usize)>,
    /// Run failed runs again (by default a failed run, being deterministic, is kept).
    #[arg(long)]
    pub retry_failed: bool,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct StatusArgs {
    /// A sweep's output directory.
    pub dir: PathBuf,
    /// Print the merged manifest as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// Sweep file (TOML).
    pub file: PathBuf,
    /// Output directory the array tasks write to (default `runs/<sweep name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Array tasks (default: one per run, at most 100).
    #[arg(long)]
    pub tasks: Option<usize>,
    /// Slurm partition (default: the cluster's default).
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task, Slurm syntax (e.g. 2:00:00).
    #[arg(long, default_value = "12:00:00")]
    pub time: String,
    /// Write the script here instead of printing it.
    #[arg(long)]
    pub write: Option<PathBuf>,
}

/// `I/N` with I < N.
pub fn parse_shard(s: &str) -> Result<(usize, usize), String> {
    let (i, n) = s
        .split_once('/')
        .ok_or_else(|| format!("`{s}`: write I/N, e.g. 0/4"))?;
    let i: usize = i
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: I must be a number"))?;
    let n: usize = n
        .trim()
        .parse()
        .map_err(|_| format!("`{s}`: N must be a number"))?;
    if n == 0 || i >= n {
        return Err(format!("`{s}`: allowed 0 <= I < N"));
    }
    Ok((i, n))
}

/// The shard of a Slurm array task, from its environment.
pub fn slurm_shard() -> Result<Option<(usize, usize)>> {
    let var = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<usize>().ok());
    match (var("SLURM_ARRAY_TASK_ID"), var("SLURM_ARRAY_TASK_COUNT")) {
        (Some(id), Some(count)) => {
            let min = var("SLURM_ARRAY_TASK_MIN").unwrap_or(0);
            let i = id.checked_sub(min).filter(|&i| i < count).ok_or_else(|| {
                anyhow!("SLURM_ARRAY_TASK_ID = {id} does not fit an array of {count} tasks from {min}; submit a contiguous array (--array=0-{})", count - 1)
            })?;
            Ok(Some((i, count)))
        }
        _ => Ok(None),
    }
}

fn default_out(plan: &Plan) -> PathBuf {
    Path::new("runs").join(&plan.name)
}

/// `tilth sweep plan`: the runs a sweep file expands into, as a table or JSON.
pub fn plan(args: &PlanArgs) -> Result<String> {
    let plan = Plan::load(args.file.as_deref())?;
    summary(|text| {
        if args.json {
            serde_json::to_writer_pretty(&mut *text, &plan.to_json())?;
            writeln!(text)?;
        } else {
            plan.write_table(text)?;
        }
        Ok(())
    })
}

/// `tilth sweep worker`: one Slurm array task's share of the lab commands' plans.
pub fn worker(args: &WorkerArgs) -> Result<()> {
    slurm_wait::work(&args.dirs, args.cores, slurm_shard()?)
}

/// `tilth sweep slurm`: the sbatch script of the sweep's job array, printed or written to
/// `--write` (then the text says how to submit it). Creates the array's log directory.
pub fn slurm(args: &SlurmArgs) -> Result<String> {
    let plan = Plan::load(Some(&args.file))?;
    let dir = args.out.clone().unwrap_or_else(|| default_out(&plan));
    let options = slurm::ArrayOptions {
        tasks: args.tasks,
        partition: args.partition.clone(),
        time: args.time.clone(),
    };
    let script = slurm::script(&plan, &args.file, &dir, &options)?;
    // sbatch needs the log directory to exist before the tasks start.
    let logs = dir.join("slurm");
    std::fs::create_dir_all(&logs).with_context(|| format!("{}: cannot create", logs.display()))?;
    match &args.write {
        Some(p) => {
            std::fs::write(p, &script).with_context(|| format!("{}: cannot write", p.display()))?;
            Ok(format!(
                "wrote {}; submit it with: sbatch {}\n",
                p.display(),
                p.display()
            ))
        }
        None => Ok(script),
    }
}

/// `tilth sweep run`: executes the sweep (resuming what is done) and writes its results table.
pub fn run(args: &RunArgs) -> Result<Ended> {
    let plan = Plan::load(args.file.as_deref())?;
    let shard = match args.shard {
        Some(s) => Some(s),
        None => slurm_shard()?,
    };
    let dir = args.out.clone().unwrap_or_else(|| default_out(&plan));
    let stop = execute::stop_on_signals()?;
    let opts = Options {
        out: dir.clone(),
        cores: args.cores,
        shard,
        retry_failed: args.retry_failed,
        show_progress: !args.quiet,
        pin: true,
    };
    let shard_text = shard
        .map(|(i, n)| format!(", shard {i}/{n}"))
        .unwrap_or_default();
    eprintln!(
        "{}: {} runs{shard_text} into {}",
        plan.name,
        plan.runs.len(),
        dir.display()
    );
    let outcome = execute::execute(&plan, &opts, stop)?;
    let table = execute::write_results(&plan, &dir)?;
    let count = |s: Status| outcome.rows.iter().filter(|r| r.status == s).count();
    let (done, failed) = (count(Status::Done), count(Status::Failed));
    let text = summary(|out| {
        execute::print_table(&table, out)?;
        for line in execute::scatter_lines(&plan, &table) {
            writeln!(out, "{line}")?;
        }
        writeln!(
            out,
            "\n{done} of {} runs done ({} run now, {failed} failed); results: {}, manifest: {}",
            outcome.rows.len(),
            outcome.ran,
            dir.join("results.csv").display(),
            super::manifest::path(&dir, shard).display()
        )?;
        Ok(())
    })?;
    let end = if outcome.interrupted {
        Err(SweepEnd::Interrupted.into())
    } else if failed > 0 {
        Err(SweepEnd::Failed(failed).into())
    } else {
        Ok(())
    };
    Ok(Ended { text, end })
}

/// `tilth sweep status`: the merged manifests of a sweep directory, as a table or JSON.
pub fn status(args: &StatusArgs) -> Result<String> {
    let merged = super::manifest::read_all(&args.dir)?;
    summary(|out| write_status(&merged, args.json, out))
}

fn write_status(merged: &super::manifest::Manifest, json: bool, out: &mut dyn Write) -> Result<()> {
    if json {
        serde_json::to_writer_pretty(&mut *out, merged)?;
        writeln!(out)?;
        return Ok(());
    }
    let count = |s: Status| merged.rows.iter().filter(|r| r.status == s).count();
    writeln!(
        out,
        "{}: {} runs: {} done, {} failed, {} interrupted, {} running, {} pending",
        merged.sweep,
        merged.rows.len(),
        count(Status::Done),
        count(Status::Failed),
        count(Status::Interrupted),
        count(Status::Running),
        count(Status::Pending)
    )?;
    for r in &merged.rows {
        writeln!(
            out,
            "{:>4}  {:<11}  {:>8}  {}  {}",
            r.id,
            r.status.as_str(),
            r.wall_seconds
                .map(|w| format!("{w:.1} s"))
                .unwrap_or_default(),
            r.mcap.as_deref().unwrap_or("-"),
            r.error.as_deref().unwrap_or("")
        )?;
    }
    Ok(())
}
