//! Measurement rows into lab runs: the bridge from the study to the sweep engine that
//! `compare`, `diagnose`, `fit`, `synth` and `next` share.
//!
//! Each row of a test becomes a run of its experiment file (the test's preset, the model,
//! `--set` overrides) at the row's conditions, with replicate seeds derived from the
//! conditions ([`condition_seed`]), so that the same row always gets the same runs. The runs
//! go through the sweep runner (pinned cores, resumable) locally or as a Slurm job array, and
//! are reused from a cache keyed by the build and the model's text.

use super::measurements::{Measurement, TESTS, setting_columns};
use crate::sweep::execute::{self, Options};
use crate::sweep::job::{RunSummary, Status, read_summary, run_dir, write_atomic};
use crate::sweep::plan::{Factor, Plan, PlannedRun, fnv1a};
use crate::sweep::slurm_wait::{self, SlurmJob};
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

/// How the lab tests' runs are made: the options `compare`, `diagnose`, `fit` and `synth`
/// share, with one meaning and one help text.
#[derive(Debug, Clone, Args)]
pub struct LabRunArgs {
    /// Each test's coarse preset (bigger particles, less material): quick, not for numbers.
    #[arg(long)]
    pub coarse: bool,
    #[command(flatten)]
    pub set: SetArgs,
    /// Cores to use (default: all this process may use).
    #[arg(long)]
    pub cores: Option<usize>,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
    /// Keep the runs in this directory, keyed by the model's values (not its comments), the
    /// test, the conditions, the seeds and this build of tilth, and reuse any run already
    /// there, whichever command made it (one command at a time per cache). More replicates
    /// later run only the new seeds.
    #[arg(long)]
    pub cache: Option<PathBuf>,
    /// Run the runs as Slurm job arrays (`sbatch --wait`; one per setting of the model, or
    /// one for all of diagnose's variants and of each fit Jacobian) instead of on this
    /// machine: the same numbers, bit for bit. The output directory, the cache and the model
    /// must be on storage the nodes share.
    #[arg(long, conflicts_with = "cores")]
    pub slurm: bool,
    /// With --slurm: array tasks per job (default: one per run left, at most 100).
    #[arg(long, requires = "slurm", value_parser = clap::value_parser!(u64).range(1..))]
    pub slurm_tasks: Option<u64>,
    /// With --slurm: time limit per task, Slurm syntax (default 12:00:00).
    #[arg(long, requires = "slurm")]
    pub slurm_time: Option<String>,
    /// With --slurm: the partition (default: the cluster's default).
    #[arg(long, requires = "slurm")]
    pub slurm_partition: Option<String>,
}

impl LabRunArgs {
    /// How the runs are made: on this machine's cores, or as Slurm arrays.
    pub fn dispatch(&self) -> Dispatch {
        if !self.slurm {
            return Dispatch::Local(self.cores);
        }
        Dispatch::Slurm(SlurmJob {
            tasks: self.slurm_tasks.map(|t| t as usize),
            time: self.slurm_time.clone().unwrap_or_else(|| "12:00:00".into()),
            partition: self.slurm_partition.clone(),
        })
    }
}

/// Where a lab command's runs are made.
pub enum Dispatch {
    /// On this machine, with at most this many cores (default: all it may use).
    Local(Option<usize>),
    Slurm(SlurmJob),
}

pub fn experiment_text(test: &str, model: &Path, coarse: bool, set: &[TestSetting]) -> String {
    // The test's own table is written (empty: defaults) so that factors can set its keys.
    let mut text = format!(
        "format_version = 1\nexperiment = \"{test}\"\nmodel = {:?}\ncoarse = {coarse}\n[conditions]\n[{test}]\n",
        model.display().to_string()
    );
    for s in set.iter().filter(|s| s.test == test) {
        text.push_str(&format!("{} = {}\n", s.key, s.value));
    }
    text
}

/// `--set TEST.KEY=VALUE`, for the commands that run the lab tests: one key of a test's own
/// table (`[repose]`, `[direct_shear]` or `[ucs]` of an experiment file) in every run of
/// that test, over the preset: another instrument (`repose.tray_diameter=0.1236`), another
/// amount of soil (`repose.mass_g=300`).
#[derive(Debug, Clone, Default, Args)]
pub struct SetArgs {
    /// A key of a test's table in every run of that test, e.g. repose.mass_g=300 (the keys
    /// of sweeps/experiments/*.toml, with their ranges); repeatable.
    #[arg(long = "set", value_name = "TEST.KEY=VALUE")]
    pub set: Vec<String>,
}

