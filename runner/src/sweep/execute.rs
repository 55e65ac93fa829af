//! Running a sweep: runs as independent jobs on the cores this process may use.
//!
//! Each job gets `threads` cores of the allowed CPU set (the affinity mask, which cgroups and
//! Slurm set; never "cores 0..N"): its simulation workers, its own thread and its MCAP
//! writer are pinned there, so compression and writing count against the same budget. The
//! scheduler starts the next job in order whenever enough cores are free.

use super::job::{Live, RunSummary, Status, run_dir, run_job, write_atomic};
use super::manifest::{self, Manifest, Row};
use super::plan::{Plan, PlannedRun, num};
use anyhow::{Result, bail};
use core_affinity::CoreId;
use crossbeam::channel::{RecvTimeoutError, unbounded};
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::{BTreeMap, VecDeque};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How to run a sweep.
#[derive(Debug, Clone)]
pub struct Options {
    pub out: PathBuf,
    /// Core budget; default: every core this process may use.
    pub cores: Option<usize>,
    /// Run only runs with (id - 1) % N == I.
    pub shard: Option<(usize, usize)>,
    /// Run failed runs again instead of keeping their failure.
    pub retry_failed: bool,
    pub show_progress: bool,
    /// Pin each run to its cores (a sweep); a single `tilth run` leaves placement to the OS,
    /// so that two of them started side by side do not share one core.
    pub pin: bool,
}

/// The cores to use and whether to pin to them.
#[derive(Debug, Clone)]
pub struct Budget {
    pub cores: Vec<CoreId>,
    /// False when the allowed set is wider than the budget the batch system granted
    /// (Slurm without CPU binding): pinning would pile every task onto the same cores.
    pub pin: bool,
}

/// The CPUs in this process's affinity mask (which reflects cgroup cpusets and Slurm's
/// binding), limited by `--cores` and by Slurm's allocation.
pub fn budget(requested: Option<usize>) -> Result<Budget> {
    let allowed = core_affinity::get_core_ids().unwrap_or_default();
    let allowed = if allowed.is_empty() {
        vec![CoreId { id: 0 }]
    } else {
        allowed
    };
    let quota = std::thread::available_parallelism().map_or(1, |n| n.get());
    let slurm = ["SLURM_CPUS_PER_TASK", "SLURM_CPUS_ON_NODE"]
        .iter()
        .find_map(|k| std::env::var(k).ok()?.parse::<usize>().ok());
    let mut n = allowed.len().min(quota);
    let mut pin = true;
    if let Some(s) = slurm {
        if s < n {
            n = s;
            pin = false;
        }
    }
    let ids: Vec<String> = allowed.iter().map(|c| c.id.to_string()).collect();
    if let Some(c) = requested {
        if c == 0 || c > n {
            bail!(
                "--cores {c} is out of range: this process may use 1 to {n} (allowed CPUs {})",
                ids.join(",")
            );
        }
        // A share of the machine: pinned, every such process would take the first cores
        // (two `--cores 1` sweeps side by side ran on one core at half speed each), so the
        // operating system places the workers instead.
        if c < n {
            pin = false;
        }
        n = c;
    }
    Ok(Budget {
        cores: allowed[..n].to_vec(),
        pin,
    })
}

/// Whether run `id` belongs to `shard`.
pub fn in_shard(id: usize, shard: Option<(usize, usize)>) -> bool {
    shard.is_none_or(|(i, n)| (id - 1) % n == i)
}

/// What a sweep invocation did.
pub struct Outcome {
    /// Rows of this invocation's runs (its shard), in id order.
    pub rows: Vec<Row>,
    pub interrupted: bool,
    pub ran: usize,
}

/// A flag that SIGINT and SIGTERM raise, so that runs stop cleanly (MCAP files closed, the
/// manifest written); a second signal while stopping exits at once.
pub fn stop_on_signals() -> Result<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register_conditional_shutdown(sig, 130, stop.clone())?;
        signal_hook::flag::register(sig, stop.clone())?;
    }
    Ok(stop)
}

