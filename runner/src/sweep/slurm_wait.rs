//! The lab commands' runs as Slurm job arrays (`--slurm` of `compare`, `diagnose`, `fit` and
//! `synth`): what a user needs when a study outgrows one machine, such as the discovery proof
//! at the study's scale.
//!
//! The command writes the runs it needs (generated plans: one test, its conditions and seeds,
//! at one setting of the model) to `DIR/plan.json` of each plan's directory, submits one
//! array whose tasks each run `tilth sweep worker DIR...` (every N-th run of the plans
//! taken together, as `tilth sweep run` does in an array task), and waits for it
//! (`sbatch --wait`). Several settings go into one array where a command knows them
//! together (`diagnose`'s variants, `fit`'s Jacobian), so that they do not wait for each
//! other's slowest run. Then it reads the runs' summaries as after a local run, so the numbers
//! are the same bits either way: each run depends on its model, conditions and seed only.
//! Runs already done (an earlier job, a local run, the cache) are not submitted again.

use super::execute::{self, Options};
use super::job::{Status, write_atomic};
use super::manifest::Row;
use super::plan::{Factor, Plan, PlannedRun};
use anyhow::{Context, Result, anyhow, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

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

/// The array's script: task i of N runs every N-th run of the plans in `dirs`, counted
/// together.
fn script(dirs: &[PathBuf], runs: usize, tasks: usize, job: &SlurmJob) -> Result<String> {
    let exe = std::env::current_exe().context("cannot find the tilth executable")?;
    let cwd = std::env::current_dir().context("cannot read the current directory")?;
    let partition = job
        .partition
        .as_ref()
        .map(|p| format!("#SBATCH --partition={p}\n"))
        .unwrap_or_default();
    let logs = dirs[0].join("slurm");
    let list: Vec<String> = dirs
        .iter()
        .map(|d| format!("\"{}\"", d.display()))
        .collect();
    Ok(format!(
        r#"#!/bin/bash
# Written by tilth's --slurm: {runs} runs of {plans} plan(s), the first in {first}.
#SBATCH --job-name=tilth-lab
#SBATCH --array=0-{last}
#SBATCH --cpus-per-task=1
#SBATCH --time={time}
#SBATCH --signal=TERM@60
#SBATCH --chdir={cwd}
#SBATCH --output={logs}/%A_%a.out
{partition}
set -euo pipefail
exec "{exe}" sweep worker --cores "${{SLURM_CPUS_PER_TASK:-1}}" \
  {list}
"#,
        plans = dirs.len(),
        first = dirs[0].display(),
        last = tasks - 1,
        time = job.time,
        cwd = cwd.display(),
        logs = logs.display(),
        exe = exe.display(),
        list = list.join(" \\\n  "),
    ))
}

/// The runs of `plan` in `out` not done yet.
fn left(plan: &Plan, out: &Path) -> usize {
    plan.runs
        .iter()
        .filter(|r| Row::observe(out, r, &plan.fingerprint).status != Status::Done)
        .count()
}

/// Runs what is left of each plan (in its directory) as one Slurm array and waits for it.
/// Its script and the tasks' logs go to the first directory's `slurm/`.
pub fn run(batch: &[(Plan, PathBuf)], job: &SlurmJob, quiet: bool) -> Result<()> {
    let mut todo: Vec<(&Plan, PathBuf)> = vec![];
    for (plan, dir) in batch {
        let dir = std::path::absolute(dir)?;
        super::manifest::claim(&dir, plan)?;
        if left(plan, &dir) > 0 && !todo.iter().any(|(_, d)| *d == dir) {
            todo.push((plan, dir));
        }
    }
    if todo.is_empty() {
        return Ok(());
    }
    let runs: usize = todo.iter().map(|(p, _)| p.runs.len()).sum();
    let remaining: usize = todo.iter().map(|(p, d)| left(p, d)).sum();
    if todo.iter().any(|(p, _)| p.threads != 1) {
        bail!("--slurm: a plan with more than one thread per run is not supported");
    }
    let tasks = job.tasks.unwrap_or(remaining.min(100)).clamp(1, runs);
    for (plan, dir) in &todo {
        write_plan(plan, dir)?;
    }
    let dirs: Vec<PathBuf> = todo.iter().map(|(_, d)| d.clone()).collect();
    let logs = dirs[0].join("slurm");
    std::fs::create_dir_all(&logs).with_context(|| format!("{}: cannot create", logs.display()))?;
    let path = logs.join("job.sh");
    write_atomic(&path, script(&dirs, runs, tasks, job)?.as_bytes())?;
    if !quiet {
        eprintln!(
            "{remaining} runs of {} setting(s) as a Slurm array of {tasks} tasks ({}), waiting for it",
            todo.len(),
            path.display()
        );
    }
    let child = Command::new("sbatch")
        .arg("--wait")
        .arg(&path)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| anyhow!("--slurm: cannot start sbatch ({e}); it must be on PATH"))?;
    let done = wait_showing_progress(child, &todo, remaining, quiet)?;
    if !done.status.success() {
        // A task that ran out of time or failed: what finished is kept, the command can be
        // run again to go on. Say how many runs are missing and where the task logs are.
        let missing: usize = todo.iter().map(|(p, d)| left(p, d)).sum();
        bail!(
            "the Slurm job ended with {} ({missing} of {runs} runs not done); the tasks' logs are in {}; run the command again to resume\n{}",
            done.status,
            logs.display(),
            String::from_utf8_lossy(&done.stderr).trim()
        );
    }
    Ok(())
}