/// One `--set`, checked: a known test, a bare key, a TOML value. Whether the test has the key
/// and the value is in its range is checked when the runs are planned, before any runs.
#[derive(Debug, Clone, PartialEq)]
pub struct TestSetting {
    pub test: String,
    pub key: String,
    pub value: toml::Value,
}

impl SetArgs {
    pub fn parse(&self) -> Result<Vec<TestSetting>> {
        let mut out: Vec<TestSetting> = vec![];
        for raw in &self.set {
            let example = "expected TEST.KEY=VALUE, e.g. repose.mass_g=300";
            let (path, value) = raw
                .split_once('=')
                .ok_or_else(|| anyhow!("--set {raw}: {example}"))?;
            let (test, key) = path
                .trim()
                .split_once('.')
                .ok_or_else(|| anyhow!("--set {raw}: {example}"))?;
            if !TESTS.contains(&test) {
                bail!(
                    "--set {raw}: `{test}` is not a test: allowed {}",
                    TESTS.join(", ")
                );
            }
            let bare = |k: &str| {
                !k.is_empty()
                    && k.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            };
            if !bare(key) {
                bail!("--set {raw}: `{key}` is not a key of [{test}] (letters, digits, _ and -)");
            }
            let value = toml::from_str::<toml::Table>(&format!("v = {}", value.trim()))
                .ok()
                .and_then(|mut t| t.remove("v"))
                .ok_or_else(|| {
                    anyhow!(
                        "--set {raw}: `{}` is not a value (a number, true or false, or a quoted string)",
                        value.trim()
                    )
                })?;
            if out.iter().any(|s| s.test == test && s.key == key) {
                bail!("--set {raw}: {test}.{key} is set twice");
            }
            // Checked here, not when the test's runs are planned: a test without measured rows
            // never plans any, and a mistyped key would pass unseen.
            crate::lab::experiment::check_test_key(test, key, &value)
                .map_err(|e| anyhow!("--set {raw}: {e}"))?;
            out.push(TestSetting {
                test: test.to_string(),
                key: key.to_string(),
                value,
            });
        }
        Ok(out)
    }
}

/// How to simulate measurement rows.
pub struct Simulate<'a> {
    /// Absolute path of the model file.
    pub model: &'a Path,
    /// The rows' file, for errors.
    pub data: &'a Path,
    /// One sweep per test goes to `out/<test>/`.
    pub out: &'a Path,
    pub replicates: usize,
    /// Replicate r of a row runs with the seed [`condition_seed`] derives from
    /// `first_seed + r` and the row's conditions.
    pub first_seed: u64,
    /// The preset, cores, progress and run cache. The cache is shared between commands:
    /// runs go to `cache/<test>-<key>/`, the key made of the model file's content, the test,
    /// the conditions, the first seed and the build of tilth (a hash of its executable), so
    /// that any command that needs the same runs, or more replicates of them, finds them done.
    pub lab: &'a LabRunArgs,
    /// `--set` of `lab`, parsed: keys of the tests' own tables in every run.
    pub set: &'a [TestSetting],
}

