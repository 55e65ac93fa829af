//! `tilth run [FILE]`: load a scene, step it with a progress bar, print a summary.

use crate::config;
use crate::sweep::job::run_dir;
use crate::sweep::single;
use anyhow::{Context, Result};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scene file (TOML); the embedded scene (sweeps/scenes/pile.toml) when omitted.
    pub file: Option<PathBuf>,
    /// Worker threads (overrides simulation.threads; results do not depend on it).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub threads: Option<u64>,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
    /// Print the summary as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Experiment files: the output directory for run.mcap and summary.json
    /// (default `runs/<file stem>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Experiment files: use the test's coarse preset (bigger particles, less material;
    /// under a minute).
    #[arg(long)]
    pub coarse: bool,
}

pub fn run(args: &RunArgs, out: &mut dyn Write) -> Result<()> {
    if let Some(file) = &args.file {
        let text = std::fs::read_to_string(file)
            .with_context(|| format!("{}: cannot read", file.display()))?;
        let is_experiment = toml::from_str::<toml::Value>(&text)
            .is_ok_and(|v| crate::lab::experiment::is_experiment(&v));
        if is_experiment {
            return run_experiment(args, file, out);
        }
    }
    if args.coarse || args.out.is_some() {
        anyhow::bail!("--coarse and --out are for experiment files (experiment = \"...\")");
    }
    let t0 = Instant::now();
    let loaded = config::load_or_demo(args.file.as_ref(), args.threads.map(|t| t as usize))?;
    let setup_seconds = t0.elapsed().as_secs_f64();
    for w in &loaded.sim.warnings {
        eprintln!("warning: {}: {w}", loaded.info.origin);
    }
    let shown = loaded.sim.warnings.len();
    let report = single::run_scene(loaded, !args.quiet, setup_seconds)?;
    for w in report.warnings.iter().skip(shown) {
        eprintln!("warning: {}: {w}", report.scene);
    }
    if args.json {
        serde_json::to_writer_pretty(&mut *out, &report)?;
        writeln!(out)?;
    } else {
        report.write_text(out)?;
    }
    Ok(())
}

/// `tilth run EXPERIMENT`: one run through the sweep machinery (pinned core, MCAP, summary).
fn run_experiment(args: &RunArgs, file: &std::path::Path, out: &mut dyn Write) -> Result<()> {
    let run = single::run_experiment(
        file,
        args.coarse,
        args.threads,
        args.out.clone(),
        !args.quiet,
    )?;
    if args.json {
        let v = run
            .summary
            .as_ref()
            .map(serde_json::to_value)
            .transpose()?
            .unwrap_or(serde_json::Value::Null);
        serde_json::to_writer_pretty(&mut *out, &v)?;
        writeln!(out)?;
    } else if let Some(s) = &run.summary {
        writeln!(out, "experiment   {} ({})", run.origin, run.title)?;
        writeln!(out, "status       {}", s.status.as_str())?;
        writeln!(out, "wall time    {:.1} s", s.wall_seconds)?;
        if let Some(x) = &s.experiment {
            writeln!(out, "results      {}", serde_json::to_string_pretty(x)?)?;
        }
        writeln!(out, "files        {}", run_dir(&run.dir, 1).display())?;
        if !run.ran {
            writeln!(
                out,
                "(already done in {}; delete it to run again)",
                run.dir.display()
            )?;
        }
    }
    run.status
}
