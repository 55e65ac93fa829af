//! One run of a sweep: its scene, its pinned cores, its MCAP file and its summary.
//!
//! Files in the run's directory: `run.mcap.partial` while it runs, renamed to `run.mcap` when
//! it completes, then `summary.json` (written last, atomically: its presence with status
//! `done` is what marks the run complete for a resumed sweep).
//!
//! [`layout`] says what the recording holds, [`stepping`] steps the run and records it, and
//! [`reduce`] measures the finished recording.

mod layout;
mod reduce;
mod stepping;

use super::plan::{Plan, PlannedRun, innermost};
use super::report::{RunCost, RunReport};
use crate::lab::observe::{self, Heap};
use crate::record::writer::RunLayout;
use crate::record::{Recorder, RecorderStats};
use anyhow::{Context, Result};
use core_affinity::CoreId;
use layout::run_layout;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;
use stepping::Stepping;
use tilth_kernel::sim::ThreadStart;

pub use reduce::reduce_run;

/// Progress is shown in thousandths.
const PROGRESS_SCALE: u64 = 1000;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Pending,
    Running,
    Done,
    Failed,
    Interrupted,
}

impl Status {
    pub fn as_str(self) -> &'static str {
        match self {
            Status::Pending => "pending",
            Status::Running => "running",
            Status::Done => "done",
            Status::Failed => "failed",
            Status::Interrupted => "interrupted",
        }
    }
}

/// `summary.json` of a run.
#[derive(Debug, Serialize, Deserialize)]
pub struct RunSummary {
    pub sweep: String,
    /// The plan's fingerprint: a summary of another sweep is not taken for this one's.
    pub fingerprint: String,
    pub run: PlannedRun,
    pub status: Status,
    pub error: Option<String>,
    /// The MCAP file, relative to the run directory.
    pub mcap: Option<String>,
    pub wall_seconds: f64,
    /// The heap on the tray at the end (scenes with a `tray` disc).
    pub heap: Option<serde_json::Value>,
    /// The kernel's end-of-run report.
    pub report: Option<serde_json::Value>,
    pub recorder: Option<RecorderStats>,
    /// Cores the run was pinned to.
    pub cores: Vec<usize>,
    /// The observable reduced from the run's MCAP file by the study's method
    /// (`repose_angle_deg`, `peak_shear_force_n` or `ucs_kpa`), or `{"error": ...}`.
    #[serde(default)]
    pub reduced: Option<serde_json::Value>,
    /// The experiment's own results (settling, phases, inertial number, warnings).
    #[serde(default)]
    pub experiment: Option<serde_json::Value>,
}

/// Shared with the sweep's progress display.
#[derive(Debug, Default)]
pub struct Live {
    pub step: AtomicU64,
    pub steps: AtomicU64,
}

/// `DIR/runs/NNN`.
pub fn run_dir(out: &Path, id: usize) -> PathBuf {
    out.join("runs").join(format!("{id:03}"))
}

/// Reads a run's summary, if it has one.
pub fn read_summary(dir: &Path) -> Option<RunSummary> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// Writes `path` atomically (a temporary file renamed over it). The temporary name is unique
/// to the process and the call: shards of one sweep (Slurm array tasks started together)
/// write the same files into one directory, and a shared temporary name let one shard rename
/// away the other's file before its own rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".{}.{n}.tmp", std::process::id()));
    let tmp = path.with_file_name(name);
    std::fs::write(&tmp, bytes).with_context(|| format!("{}: cannot write", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| format!("{}: cannot write", path.display()))
}

/// Runs `run` on `cores`, stopping early (interrupted) when `stop` is set.
pub fn run_job(
    plan: &Plan,
    run: &PlannedRun,
    out: &Path,
    cores: &[CoreId],
    pin: bool,
    stop: &AtomicBool,
    live: &Live,
) -> RunSummary {
    let dir = run_dir(out, run.id);
    let start = Instant::now();
    let mut summary = RunSummary {
        sweep: plan.name.clone(),
        fingerprint: plan.fingerprint.clone(),
        run: run.clone(),
        status: Status::Failed,
        error: None,
        mcap: None,
        wall_seconds: 0.0,
        heap: None,
        report: None,
        recorder: None,
        cores: cores.iter().map(|c| c.id).collect(),
        experiment: None,
        reduced: None,
    };
    match simulate(plan, run, &dir, cores, pin, stop, live, &mut summary) {
        Ok(status) => summary.status = status,
        Err(e) => {
            summary.status = Status::Failed;
            summary.error = Some(innermost(&e));
        }
    }
    summary.wall_seconds = start.elapsed().as_secs_f64();
    if summary.status != Status::Interrupted {
        // An interrupted run leaves no summary, so a resumed sweep runs it again.
        let text = serde_json::to_vec_pretty(&summary).unwrap_or_default();
        if let Err(e) = write_atomic(&dir.join("summary.json"), &text) {
            summary.status = Status::Failed;
            summary.error = Some(format!("{e:#}"));
        }
    }
    summary
}