/// The seed of replicate `base` (`first_seed + r`) at one condition, in [1, 2^31).
///
/// Derived from both, so that runs at different conditions are independent draws, as
/// specimens in a laboratory are. With one seed for every condition,
/// a draw that shapes the outcome at every condition alike (a fine fraction's realised
/// share of fines, which sets the funnel's flow rate at every moisture) moved the means of
/// all conditions together: with R runs per condition the rows' simulation errors were
/// correlated (0.8 across moisture levels for the flow rate with fines on), which rows
/// treated as independent cannot average out (the seven-level fine-fraction fit ended 3.3
/// of its standard errors short; docs/discovery-proof.md, "The stop rule and the seeds").
/// Changing models or parameters keeps the seeds (common random numbers between variants).
pub fn condition_seed(base: u64, conditions: &BTreeMap<String, f64>) -> u64 {
    let key = conditions
        .iter()
        .map(|(k, v)| format!("{k}={:016x}", v.to_bits()))
        .collect::<Vec<_>>()
        .join(",");
    let h = u64::from_str_radix(&fnv1a(&[&base.to_string(), &key]), 16).expect("hex");
    // splitmix64's finaliser, so that neighbouring bases land far apart.
    let mut z = h.wrapping_add(0x9e3779b97f4a7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
    z ^= z >> 31;
    1 + z % ((1 << 31) - 1)
}

/// Simulates every row (its test at its conditions, `replicates` seeds), reusing finished
/// runs; returns per row the simulated values of the replicates that finished and why the
/// others have none. Every test is planned before any run starts, so a bad row stops
/// everything first.
pub fn simulate(
    rows: &[Measurement],
    how: &Simulate,
    stop: &Arc<AtomicBool>,
) -> Result<Vec<(Vec<f64>, Vec<String>)>> {
    let tests = tests_of(rows);
    for unused in how.set.iter().filter(|s| !tests.contains(&s.test.as_str())) {
        eprintln!(
            "warning: --set {}.{}: no {} rows here, so it is not used (nor checked)",
            unused.test, unused.key, unused.test
        );
    }
    let (plans, group) = plan_tests(rows, how)?;
    // By position in `rows`: two rows may share a file row (every reading of a conditions row).
    let mut by_row: BTreeMap<usize, (Vec<f64>, Vec<String>)> = BTreeMap::new();
    for (k, (_, plan, dir)) in plans.iter().enumerate() {
        run_generated(plan, dir, &how.lab.dispatch(), how.lab.quiet, stop)?;
        for (i, m) in rows.iter().enumerate().filter(|(i, _)| group[*i].0 == k) {
            let (sims, problems) = by_row.entry(i).or_default();
            for run in plan.runs.iter().filter(|r| r.std == group[i].1) {
                let s = read_summary(&run_dir(dir, run.id));
                let v = s.as_ref().and_then(|s| observed(s, &m.observable));
                match (v, s) {
                    (Some(v), Some(s)) if s.status == Status::Done => sims.push(v),
                    (_, Some(s)) => problems.push(format!(
                        "run {}: {}",
                        run.id,
                        s.error
                            .or_else(|| s
                                .reduced
                                .and_then(|r| r.get("error").map(|e| e.to_string())))
                            .unwrap_or_else(|| s.status.as_str().to_string())
                    )),
                    (_, None) => problems.push(format!("run {}: no summary", run.id)),
                }
            }
        }
    }
    Ok((0..rows.len())
        .map(|i| by_row.remove(&i).unwrap_or_default())
        .collect())
}

/// A run's value of `observable`: reduced from its MCAP file by the study's method
/// (`repose_angle_deg`, `peak_shear_force_n`, `ucs_kpa`), else measured by the experiment as
/// it ran (the fixed-base heap angle, the tray's mass, the funnel's flow rate).
pub fn observed(s: &RunSummary, observable: &str) -> Option<f64> {
    let reduced = s.reduced.as_ref().and_then(|r| r.get(observable));
    reduced
        .or_else(|| s.experiment.as_ref()?.get(observable))?
        .as_f64()
}

/// Runs (or resumes) a generated plan into `dir`, pinned, with a progress bar unless `quiet`.
/// This build of tilth, as a hash of the running executable: a run cache must not hand the
/// runs of one build's physics to another (a rebuilt tilth starts afresh).
fn build_id() -> Result<&'static str> {
    static ID: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    if let Some(id) = ID.get() {
        return Ok(id);
    }
    let exe = std::env::current_exe().context("cannot locate the tilth executable")?;
    let bytes = std::fs::read(&exe).with_context(|| format!("{}: cannot read", exe.display()))?;
    let mut h = std::hash::DefaultHasher::new();
    std::hash::Hasher::write(&mut h, &bytes);
    let id = format!("{:016x}", std::hash::Hasher::finish(&h));
    Ok(ID.get_or_init(|| id))
}