/// Waits for `sbatch --wait`, with a bar of the runs done (their summaries, polled) when
/// stderr is a terminal: an array's tasks report to Slurm's logs, not to this terminal.
fn wait_showing_progress(
    mut child: Child,
    todo: &[(&Plan, PathBuf)],
    remaining: usize,
    quiet: bool,
) -> Result<Output> {
    let bar = if !quiet && std::io::stderr().is_terminal() {
        let bar =
            ProgressBar::with_draw_target(Some(remaining as u64), ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template(
                "slurm {bar:25} {pos}/{len} runs done, {elapsed} elapsed, ETA {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar
    } else {
        ProgressBar::hidden()
    };
    let before: usize = todo.iter().map(|(p, d)| p.runs.len() - left(p, d)).sum();
    while child.try_wait()?.is_none() {
        if !bar.is_hidden() {
            let now: usize = todo.iter().map(|(p, d)| p.runs.len() - left(p, d)).sum();
            bar.set_position(now.saturating_sub(before) as u64);
        }
        std::thread::sleep(Duration::from_secs(2));
    }
    bar.finish_and_clear();
    Ok(child.wait_with_output()?)
}

/// Task (i, n)'s shard of a plan whose runs come after `offset` runs of the plans before it:
/// run id k has place offset + k - 1 in the count, and is the task's when that is i mod n,
/// that is when k - 1 is (i - offset) mod n.
fn plan_shard((i, n): (usize, usize), offset: usize) -> (usize, usize) {
    ((i + n - offset % n) % n, n)
}

/// `tilth sweep worker DIR...`: this array task's share of the plans in `dirs`. Their runs
/// are counted together, the first plan's first, so that task i of N runs the runs whose
/// place in that count is i modulo N: every task gets work when the plans are small.
pub fn work(dirs: &[PathBuf], cores: Option<usize>, shard: Option<(usize, usize)>) -> Result<()> {
    let stop = execute::stop_on_signals()?;
    let mut offset = 0;
    for dir in dirs {
        let plan = read_plan(dir)?;
        let mine = shard.map(|s| plan_shard(s, offset));
        offset += plan.runs.len();
        let opts = Options {
            out: dir.clone(),
            cores,
            shard: mine,
            retry_failed: false,
            show_progress: false,
            // Slurm places the task; a task pinning itself to the node's first cores would
            // share them with the other tasks on the node.
            pin: false,
        };
        let outcome = execute::execute(&plan, &opts, stop.clone())?;
        if outcome.interrupted {
            return Err(super::execute::SweepEnd::Interrupted.into());
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::plan_shard;
    use crate::sweep::execute::in_shard;

    #[test]
    fn every_run_of_several_plans_goes_to_one_task_and_the_tasks_share_them_evenly() {
        let sizes = [3usize, 5, 2, 7];
        let n = 4;
        let mut load = vec![0usize; n];
        let mut offset = 0;
        for size in sizes {
            for id in 1..=size {
                let owners: Vec<usize> = (0..n)
                    .filter(|&i| in_shard(id, Some(plan_shard((i, n), offset))))
                    .collect();
                assert_eq!(owners, [(offset + id - 1) % n], "run {id} after {offset}");
                load[owners[0]] += 1;
            }
            offset += size;
        }
        // 17 runs over 4 tasks: 5, 4, 4, 4.
        assert_eq!(load, [5, 4, 4, 4]);
    }
}
