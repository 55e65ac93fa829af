//! `tilth sweep slurm`: an sbatch script that runs a sweep as a job array.
//!
//! Every array task runs `tilth sweep run` on the same sweep file and output directory; the
//! task finds its shard in `SLURM_ARRAY_TASK_ID` / `SLURM_ARRAY_TASK_COUNT` and runs every
//! N-th run. Slurm sends SIGTERM a minute before the time limit (`--signal=TERM@60`): tilth
//! closes its MCAP chunks and exits, and resubmitting the same script resumes the sweep.

use super::plan::Plan;
use anyhow::{Context, Result};
use std::path::Path;

/// Absolute form of `p` (relative to the current directory), without resolving links.
fn absolute(p: &Path) -> Result<std::path::PathBuf> {
    std::path::absolute(p).with_context(|| format!("{}: cannot make absolute", p.display()))
}

/// What the job array asks of Slurm.
#[derive(Debug, Clone)]
pub struct ArrayOptions {
    /// Array tasks (default: one per run, at most 100).
    pub tasks: Option<usize>,
    /// Slurm partition (default: the cluster's default).
    pub partition: Option<String>,
    /// Time limit per task, Slurm syntax (e.g. 2:00:00).
    pub time: String,
}

/// The script for `plan` read from `file`, writing into `out`.
pub fn script(plan: &Plan, file: &Path, out: &Path, args: &ArrayOptions) -> Result<String> {
    let tasks = args
        .tasks
        .unwrap_or(plan.runs.len().min(100))
        .clamp(1, plan.runs.len());
    let exe = std::env::current_exe().context("cannot find the tilth executable")?;
    let file = absolute(file)?;
    let out = absolute(out)?;
    let partition = args
        .partition
        .as_ref()
        .map(|p| format!("#SBATCH --partition={p}\n"))
        .unwrap_or_default();
    Ok(format!(
        r#"#!/bin/bash
# Written by `tilth sweep slurm` for the sweep `{name}` ({runs} runs, {title}).
# Each array task runs every {tasks}-th run; resubmit this script to resume the sweep.
#SBATCH --job-name=tilth-{name}
#SBATCH --array=0-{last}
#SBATCH --cpus-per-task={threads}
#SBATCH --time={time}
#SBATCH --signal=TERM@60
#SBATCH --output={out}/slurm/%A_%a.out
{partition}
set -euo pipefail
exec "{exe}" sweep run "{file}" --out "{out}" --quiet
"#,
        name = plan.name,
        runs = plan.runs.len(),
        title = plan.title,
        last = tasks - 1,
        threads = plan.threads,
        time = args.time,
        out = out.display(),
        exe = exe.display(),
        file = file.display(),
    ))
}