// The run's whole context, passed through once from `run_job`.
#[allow(clippy::too_many_arguments)]
fn simulate(
    plan: &Plan,
    run: &PlannedRun,
    dir: &Path,
    cores: &[CoreId],
    pin: bool,
    stop: &AtomicBool,
    live: &Live,
    summary: &mut RunSummary,
) -> Result<Status> {
    clear_run_dir(dir)?;
    let origin = format!("{} (run {})", plan.scene.origin, run.id);
    let (prepared, mut protocol) = plan.build(run)?;
    let rates = plan.record.resolve(prepared.setup.dt)?;
    let rates_dt = prepared.setup.dt;
    let wall_names: Vec<String> = prepared.info.walls.iter().map(|(n, _)| n.clone()).collect();
    let tray = observe::find_tray(&wall_names, &prepared.wall_shapes);
    let (layout, kind) = run_layout(plan, run, &prepared, protocol.as_ref(), wall_names, tray);
    let pinned: Vec<CoreId> = if pin { cores.to_vec() } else { vec![] };
    let loaded = prepared.start(Some(pin_workers(pinned.clone())))?;
    let info = loaded.info.clone();
    let threads = loaded.threads;
    let mut sim = loaded.sim;
    live.steps.store(PROGRESS_SCALE, Ordering::Relaxed);
    // The writer shares the run's first core: its time counts against the run's budget.
    let mut recorder = start_recorder(dir, layout, pinned.first().copied())?;
    let times_before = sim.times;
    let mut stepping = Stepping {
        plan,
        rates,
        rates_dt,
        tray,
        stop,
        live,
        origin: &origin,
    };
    let stepped = stepping.run(&mut sim, protocol.as_mut(), &mut recorder)?;
    summary.experiment = Some(protocol.summary(&sim)).filter(|v| !v.is_null());
    let wall = stepped.started.elapsed().as_secs_f64();
    let complete = !stepped.interrupted && stepped.failure.is_none();
    summary.recorder = Some(recorder.finish(complete)?);
    if let Some(t) = tray {
        let h: Heap = observe::heap(&sim, t);
        summary.heap = serde_json::to_value(h).ok();
    }
    let cost = RunCost {
        threads,
        setup_seconds: 0.0,
        wall_seconds: wall,
        times: &(sim.times - times_before),
        particle_steps: stepped.particle_steps,
    };
    summary.report = serde_json::to_value(RunReport::new(&sim, &info, cost, vec![])).ok();
    if let Some(e) = stepped.failure {
        summary.mcap = Some("run.mcap.partial".into());
        return Err(e);
    }
    if stepped.interrupted {
        summary.mcap = Some("run.mcap.partial".into());
        return Ok(Status::Interrupted);
    }
    summary.mcap = Some("run.mcap".into());
    if let Some(kind) = kind {
        summary.reduced = Some(reduce_run(&dir.join("run.mcap"), &kind));
    }
    Ok(Status::Done)
}

/// Creates the run's directory and removes what an earlier attempt left in it, so that no
/// stale summary or recording is taken for this run's.
fn clear_run_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for stale in ["summary.json", "run.mcap", "run.mcap.partial"] {
        let _ = std::fs::remove_file(dir.join(stale));
    }
    Ok(())
}

/// Pins the simulation's worker `k` to core `k` of `cores`, round robin; no pinning when
/// `cores` is empty.
fn pin_workers(cores: Vec<CoreId>) -> ThreadStart {
    Arc::new(move |k: usize| {
        if !cores.is_empty() {
            core_affinity::set_for_current(cores[k % cores.len()]);
        }
    })
}

/// Starts the MCAP writer on `DIR/run.mcap`, its thread pinned to `core` when given.
fn start_recorder(dir: &Path, layout: RunLayout, core: Option<CoreId>) -> Result<Recorder> {
    Recorder::start(&dir.join("run.mcap"), layout, move || {
        if let Some(c) = core {
            core_affinity::set_for_current(c);
        }
    })
}
