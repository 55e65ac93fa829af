//! The lab commands' runs as Slurm job arrays (`--slurm` of `compare`, `diagnose`, `fit` and
//! `synth`): what a user needs when a study outgrows one machine, such as the discovery proof
//! at the study's scale.
//!
//! The command writes the runs it needs (a generated plan: one test, its conditions and
//! seeds) to `DIR/plan.json`, submits an array whose tasks each run `tilth sweep worker DIR`
//! (every N-th run, as `tilth sweep run` does in an array task), and waits for it
//! (`sbatch --wait`). Then it reads the runs' summaries as after a local run, so the numbers
//! are the same bits either way: each run depends on its model, conditions and seed only.
//! Runs already done (an earlier job, a local run, the cache) are not submitted again.

use super::execute::{self, Options};
use super::job::{Status, write_atomic};
use super::manifest::Row;
use super::plan::{Factor, Plan, PlannedRun};
use anyhow::{Context, Result, anyhow, bail};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;

/// How the array is submitted.
#[derive(Debug, Clone)]
pub struct SlurmJob {
    /// Array tasks (default: one per run left, at most 100).
    pub tasks: Option<usize>,
    /// Time limit per task, Slurm syntax.
    pub time: String,
    pub partition: Option<String>,
}

/// A generated plan as the workers read it.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanFile {
    name: String,
    experiment_text: String,
    /// The directory the experiment's relative paths (its model) are read from.
    dir: PathBuf,
    factors: Vec<FactorFile>,
    runs: Vec<PlannedRun>,
    fingerprint: String,
}

/// A factor in `plan.json`: a generated plan's factors have no range (NaN), which JSON
/// cannot hold, so a missing bound is written as null.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FactorFile {
    name: String,
    target: String,
    label: Option<String>,
    unit: Option<String>,
    low: Option<f64>,
    high: Option<f64>,
}

impl From<&Factor> for FactorFile {
    fn from(f: &Factor) -> Self {
        let finite = |x: f64| x.is_finite().then_some(x);
        FactorFile {
            name: f.name.clone(),
            target: f.target.clone(),
            label: f.label.clone(),
            unit: f.unit.clone(),
            low: finite(f.low),
            high: finite(f.high),
        }
    }
}

impl From<FactorFile> for Factor {
    fn from(f: FactorFile) -> Self {
        Factor {
            name: f.name,
            target: f.target,
            label: f.label,
            unit: f.unit,
            low: f.low.unwrap_or(f64::NAN),
            high: f.high.unwrap_or(f64::NAN),
        }
    }
}

const PLAN_FILE: &str = "plan.json";

/// The plan a worker runs, from `out/plan.json`.
pub fn read_plan(out: &Path) -> Result<Plan> {
    let path = out.join(PLAN_FILE);
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let f: PlanFile = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a plan written by --slurm", path.display()))?;
    let mut plan = Plan::generated(
        &f.name,
        f.experiment_text,
        &f.dir,
        f.factors.into_iter().map(Factor::from).collect(),
        f.runs,
    )?;
    plan.fingerprint = f.fingerprint;
    Ok(plan)
}

fn write_plan(plan: &Plan, out: &Path) -> Result<()> {
    let f = PlanFile {
        name: plan.name.clone(),
        experiment_text: plan.scene.text.clone(),
        dir: std::path::absolute(&plan.scene.dir)?,
        factors: plan.factors.iter().map(FactorFile::from).collect(),
        runs: plan.runs.clone(),
        fingerprint: plan.fingerprint.clone(),
    };
    write_atomic(&out.join(PLAN_FILE), &serde_json::to_vec_pretty(&f)?)
}

/// The array's script: each task runs its share of `out/plan.json`.
fn script(plan: &Plan, out: &Path, tasks: usize, job: &SlurmJob) -> Result<String> {
    let exe = std::env::current_exe().context("cannot find the tilth executable")?;
    let cwd = std::env::current_dir().context("cannot read the current directory")?;
    let partition = job
        .partition
        .as_ref()
        .map(|p| format!("#SBATCH --partition={p}\n"))
        .unwrap_or_default();
    Ok(format!(
        r#"#!/bin/bash
# Written by tilth's --slurm for the runs of `{name}` in {out} ({runs} runs).
#SBATCH --job-name=tilth-{name}
#SBATCH --array=0-{last}
#SBATCH --cpus-per-task={threads}
#SBATCH --time={time}
#SBATCH --signal=TERM@60
#SBATCH --chdir={cwd}
#SBATCH --output={out}/slurm/%A_%a.out
{partition}
set -euo pipefail
exec "{exe}" sweep worker "{out}" --cores "${{SLURM_CPUS_PER_TASK:-{threads}}}"
"#,
        name = plan.name,
        runs = plan.runs.len(),
        last = tasks - 1,
        threads = plan.threads,
        time = job.time,
        cwd = cwd.display(),
        out = out.display(),
        exe = exe.display(),
    ))
}

/// Runs what is left of `plan` in `out` as a Slurm array and waits for it.
pub fn run(plan: &Plan, out: &Path, job: &SlurmJob, quiet: bool) -> Result<()> {
    let out = std::path::absolute(out)?;
    super::manifest::claim(&out, plan)?;
    let left = plan
        .runs
        .iter()
        .filter(|r| Row::observe(&out, r, &plan.fingerprint).status != Status::Done)
        .count();
    if left == 0 {
        return Ok(());
    }
    let tasks = job.tasks.unwrap_or(left.min(100)).clamp(1, plan.runs.len());
    write_plan(plan, &out)?;
    let logs = out.join("slurm");
    std::fs::create_dir_all(&logs).with_context(|| format!("{}: cannot create", logs.display()))?;
    let path = logs.join("job.sh");
    write_atomic(&path, script(plan, &out, tasks, job)?.as_bytes())?;
    if !quiet {
        eprintln!(
            "{}: {left} runs as a Slurm array of {tasks} tasks ({}), waiting for it",
            plan.name,
            path.display()
        );
    }
    let done = Command::new("sbatch")
        .arg("--wait")
        .arg(&path)
        .output()
        .map_err(|e| anyhow!("--slurm: cannot start sbatch ({e}); it must be on PATH"))?;
    if !done.status.success() {
        // A task that ran out of time or failed: what finished is kept, the command can be
        // run again to go on. Say which runs are missing and where the task logs are.
        let missing = plan
            .runs
            .iter()
            .filter(|r| Row::observe(&out, r, &plan.fingerprint).status != Status::Done)
            .count();
        bail!(
            "{}: the Slurm job ended with {} ({} of {} runs not done); the tasks' logs are in {}; run the command again to resume\n{}",
            plan.name,
            done.status,
            missing,
            plan.runs.len(),
            logs.display(),
            String::from_utf8_lossy(&done.stderr).trim()
        );
    }
    Ok(())
}

/// `tilth sweep worker DIR`: this array task's share of `DIR/plan.json`.
pub fn work(out: &Path, cores: Option<usize>, shard: Option<(usize, usize)>) -> Result<()> {
    let plan = read_plan(out)?;
    let opts = Options {
        out: out.to_path_buf(),
        cores,
        shard,
        retry_failed: false,
        show_progress: false,
        // Slurm places the task; a task pinning itself to the node's first cores would share
        // them with the other tasks on the node.
        pin: false,
    };
    let stop = execute::stop_on_signals()?;
    let outcome = execute::execute(&plan, &opts, stop)?;
    if outcome.interrupted {
        return Err(crate::commands::sweep::SweepEnd::Interrupted.into());
    }
    Ok(())
}
