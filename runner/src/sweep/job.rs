//! One run of a sweep: its scene, its pinned cores, its MCAP file and its summary.
//!
//! Files in the run's directory: `run.mcap.partial` while it runs, renamed to `run.mcap` when
//! it completes, then `summary.json` (written last, atomically: its presence with status
//! `done` is what marks the run complete for a resumed sweep).

use super::plan::{Plan, PlannedRun, innermost};
use super::report::{RunCost, RunReport};
use crate::lab::observe::{self, Heap};
use crate::lab::protocol::{Control, Protocol};
use crate::record::writer::RunLayout;
use crate::record::{Recorder, RecorderStats, snapshot};
use anyhow::{Context, Result};
use core_affinity::CoreId;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Progress is shown in thousandths.
const PROGRESS_SCALE: u64 = 1000;

/// Steps between looks at the stop flag.
const STOP_CHECK: u64 = 1000;

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
    std::fs::create_dir_all(dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    for stale in ["summary.json", "run.mcap", "run.mcap.partial"] {
        let _ = std::fs::remove_file(dir.join(stale));
    }
    let origin = format!("{} (run {})", plan.scene.origin, run.id);
    let (prepared, mut protocol) = plan.build(run)?;
    // Frame intervals are in steps: resolved again whenever the protocol changes the time
    // step (bonded specimens), so that frames keep their rates in simulated time.
    let mut rates = plan.record.resolve(prepared.setup.dt)?;
    let mut rates_dt = prepared.setup.dt;
    let wall_names: Vec<String> = prepared.info.walls.iter().map(|(n, _)| n.clone()).collect();
    let tray = observe::find_tray(&wall_names, &prepared.wall_shapes);
    let mut units = units();
    units.extend(protocol.units());
    let mut metadata = metadata(plan, run);
    let mut experiment = protocol.metadata();
    if experiment.is_empty() {
        // A plain scene with a tray: the repose reducer can measure its heap.
        if let Some(t) = tray {
            experiment = [
                ("type", "repose".to_string()),
                ("tray_radius_m", t.radius.to_string()),
                ("tray_top_z_m", t.centre[2].to_string()),
                ("tray_centre_x_m", t.centre[0].to_string()),
                ("tray_centre_y_m", t.centre[1].to_string()),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect();
        }
    }
    let kind = experiment.get("type").cloned();
    if !experiment.is_empty() {
        metadata.insert("tilth.experiment".into(), experiment);
    }
    let layout = RunLayout {
        wall_names,
        wall_shapes: prepared.wall_shapes.clone(),
        metadata,
        units,
        spheres: plan.record.spheres,
        flush_frames: plan.record.flush_frames,
    };
    let pinned: Vec<CoreId> = if pin { cores.to_vec() } else { vec![] };
    let workers = pinned.clone();
    let loaded = prepared.start(Some(Arc::new(move |k: usize| {
        if !workers.is_empty() {
            core_affinity::set_for_current(workers[k % workers.len()]);
        }
    })))?;
    let info = loaded.info.clone();
    let threads = loaded.threads;
    let mut sim = loaded.sim;
    live.steps.store(PROGRESS_SCALE, Ordering::Relaxed);
    // The writer shares the run's first core: its time counts against the run's budget.
    let writer_core = pinned.first().copied();
    let mut recorder = Recorder::start(&dir.join("run.mcap"), layout, move || {
        if let Some(c) = writer_core {
            core_affinity::set_for_current(c);
        }
    })?;
    let extra = |sim: &tilth_kernel::sim::Simulation, protocol: &dyn Protocol| {
        let own = protocol.scalars(sim);
        if !own.is_empty() {
            return own;
        }
        tray.map(|t| {
            let h = observe::heap(sim, t);
            vec![
                ("heap_cone_angle_deg".to_string(), h.cone_angle_deg),
                ("heap_height".to_string(), h.height_m),
            ]
        })
        .unwrap_or_default()
    };
    let record = |sim: &tilth_kernel::sim::Simulation,
                  protocol: &dyn Protocol,
                  rec: &mut Recorder,
                  rates: crate::record::FrameRates|
     -> Result<()> {
        let step = sim.step;
        if crate::record::FrameRates::due(rates.particles, step) {
            rec.send(snapshot::particles(sim))?;
        }
        if crate::record::FrameRates::due(rates.walls, step) {
            rec.send(snapshot::walls(sim))?;
        }
        if crate::record::FrameRates::due(rates.scalars, step) {
            rec.send(snapshot::scalars(sim, &extra(sim, protocol)))?;
        }
        if crate::record::FrameRates::due(rates.bonds, step) {
            if let Some(b) = snapshot::bonds(sim) {
                rec.send(b)?;
            }
        }
        Ok(())
    };
    let times_before = sim.times;
    let t0 = Instant::now();
    let mut particle_steps: u64 = 0;
    let mut interrupted = false;
    let mut failure = None;
    record(&sim, protocol.as_ref(), &mut recorder, rates)?;
    loop {
        if stop.load(Ordering::Relaxed) {
            interrupted = true;
            break;
        }
        let k = match protocol.control(&mut sim) {
            Ok(Control::Done) => break,
            Ok(Control::Step(k)) => k.max(1),
            Err(e) => {
                failure = Some(e.context(origin.clone()));
                break;
            }
        };
        if sim.dt != rates_dt {
            rates = plan.record.resolve(sim.dt)?;
            rates_dt = sim.dt;
        }
        let n = rates
            .steps_to_next(sim.step, k)
            .min(STOP_CHECK - sim.step % STOP_CHECK);
        let before = sim.particles.len() as u64;
        if let Err(e) = sim.run(n) {
            failure = Some(anyhow::Error::from(e).context(origin.clone()));
            break;
        }
        particle_steps += n * before.max(sim.particles.len() as u64);
        let done = (protocol.progress(&sim).clamp(0.0, 1.0) * PROGRESS_SCALE as f64) as u64;
        live.step.store(done, Ordering::Relaxed);
        record(&sim, protocol.as_ref(), &mut recorder, rates)?;
    }
    summary.experiment = Some(protocol.summary(&sim)).filter(|v| !v.is_null());
    let wall = t0.elapsed().as_secs_f64();
    let complete = !interrupted && failure.is_none();
    summary.recorder = Some(recorder.finish(complete)?);
    if let Some(t) = tray {
        let h: Heap = observe::heap(&sim, t);
        summary.heap = serde_json::to_value(h).ok();
    }
    let times = sim.times - times_before;
    let cost = RunCost {
        threads,
        setup_seconds: 0.0,
        wall_seconds: wall,
        times: &times,
        particle_steps,
    };
    let report = RunReport::new(&sim, &info, cost, vec![]);
    summary.report = serde_json::to_value(&report).ok();
    if let Some(e) = failure {
        summary.mcap = Some("run.mcap.partial".into());
        return Err(e);
    }
    if interrupted {
        summary.mcap = Some("run.mcap.partial".into());
        return Ok(Status::Interrupted);
    }
    summary.mcap = Some("run.mcap".into());
    if let Some(kind) = kind {
        summary.reduced = Some(reduce_run(&dir.join("run.mcap"), &kind));
    }
    Ok(Status::Done)
}

/// MCAP metadata records: what the run is and what made it.
fn metadata(plan: &Plan, run: &PlannedRun) -> BTreeMap<String, BTreeMap<String, String>> {
    let mut r = BTreeMap::new();
    r.insert("sweep".into(), plan.origin.clone());
    r.insert("sweep_name".into(), plan.name.clone());
    r.insert("design".into(), plan.title.clone());
    r.insert("scene".into(), plan.scene.origin.clone());
    r.insert("run_id".into(), run.id.to_string());
    r.insert("std_order".into(), run.std.to_string());
    r.insert("replicate".into(), run.replicate.to_string());
    r.insert("seed".into(), run.seed.to_string());
    r.insert("fingerprint".into(), plan.fingerprint.clone());
    r.insert("tilth_version".into(), env!("CARGO_PKG_VERSION").into());
    r.insert("git_commit".into(), crate::provenance::GIT_COMMIT.into());
    for (k, v) in &run.values {
        r.insert(format!("factor.{k}"), v.to_string());
    }
    for (k, v) in &run.coded {
        r.insert(format!("coded.{k}"), v.to_string());
    }
    let mut channels = BTreeMap::new();
    channels.insert(
        "/particles".into(),
        "foxglove.PointCloud in frame world: x, y, z, radius (m), speed (m/s), id, material".into(),
    );
    channels.insert(
        "/walls".into(),
        "foxglove.SceneUpdate: one entity per wall, moved by its motion".into(),
    );
    channels.insert(
        "/walls/<name>/force".into(),
        "foxglove.Vector3: force of the particles on the wall, N".into(),
    );
    channels.insert(
        "/walls/<name>/torque".into(),
        "foxglove.Vector3: torque about the wall's reference point, N m".into(),
    );
    channels.insert(
        "/scalars/<name>".into(),
        "foxglove.Vector3 with the value in x (Foxglove's schemas have no scalar type)".into(),
    );
    for (k, u) in units() {
        channels.insert(format!("/scalars/{k}"), u);
    }
    let mut m = BTreeMap::new();
    m.insert("tilth.run".to_string(), r);
    m.insert("tilth.channels".to_string(), channels);
    m
}

/// Units of the scalar channels.
fn units() -> BTreeMap<String, String> {
    [
        ("kinetic_energy", "J"),
        ("particles", "count"),
        ("contacts", "count"),
        ("heap_cone_angle_deg", "degree"),
        ("heap_height", "m"),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect()
}

/// Reduces a finished run's MCAP file with the reducer of its experiment `kind`.
pub fn reduce_run(path: &Path, kind: &str) -> serde_json::Value {
    use tilth_tools::reduce;
    let result = (|| -> Result<serde_json::Value> {
        let run = reduce::read_run(path, &reduce::ReadOptions::default())?;
        Ok(match kind {
            "repose" => {
                let r = reduce::repose(&run, &reduce::ReposeOptions::of_run(&run))?;
                std::fs::write(
                    path.with_file_name("repose.svg"),
                    reduce::plot::repose_svg(&r)?,
                )?;
                serde_json::json!({
                    "repose_angle_deg": r.analysis.repose_angle_deg,
                    "cone_fit_deg": r.analysis.cone.angle_deg,
                })
            }
            "direct_shear" => {
                let r = reduce::shear(&run, &Default::default())?;
                std::fs::write(
                    path.with_file_name("shear.svg"),
                    reduce::plot::shear_svg(&r)?,
                )?;
                serde_json::json!({
                    "peak_shear_force_n": r.analysis.peak_shear_force_n,
                    "max_inertial_number": r.analysis.max_inertial_number,
                })
            }
            "ucs" => {
                let r = reduce::ucs(&run, &Default::default())?;
                std::fs::write(path.with_file_name("ucs.svg"), reduce::plot::ucs_svg(&r)?)?;
                serde_json::json!({
                    "ucs_kpa": r.analysis.ucs_kpa,
                    "failure": format!("{:?}", r.analysis.failure),
                    "max_inertial_number": r.analysis.max_inertial_number,
                })
            }
            other => serde_json::json!({ "error": format!("no reducer for `{other}`") }),
        })
    })();
    result.unwrap_or_else(|e| serde_json::json!({ "error": format!("{e:#}") }))
}
