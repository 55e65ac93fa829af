//! `tilth bench lab`: the wall time of each instrument's run, as a user waits for it (setup,
//! stepping, recording the MCAP file and reducing it), at the coarse preset and at the
//! study's scale, on 1 and 2 threads. The runs go through [`run_experiment`] exactly as
//! `tilth run FILE` does, into a scratch directory that is removed afterwards.

use super::single::run_experiment;
use crate::text::summary;
use anyhow::{Context, Result, bail};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Which size of each experiment to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// The experiment's coarse preset (bigger particles, less material).
    Coarse,
    /// The experiment file as written (the study's scale for `sweeps/experiments/`).
    Study,
}

impl Scale {
    fn name(self) -> &'static str {
        match self {
            Scale::Coarse => "coarse",
            Scale::Study => "study",
        }
    }
}

/// One `tilth bench lab`.
pub struct LabBench {
    /// Experiment files (`experiment = "..."`).
    pub files: Vec<PathBuf>,
    pub scales: Vec<Scale>,
    /// Worker threads per run, each value measured in turn.
    pub threads: Vec<u64>,
    /// Runs of each (file, scale, threads); the table shows the median.
    pub rounds: usize,
    /// Cores a sweep would fill with such runs (for the runs-per-hour column).
    pub cores: u64,
    /// Scratch directory for the runs' files (removed after each run).
    pub scratch: PathBuf,
    pub show_progress: bool,
}

/// One measured (file, scale, threads): the wall times of its rounds and what the last ran.
struct Measured {
    file: String,
    scale: Scale,
    threads: u64,
    walls: Vec<f64>,
    particles: u64,
    simulated_s: f64,
    steps: u64,
}

/// Runs every (file, scale, threads) `rounds` times and reports the medians as a table.
/// Every file is checked (readable, an experiment) before the first run starts.
pub fn lab(req: &LabBench) -> Result<String> {
    if req.rounds == 0 {
        bail!("--rounds must be at least 1");
    }
    if req.threads.is_empty() || req.scales.is_empty() || req.files.is_empty() {
        bail!("nothing to measure: give at least one file, scale and thread count");
    }
    for file in &req.files {
        for &scale in &req.scales {
            super::Plan::single(file, scale == Scale::Coarse)
                .with_context(|| format!("{}: not a runnable experiment file", file.display()))?;
        }
    }
    let total = req.files.len() * req.scales.len() * req.threads.len() * req.rounds;
    let mut done = 0;
    let mut rows = vec![];
    for file in &req.files {
        for &scale in &req.scales {
            for &threads in &req.threads {
                let mut row = Measured {
                    file: file.display().to_string(),
                    scale,
                    threads,
                    walls: vec![],
                    particles: 0,
                    simulated_s: 0.0,
                    steps: 0,
                };
                for _ in 0..req.rounds {
                    done += 1;
                    eprintln!(
                        "bench lab: run {done}/{total}: {} ({}, {threads} thread{})",
                        row.file,
                        scale.name(),
                        if threads == 1 { "" } else { "s" }
                    );
                    measure_one(req, file, &mut row)?;
                }
                rows.push(row);
            }
        }
    }
    summary(|out| write_table(req, &rows, out))
}

/// One timed run of `file` into a fresh scratch directory, added to `row`.
fn measure_one(req: &LabBench, file: &Path, row: &mut Measured) -> Result<()> {
    let dir = req.scratch.join(format!(
        "{}-{}-t{}",
        file.file_stem().unwrap_or_default().to_string_lossy(),
        row.scale.name(),
        row.threads
    ));
    if dir.exists() {
        std::fs::remove_dir_all(&dir)
            .with_context(|| format!("{}: cannot clear the scratch directory", dir.display()))?;
    }
    let start = Instant::now();
    let run = run_experiment(
        file,
        row.scale == Scale::Coarse,
        Some(row.threads),
        Some(dir.clone()),
        req.show_progress,
    )?;
    let wall = start.elapsed().as_secs_f64();
    run.status?;
    let report = run.summary.and_then(|s| s.report);
    let get = |k: &str| {
        report
            .as_ref()
            .and_then(|r| r.get(k))
            .and_then(|v| v.as_f64())
    };
    row.walls.push(wall);
    row.particles = get("particles").unwrap_or(0.0) as u64;
    row.simulated_s = get("simulated_time").unwrap_or(0.0);
    row.steps = get("steps").unwrap_or(0.0) as u64;
    std::fs::remove_dir_all(&dir)
        .with_context(|| format!("{}: cannot remove the scratch run", dir.display()))?;
    Ok(())
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

fn write_table(req: &LabBench, rows: &[Measured], out: &mut dyn Write) -> Result<()> {
    writeln!(
        out,
        "{:<40} {:<7} {:>7} {:>10} {:>10} {:>9} {:>10} {:>8}",
        "experiment", "scale", "threads", "wall s", "runs/h", "particles", "simulated", "steps"
    )?;
    for r in rows {
        let wall = median(&r.walls);
        // A sweep fills the cores with runs of this many threads each.
        let at_once = (req.cores / r.threads).max(1) as f64;
        writeln!(
            out,
            "{:<40} {:<7} {:>7} {:>10.2} {:>10.1} {:>9} {:>9.3}s {:>8}",
            r.file,
            r.scale.name(),
            r.threads,
            wall,
            at_once * 3600.0 / wall,
            r.particles,
            r.simulated_s,
            r.steps
        )?;
    }
    writeln!(
        out,
        "wall s: median of {} run{} (setup, stepping, MCAP recording and reduction); runs/h: \
         {} core{} filled with such runs, each as fast as alone (memory contention not counted)",
        req.rounds,
        if req.rounds == 1 { "" } else { "s" },
        req.cores,
        if req.cores == 1 { "" } else { "s" }
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn the_median_of_an_even_count_is_the_mean_of_the_middle_two() {
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 3.0, 2.0]), 2.5);
    }
}
