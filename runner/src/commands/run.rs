//! `tilth run [FILE]`: load a scene, step it with a progress bar, print a summary.

use super::report::{RunReport, Sample};
use crate::config;
use crate::progress::Progress;
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
}

pub fn run(args: &RunArgs, out: &mut dyn Write) -> Result<()> {
    let t0 = Instant::now();
    let loaded = config::load_or_demo(args.file.as_ref(), args.threads.map(|t| t as usize))?;
    let setup_seconds = t0.elapsed().as_secs_f64();
    for w in &loaded.sim.warnings {
        eprintln!("warning: {}: {w}", loaded.info.origin);
    }
    let shown = loaded.sim.warnings.len();
    let report = simulate(loaded, !args.quiet, setup_seconds)?;
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

/// Steps the loaded scene to the end, recording samples; a kernel failure comes back as
/// the error (with the scene's name).
pub fn simulate(
    loaded: config::Loaded,
    show_progress: bool,
    setup_seconds: f64,
) -> Result<RunReport> {
    let config::Loaded {
        mut sim,
        threads,
        steps,
        sample_every,
        info,
    } = loaded;
    let mut progress = Progress::new(steps, show_progress);
    let mut samples = vec![];
    if sample_every.is_some() {
        samples.push(Sample::of(&sim));
    }
    let mut particle_steps: u64 = 0;
    let start = Instant::now();
    for k in 1..=steps {
        let stepped = sim.advance();
        if stepped.is_err() {
            progress.finish();
        }
        stepped.with_context(|| info.origin.clone())?;
        particle_steps += sim.particles.len() as u64;
        if sample_every.is_some_and(|e| k % e == 0) {
            samples.push(Sample::of(&sim));
        }
        progress.update(&sim);
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    progress.finish();
    Ok(RunReport::new(
        &sim,
        &info,
        threads,
        setup_seconds,
        wall_seconds,
        particle_steps,
        samples,
    ))
}