/// The model file's copy in the cache, named by its content, so that the runs' fingerprint
/// (which holds the model's path) is the same for every copy of the same model.
///
/// The copy is the model's TOML written out again without its comments and layout: a model
/// that differs only in those (the one `tilth fit` writes, with its header, against the
/// setting it ran last) is the same model and reuses the same runs.
fn cached_model(model: &Path, cache: &Path) -> Result<PathBuf> {
    let source = std::fs::read_to_string(model)
        .with_context(|| format!("{}: cannot read", model.display()))?;
    let table: toml::Table =
        toml::from_str(&source).with_context(|| format!("{}: not TOML", model.display()))?;
    let text = toml::to_string(&table)
        .with_context(|| format!("{}: cannot write out again", model.display()))?;
    let dir = std::path::absolute(cache.join("models"))?;
    std::fs::create_dir_all(&dir).with_context(|| format!("{}: cannot create", dir.display()))?;
    let path = dir.join(format!("{}.toml", fnv1a(&[&text])));
    if std::fs::read_to_string(&path).ok().as_deref() != Some(text.as_str()) {
        write_atomic(&path, text.as_bytes())?;
    }
    Ok(path)
}

/// The tests of `rows`, in their first row's order.
fn tests_of(rows: &[Measurement]) -> Vec<&str> {
    let mut tests: Vec<&str> = vec![];
    for m in rows {
        if !tests.contains(&m.test.as_str()) {
            tests.push(&m.test);
        }
    }
    tests
}

/// A test's runs for `rows`: the test, its generated plan and the directory it runs in.
type TestPlan = (String, Plan, PathBuf);

/// Row i's plan (its index) and its set of runs in that plan (its conditions' number).
type RowRuns = (usize, usize);

/// The runs `simulate` needs and `group[i]`: row i's plan and its set of runs in that plan
/// (its conditions' number). One plan per test and set of setting columns the rows fill
/// (`repose.drop_height`, ...): each setting is a factor of its plan.
fn plan_tests(rows: &[Measurement], how: &Simulate) -> Result<(Vec<TestPlan>, Vec<RowRuns>)> {
    let model = match how.lab.cache.as_deref() {
        Some(cache) => cached_model(how.model, cache)?,
        None => how.model.to_path_buf(),
    };
    let mut group: Vec<RowRuns> = vec![(0, 0); rows.len()];
    let mut plans = vec![];
    let settings_of: Vec<Vec<String>> = rows
        .iter()
        .map(|m| setting_columns(std::slice::from_ref(m)))
        .collect();
    for (test, settings) in tests_and_settings(rows, &settings_of) {
        let mut factors = condition_factors(&test);
        factors.extend(settings.iter().map(|k| factor(k, k)));
        // Rows of one test at the same conditions (a repose run's angle, tray mass and flow
        // rate) share their runs: numbered per plan.
        let mut conditions: Vec<BTreeMap<String, f64>> = vec![];
        let mut seen: Vec<&BTreeMap<String, f64>> = vec![];
        let mine = rows
            .iter()
            .enumerate()
            .filter(|(i, m)| m.test == test && settings_of[*i] == settings);
        for (i, m) in mine {
            if let Some(g) = seen.iter().position(|c| **c == m.conditions) {
                group[i] = (plans.len(), g + 1);
                continue;
            }
            seen.push(&m.conditions);
            group[i] = (plans.len(), seen.len());
            let mut values = BTreeMap::new();
            for f in &factors {
                let v = m.conditions.get(&f.name).ok_or_else(|| {
                    anyhow!(
                        "{}: row {}: a {test} row needs `{}`",
                        how.data.display(),
                        m.row,
                        f.name
                    )
                })?;
                values.insert(f.name.clone(), *v);
            }
            conditions.push(values);
        }
        let name = std::iter::once(test.clone())
            .chain(settings.iter().map(|k| k.replace('.', "_")))
            .collect::<Vec<_>>()
            .join("+");
        plans.push(plan_one(&test, &name, factors, &conditions, &model, how)?);
    }
    Ok((plans, group))
}

/// The tests of `rows` with the setting columns each row fills (`settings_of`), in
/// first-row order.
fn tests_and_settings(
    rows: &[Measurement],
    settings_of: &[Vec<String>],
) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = vec![];
    for (m, settings) in rows.iter().zip(settings_of) {
        let key = (m.test.clone(), settings.clone());
        if !out.contains(&key) {
            out.push(key);
        }
    }
    out
}