/// Runs every run of `plan` in this shard that is not done yet.
pub fn execute(plan: &Plan, opts: &Options, stop: Arc<AtomicBool>) -> Result<Outcome> {
    let mut budget = budget(opts.cores)?;
    budget.pin &= opts.pin;
    if plan.threads > budget.cores.len() {
        bail!(
            "{}: experiment.threads = {} but the core budget is {}; lower threads or raise --cores",
            plan.origin,
            plan.threads,
            budget.cores.len()
        );
    }
    manifest::claim(&opts.out, plan)?;
    let mine: Vec<&PlannedRun> = plan
        .runs
        .iter()
        .filter(|r| in_shard(r.id, opts.shard))
        .collect();
    let mut rows: BTreeMap<usize, Row> = mine
        .iter()
        .map(|r| (r.id, Row::observe(&opts.out, r, &plan.fingerprint)))
        .collect();
    let mut queue: VecDeque<&PlannedRun> = mine
        .iter()
        .filter(|r| match rows[&r.id].status {
            Status::Done => false,
            Status::Failed => opts.retry_failed,
            _ => true,
        })
        .copied()
        .collect();
    let write_manifest = |rows: &BTreeMap<usize, Row>| {
        Manifest {
            sweep: plan.name.clone(),
            fingerprint: plan.fingerprint.clone(),
            shard: opts.shard.map(|(i, n)| format!("{i}/{n}")),
            rows: rows.values().cloned().collect(),
        }
        .write(&opts.out, opts.shard)
    };
    write_manifest(&rows)?;
    let todo = queue.len();
    let progress = SweepProgress::new(todo, opts.show_progress);
    let mut free = budget.cores.clone();
    let (done_tx, done_rx) = unbounded::<(RunSummary, Vec<CoreId>)>();
    let mut running: BTreeMap<usize, (Arc<Live>, ProgressBar)> = BTreeMap::new();
    let mut failed = 0;
    std::thread::scope(|scope| -> Result<()> {
        loop {
            while !stop.load(Ordering::Relaxed) && !queue.is_empty() && free.len() >= plan.threads {
                let run = queue.pop_front().expect("not empty");
                let cores: Vec<CoreId> = free.drain(..plan.threads).collect();
                let live = Arc::new(Live::default());
                running.insert(run.id, (live.clone(), progress.run_bar(run)));
                rows.get_mut(&run.id).expect("row").status = Status::Running;
                let tx = done_tx.clone();
                let stop = stop.clone();
                let out = opts.out.clone();
                let pin = budget.pin;
                std::thread::Builder::new()
                    .name(format!("tilth-run-{}", run.id))
                    .spawn_scoped(scope, move || {
                        let pinned: Vec<CoreId> = if pin { cores.clone() } else { vec![] };
                        if let Some(&c) = pinned.first() {
                            core_affinity::set_for_current(c);
                        }
                        let summary = run_job(plan, run, &out, &cores, pin, &stop, &live);
                        let _ = tx.send((summary, cores));
                    })?;
                write_manifest(&rows)?;
            }
            if running.is_empty() && (queue.is_empty() || stop.load(Ordering::Relaxed)) {
                break;
            }
            match done_rx.recv_timeout(Duration::from_millis(200)) {
                Ok((summary, cores)) => {
                    free.extend(cores);
                    free.sort_by_key(|c| c.id);
                    if let Some((_, bar)) = running.remove(&summary.run.id) {
                        bar.finish_and_clear();
                    }
                    if summary.status == Status::Failed {
                        failed += 1;
                        progress.println_unless_logging(format!(
                            "run {} failed: {}",
                            summary.run.id,
                            summary.error.as_deref().unwrap_or("")
                        ));
                    }
                    if summary.status != Status::Interrupted {
                        progress.done.inc(1);
                    }
                    progress.log_finished(&summary, todo);
                    rows.insert(summary.run.id, Row::from_summary(&summary));
                    write_manifest(&rows)?;
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            progress.update(&running, failed, stop.load(Ordering::Relaxed));
        }
        Ok(())
    })?;
    progress.finish();
    write_manifest(&rows)?;
    write_results(plan, &opts.out)?;
    let interrupted = stop.load(Ordering::Relaxed);
    Ok(Outcome {
        rows: rows.into_values().collect(),
        interrupted,
        ran: todo,
    })
}

/// The sweep bar and one bar per running run, on stderr when it is a terminal; when it is not
/// (a log file, `nohup`, a batch job), one line per finished run instead, so that a log shows
/// how far a sweep got and what each run read.
struct SweepProgress {
    multi: MultiProgress,
    done: ProgressBar,
    lines: bool,
}

impl SweepProgress {
    fn new(todo: usize, show: bool) -> SweepProgress {
        let terminal = std::io::stderr().is_terminal();
        let target = if show && terminal {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let multi = MultiProgress::with_draw_target(target);
        let done = multi.add(ProgressBar::new(todo as u64));
        done.set_style(
            ProgressStyle::with_template(
                "sweep {bar:25} {pos}/{len} runs done, {msg}, {elapsed} elapsed, ETA {eta}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        SweepProgress {
            multi,
            done,
            lines: show && !terminal,
        }
    }

    /// `[3/10] run 3 (tau_c = 400000) done in 173 s: peak_shear_force_n = 311`, when stderr is
    /// not a terminal.
    fn log_finished(&self, summary: &RunSummary, todo: usize) {
        if self.lines {
            eprintln!("{}", finished_line(summary, self.done.position(), todo));
        }
    }

    fn run_bar(&self, run: &PlannedRun) -> ProgressBar {
        let bar = self.multi.add(ProgressBar::new(1));
        bar.set_style(
            ProgressStyle::with_template(
                "  run {prefix:>4} {bar:25} {percent:>3}% of simulated time {msg}",
            )
            .expect("valid template")
            .progress_chars("=> "),
        );
        bar.set_prefix(run.id.to_string());
        bar
    }

    fn update(
        &self,
        running: &BTreeMap<usize, (Arc<Live>, ProgressBar)>,
        failed: usize,
        stopping: bool,
    ) {
        for (live, bar) in running.values() {
            bar.set_length(live.steps.load(Ordering::Relaxed).max(1));
            bar.set_position(live.step.load(Ordering::Relaxed));
        }
        let stop = if stopping {
            ", stopping (finishing chunks)"
        } else {
            ""
        };
        self.done
            .set_message(format!("{} running, {failed} failed{stop}", running.len()));
    }

    /// A message above the bars (or on its own line without them), unless the finished-run
    /// line that says the same is written.
    fn println_unless_logging(&self, msg: String) {
        if self.lines {
            return;
        }
        if self.done.is_hidden() {
            eprintln!("{msg}");
        } else {
            let _ = self.multi.println(msg);
        }
    }

    fn finish(&self) {
        self.done.finish_and_clear();
    }
}

/// The observables a run's summary holds as reduced from its MCAP file (`RunSummary::reduced`),
/// in the order of results.csv's columns.
const REDUCED: [&str; 4] = [
    "repose_angle_deg",
    "peak_shear_force_n",
    "ucs_kpa",
    "slide_angle_deg",
];

/// One finished run in a log: its place in this invocation, its factor settings, status, wall
/// time and the observable reduced from its MCAP file.
fn finished_line(summary: &RunSummary, done: u64, todo: usize) -> String {
    let run = &summary.run;
    let settings: Vec<String> = run
        .values
        .iter()
        .map(|(name, value)| format!("{name} = {}", num(*value)))
        .collect();
    let mut settings = settings.join(", ");
    if !settings.is_empty() {
        settings.push_str(", ");
    }
    let mut line = format!(
        "[{done}/{todo}] run {} ({settings}seed {}) {} in {:.0} s",
        run.id,
        run.seed,
        summary.status.as_str(),
        summary.wall_seconds
    );
    if let Some(reduced) = summary.reduced.as_ref().and_then(|r| r.as_object()) {
        for key in REDUCED {
            if let Some(v) = reduced.get(key).and_then(|v| v.as_f64()) {
                line.push_str(&format!(": {key} = {v:.2}"));
            }
        }
        if let Some(e) = reduced.get("error").and_then(|e| e.as_str()) {
            line.push_str(&format!(": not reduced ({e})"));
        }
    }
    if let Some(e) = &summary.error {
        line.push_str(&format!(": {e}"));
    }
    line
}

/// Every run of the sweep (all shards) with its status and observables, from the run
/// directories: `DIR/results.csv`.
pub fn write_results(plan: &Plan, out: &Path) -> Result<Vec<Vec<String>>> {
    let mut table = vec![];
    let mut head: Vec<String> = ["run", "std", "replicate", "seed"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    head.extend(plan.factors.iter().map(|f| f.name.clone()));
    head.push("status".to_string());
    head.extend(REDUCED.iter().map(|s| s.to_string()));
    head.extend(
        [
            "heap_cone_angle_deg",
            "heap_height_m",
            "particles",
            "kinetic_energy_j",
            "wall_seconds",
            "mcap",
        ]
        .iter()
        .map(|s| s.to_string()),
    );
    table.push(head);
    for run in &plan.runs {
        let row = Row::observe(out, run, &plan.fingerprint);
        let summary = super::job::read_summary(&run_dir(out, run.id));
        let get = |f: &dyn Fn(&RunSummary) -> Option<f64>| {
            summary.as_ref().and_then(f).map(num).unwrap_or_default()
        };
        let mut line = vec![
            run.id.to_string(),
            run.std.to_string(),
            run.replicate.to_string(),
            run.seed.to_string(),
        ];
        line.extend(plan.factors.iter().map(|f| num(run.values[&f.name])));
        line.push(row.status.as_str().to_string());
        for key in REDUCED {
            line.push(get(&|s| s.reduced.as_ref()?.get(key)?.as_f64()));
        }
        line.push(get(&|s| s.heap.as_ref()?.get("cone_angle_deg")?.as_f64()));
        line.push(get(&|s| s.heap.as_ref()?.get("height_m")?.as_f64()));
        line.push(get(&|s| s.report.as_ref()?.get("particles")?.as_f64()));
        line.push(get(&|s| s.report.as_ref()?.get("kinetic_energy")?.as_f64()));
        line.push(
            row.wall_seconds
                .map(|w| format!("{w:.2}"))
                .unwrap_or_default(),
        );
        line.push(row.mcap.clone().unwrap_or_default());
        table.push(line);
    }
    let csv: String = table.iter().map(|l| l.join(",") + "\n").collect();
    write_atomic(&out.join("results.csv"), csv.as_bytes())?;
    Ok(table)
}

/// For a sweep of one setting over several seeds (no factors): each observable's mean, the
/// standard deviation between seeds and the standard error of the mean, from the results
/// table's done runs. Empty for a sweep with factors, where the runs differ in their settings.
pub fn scatter_lines(plan: &Plan, table: &[Vec<String>]) -> Vec<String> {
    let Some((head, rows)) = table.split_first() else {
        return vec![];
    };
    if !plan.factors.is_empty() {
        return vec![];
    }
    let status = head.iter().position(|h| h == "status");
    let mut out = vec![];
    for key in REDUCED.iter().chain(&["heap_cone_angle_deg"]) {
        let Some(col) = head.iter().position(|h| h == key) else {
            continue;
        };
        let values: Vec<f64> = rows
            .iter()
            .filter(|r| status.is_some_and(|s| r[s] == Status::Done.as_str()))
            .filter_map(|r| r[col].parse::<f64>().ok())
            .collect();
        let (mean, Some(sd)) = tilth_tools::compare::mean_sd(&values) else {
            continue;
        };
        let se = sd / (values.len() as f64).sqrt();
        let rel = if mean != 0.0 {
            format!(" ({:.2} % of the mean)", 100.0 * se / mean.abs())
        } else {
            String::new()
        };
        out.push(format!(
            "{key} over {} seeds: mean {}, sd {}, s.e. {}{rel}",
            values.len(),
            num(mean),
            num(sd),
            num(se)
        ));
    }
    out
}

/// The results table, aligned, for the terminal.
pub fn print_table(table: &[Vec<String>], out: &mut dyn Write) -> Result<()> {
    let cols = table.first().map_or(0, Vec::len);
    // The MCAP path is long and in results.csv; columns empty in every row say nothing.
    let shown: Vec<usize> = (0..cols.saturating_sub(1))
        .filter(|&c| table.iter().skip(1).any(|l| !l[c].is_empty()))
        .collect();
    let widths: Vec<usize> = (0..cols)
        .map(|c| table.iter().map(|l| l[c].len()).max().unwrap_or(0))
        .collect();
    for line in table {
        let cells: Vec<String> = shown
            .iter()
            .map(|&c| format!("{:>w$}", line[c], w = widths[c]))
            .collect();
        writeln!(out, "{}", cells.join("  "))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::budget;

    /// A sweep on a share of the machine is not pinned (two of them would share the first
    /// core); one on all of it is, outside Slurm.
    #[test]
    fn only_a_sweep_on_every_allowed_core_is_pinned() {
        let all = budget(None).unwrap();
        let n = all.cores.len();
        let slurm = std::env::var("SLURM_CPUS_PER_TASK").is_ok()
            || std::env::var("SLURM_CPUS_ON_NODE").is_ok();
        if !slurm {
            assert!(all.pin);
        }
        let one = budget(Some(1)).unwrap();
        assert_eq!(one.cores.len(), 1);
        assert_eq!(one.pin, n == 1 && !slurm);
        assert_eq!(budget(Some(n)).unwrap().pin, all.pin);
    }
}

/// A sweep that ended with failed or interrupted runs (exit codes 1 and 130).
#[derive(Debug)]
pub enum SweepEnd {
    Failed(usize),
    Interrupted,
}

impl std::fmt::Display for SweepEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SweepEnd::Failed(n) => write!(
                f,
                "{n} run(s) failed; their errors are in the manifest and in runs/NNN/summary.json"
            ),
            SweepEnd::Interrupted => write!(
                f,
                "interrupted: running runs stopped after closing their MCAP chunks; run the same command again to finish the sweep"
            ),
        }
    }
}

impl std::error::Error for SweepEnd {}
