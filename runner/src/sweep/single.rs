//! One run outside a sweep: `tilth run FILE`. A scene file is stepped to its end in this
//! process ([`run_scene`]); an experiment file goes through the sweep machinery as a sweep of
//! one run ([`run_experiment`]: pinned core, MCAP file, summary, resumable).

use super::execute::{self, Options, SweepEnd};
use super::job::{RunSummary, Status, read_summary, run_dir};
use super::report::{RunCost, RunReport, Sample};
use crate::config;
use crate::progress::Progress;
use crate::text::{Ended, summary};
use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tilth_kernel::sim::INSERT_EVERY;

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

/// `tilth run [FILE]`: a scene file stepped here, an experiment file as a sweep of one run;
/// the summary as text or JSON.
pub fn run(args: &RunArgs) -> Result<Ended> {
    if let Some(file) = &args.file {
        let text = std::fs::read_to_string(file)
            .with_context(|| format!("{}: cannot read", file.display()))?;
        let is_experiment = toml::from_str::<toml::Value>(&text)
            .is_ok_and(|v| crate::lab::experiment::is_experiment(&v));
        if is_experiment {
            return experiment(args, file);
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
    let report = run_scene(loaded, !args.quiet, setup_seconds)?;
    for w in report.warnings.iter().skip(shown) {
        eprintln!("warning: {}: {w}", report.scene);
    }
    let text = summary(|out| {
        if args.json {
            serde_json::to_writer_pretty(&mut *out, &report)?;
            writeln!(out)?;
        } else {
            report.write_text(out)?;
        }
        Ok(())
    })?;
    Ok(Ended { text, end: Ok(()) })
}

/// `tilth run EXPERIMENT`: one run through the sweep machinery (pinned core, MCAP, summary).
fn experiment(args: &RunArgs, file: &Path) -> Result<Ended> {
    let run = run_experiment(
        file,
        args.coarse,
        args.threads,
        args.out.clone(),
        !args.quiet,
    )?;
    let text = summary(|out| {
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
        Ok(())
    })?;
    Ok(Ended {
        text,
        end: run.status,
    })
}

/// Steps the loaded scene to the end, recording samples; a kernel failure comes back as
/// the error (with the scene's name).
pub fn run_scene(
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
    let times_before = sim.times;
    let start = Instant::now();
    // Stepped in runs of steps, not one `advance` at a time: each `run` enters the thread
    // pool once, where a lone step pays for handing three phases to the workers and waking
    // the caller (most of a small scene's time). The runs end where factories insert (so
    // the particle count is known for each step) and where a sample is due.
    let mut k: u64 = 0;
    while k < steps {
        let next_insert = (sim.step / INSERT_EVERY + 1) * INSERT_EVERY - sim.step;
        let next_sample = sample_every.map_or(u64::MAX, |e| e - k % e);
        let n = next_insert.min(next_sample).min(steps - k);
        let before = sim.particles.len() as u64;
        let stepped = sim.run(n);
        if stepped.is_err() {
            progress.finish();
        }
        stepped.with_context(|| info.origin.clone())?;
        // Only the last step of a run can have inserted particles.
        particle_steps += (n - 1) * before + sim.particles.len() as u64;
        k += n;
        if sample_every.is_some_and(|e| k % e == 0) {
            samples.push(Sample::of(&sim));
        }
        progress.update(&sim);
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    progress.finish();
    let times = sim.times - times_before;
    let cost = RunCost {
        threads,
        setup_seconds,
        wall_seconds,
        times: &times,
        particle_steps,
    };
    Ok(RunReport::new(&sim, &info, cost, samples))
}

/// What [`run_experiment`] did: the experiment, where its files are, its summary and
/// whether it ran now or was found done.
pub struct ExperimentRun {
    /// The experiment file, as named.
    pub origin: String,
    /// The experiment's title.
    pub title: String,
    /// The output directory.
    pub dir: PathBuf,
    /// The run's summary (`None` if it wrote none).
    pub summary: Option<RunSummary>,
    /// Whether it ran now (false: found done in `dir`).
    pub ran: bool,
    /// `Err` when the run failed or was interrupted (its files are written either way, so
    /// they can be reported before the error).
    pub status: Result<()>,
}

/// Runs the experiment `file` as a sweep of one run into `out` (default `runs/<name>`).
pub fn run_experiment(
    file: &Path,
    coarse: bool,
    threads: Option<u64>,
    out: Option<PathBuf>,
    show_progress: bool,
) -> Result<ExperimentRun> {
    let mut plan = super::Plan::single(file, coarse)?;
    if let Some(t) = threads {
        plan.threads = t as usize;
    }
    let dir = out.unwrap_or_else(|| PathBuf::from("runs").join(&plan.name));
    let stop = execute::stop_on_signals()?;
    let opts = Options {
        out: dir.clone(),
        cores: Some(plan.threads),
        shard: None,
        retry_failed: true,
        show_progress,
        pin: false,
    };
    // A finished run in the directory is not run again: the caller says so.
    let outcome = execute::execute(&plan, &opts, stop)?;
    let summary = read_summary(&run_dir(&dir, 1));
    let row = &outcome.rows[0];
    let status = match row.status {
        Status::Done => Ok(()),
        Status::Interrupted => Err(SweepEnd::Interrupted.into()),
        _ => Err(anyhow::anyhow!(
            "{}: {}",
            plan.origin,
            row.error.clone().unwrap_or_else(|| "the run failed".into())
        )),
    };
    Ok(ExperimentRun {
        origin: plan.origin.clone(),
        title: plan.title.clone(),
        dir,
        summary,
        ran: outcome.ran > 0,
        status,
    })
}