/// The plan of one test's `conditions` (each a factor setting), with `how.replicates` seeds
/// each, and its directory: `out/NAME/`, or in the cache by its fingerprint.
fn plan_one(
    test: &str,
    name: &str,
    factors: Vec<Factor>,
    conditions: &[BTreeMap<String, f64>],
    model: &Path,
    how: &Simulate,
) -> Result<TestPlan> {
    // Replicate-major: every condition's first seed, then every condition's second, ...
    // so that asking for more replicates later appends runs and keeps the numbers (and
    // the finished runs) of those already done.
    let mut runs = vec![];
    for r in 0..how.replicates {
        for (k, values) in conditions.iter().enumerate() {
            runs.push(PlannedRun {
                id: runs.len() + 1,
                std: k + 1,
                replicate: r + 1,
                coded: BTreeMap::new(),
                values: values.clone(),
                seed: condition_seed(how.first_seed + r as u64, values),
            });
        }
    }
    let text = experiment_text(test, model, how.lab.coarse, how.set);
    let mut plan = Plan::generated(test, text, Path::new("."), factors, runs)
        .with_context(|| format!("{}: rows of test {test}", how.data.display()))?;
    // The sweep's identity leaves out how many replicates it has (each run is still
    // checked against its own seed and conditions when it is reused).
    plan.fingerprint = fnv1a(&[
        &plan.sweep_text,
        &serde_json::to_string(&conditions)?,
        &how.first_seed.to_string(),
    ]);
    let dir = match how.lab.cache.as_deref() {
        Some(cache) => cache.join(format!(
            "{test}-{}",
            fnv1a(&[&plan.fingerprint, build_id()?])
        )),
        None => how.out.join(name),
    };
    Ok((test.to_string(), plan, dir))
}

/// Makes the runs of several settings of the model (`hows`) at once where that saves time:
/// with `--slurm`, as one job array, where one array per setting would wait for each
/// setting's slowest run in turn (`diagnose`'s variants, `fit`'s Jacobian). Without it,
/// nothing: `simulate` runs each setting when it is asked for, on this machine's cores.
pub fn prefetch(rows: &[Measurement], hows: &[Simulate]) -> Result<()> {
    let Some(first) = hows.first() else {
        return Ok(());
    };
    let Dispatch::Slurm(job) = first.lab.dispatch() else {
        return Ok(());
    };
    let mut batch = vec![];
    for how in hows {
        batch.extend(plan_tests(rows, how)?.0.into_iter().map(|(_, p, d)| (p, d)));
    }
    slurm_wait::run(&batch, &job, first.lab.quiet)
}

pub fn run_generated(
    plan: &Plan,
    dir: &Path,
    dispatch: &Dispatch,
    quiet: bool,
    stop: &Arc<AtomicBool>,
) -> Result<()> {
    let cores = match dispatch {
        Dispatch::Local(cores) => *cores,
        Dispatch::Slurm(job) => {
            return slurm_wait::run(&[(plan.clone(), dir.to_path_buf())], job, quiet);
        }
    };
    if !quiet {
        eprintln!(
            "{}: {} runs into {}",
            plan.name,
            plan.runs.len(),
            dir.display()
        );
    }
    let opts = Options {
        out: dir.to_path_buf(),
        cores,
        shard: None,
        retry_failed: false,
        show_progress: !quiet,
        pin: true,
    };
    let outcome = execute::execute(plan, &opts, stop.clone())?;
    if outcome.interrupted {
        return Err(crate::sweep::execute::SweepEnd::Interrupted.into());
    }
    Ok(())
}

/// The measured conditions of a test, as factors of its experiment file.
pub fn condition_factors(test: &str) -> Vec<Factor> {
    let mut factors = vec![factor("moisture_pct", "conditions.moisture_pct")];
    if test != "repose" {
        factors.push(factor("firmness_mpa", "conditions.firmness_mpa"));
    }
    if test == "direct_shear" {
        factors.push(factor("normal_pressure_pa", "direct_shear.normal_pressure"));
    }
    factors
}

pub fn factor(name: &str, target: &str) -> Factor {
    Factor {
        name: name.into(),
        target: target.into(),
        label: None,
        unit: None,
        low: f64::NAN,
        high: f64::NAN,
    }
}
