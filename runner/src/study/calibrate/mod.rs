//! `tilth calibrate`: choose free parameters of a model file so that simulations of one test
//! hit its measurements at every measured condition, with the scatter of the simulations
//! measured and the parameters' uncertainty reported.
//!
//! 1. **Surface.** At each measured condition, a 3^k factorial over the free parameters' ranges
//!    plus two more centre points, each run with `--seeds` seeds (so the scatter between
//!    seeds is pure error in the fit), through the sweep runner (resumable).
//! 2. **Solve.** A quadratic response surface per condition (`tilth rsm`), solved for the
//!    measured value: every setting that hits it. When that is a ridge, one measurement
//!    cannot separate the parameters; the setting chosen is the one on the ridge closest (in
//!    coded units) to the starting model: the least change that fits, stated as such.
//! 3. **Refine.** Direct runs at the chosen setting with `--seeds` fresh seeds (the same seeds
//!    at every iteration: common random numbers); while the mean misses the measurement by
//!    more than `--tolerance` %, a Newton step along the surface's gradient (at most a quarter
//!    of each range), up to `--refine` times. With one free parameter, once the checks stand
//!    at two settings or more, the step goes instead to where the line through every check
//!    (weighted by runs) meets the measurement, when that line's slope has the surface's sign:
//!    the checks measure the slope where the calibration is, the surface only guesses it.
//! 4. **Uncertainty.** Linearised intervals (and the ridge direction when the data cannot
//!    fix every parameter) and a posterior sample by sequential Monte Carlo on the surface,
//!    the likelihood's spread being the fit's residual standard deviation.
//! 5. **Output.** `DIR/calibration.json`, `calibration.md`, a contour plot per condition, the
//!    posterior samples, and `DIR/model.toml`: the starting model with the calibrated
//!    parameters as tables over the condition (comments kept). Calibrated where a condition
//!    is fixed (`--where moisture_pct=6`, or one condition only), a value applies there only:
//!    it is written as the first case of a `cases` table that keeps the model's previous
//!    value for every other condition.

mod inputs;
pub mod joint;
mod outputs;
mod refine;
pub mod report;
mod surface;

pub(crate) use inputs::push_surface_runs;
pub use inputs::{cond_values, describe, load_params, run_factors, select_rows, surface_grid};
pub use refine::{run_and_read, wants_more_seeds};
pub use surface::surface;

use crate::lab::model::Model;
use crate::study::lab_runs::{SetArgs, experiment_text};
use crate::study::measurements::Measurement;
use crate::sweep::execute;
use crate::sweep::plan::Factor;
use anyhow::{Result, anyhow, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tilth_tools::calibrate::{Linearised, Posterior};

#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Starting model file, e.g. models/li2022.toml.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV), e.g. data/li2022/measurements.csv.
    #[arg(long)]
    pub data: PathBuf,
    /// The test whose measurements to fit: repose, direct_shear, ucs or tilt (with `--joint`,
    /// several, comma-separated: `repose,ucs`).
    #[arg(long)]
    pub test: String,
    /// One value per parameter shared by every selected measurement (all conditions, all
    /// tests), fitted to all of them at once by weighted least squares, instead of one value
    /// per condition.
    #[arg(long)]
    pub joint: bool,
    /// The calibrated values hold for this test's specimens only: written as a case that
    /// names the test (`when = { test = "ucs", ... }`), the other tests keeping the model's
    /// values. For specimens prepared differently per test, as the study's bond tables
    /// (2 from the shear box, 3 from compression).
    #[arg(long)]
    pub per_test: bool,
    /// A free parameter and its range: `PAIR.KEY=LOW:HIGH`, e.g.
    /// `soil-soil.rolling_friction=0.05:0.45` (repeatable).
    #[arg(long = "param", required = true)]
    pub params: Vec<String>,
    /// Runs per setting, with different seeds.
    #[arg(long, default_value_t = 3)]
    pub seeds: usize,
    /// Runs per direct check at the chosen setting (default: `--seeds`): the mean's standard
    /// error falls as 1/sqrt(n), and a tolerance of 2 % needs it well below 2 %.
    #[arg(long)]
    pub check_seeds: Option<usize>,
    /// Precision of a check: while the standard error of its mean is above this many percent
    /// of the measurement, the check takes `--check-seeds` more seeds (up to
    /// `--max-check-seeds`), unless it already misses by more than the tolerance plus two
    /// standard errors (the Newton step needs no more to know its direction). Without it,
    /// every check has `--check-seeds` seeds.
    #[arg(long, value_name = "PCT")]
    pub check_se: Option<f64>,
    /// The most seeds a check takes with `--check-se` (default: four times `--check-seeds`).
    #[arg(long)]
    pub max_check_seeds: Option<usize>,
    /// Done when the mean of the runs is within this many percent of the measurement.
    #[arg(long, default_value_t = 2.0)]
    pub tolerance: f64,
    /// Newton refinements with direct runs, at most.
    #[arg(long, default_value_t = 3)]
    pub refine: usize,
    /// The test's coarse preset (bigger particles, less material).
    #[arg(long)]
    pub coarse: bool,
    #[command(flatten)]
    pub set: SetArgs,
    /// Only measurements whose condition is one of these, e.g. `moisture_pct=6`.
    #[arg(long = "where")]
    pub filters: Vec<String>,
    #[arg(long)]
    pub out: PathBuf,
    #[arg(long)]
    pub cores: Option<usize>,
    #[arg(long)]
    pub quiet: bool,
}

/// A free parameter.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct Param {
    /// `rolling_friction`
    pub name: String,
    /// `soil-soil`
    pub pair: String,
    pub key: String,
    pub low: f64,
    pub high: f64,
}

/// The free parameters with their ranges, as the reports list them:
/// `soil-soil.rolling_friction in [0.05, 0.45], ...`.
pub fn params_text(params: &[Param]) -> String {
    params
        .iter()
        .map(|p| format!("{}.{} in [{}, {}]", p.pair, p.key, p.low, p.high))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A free parameter's value form in the model: `[pairs.PAIR]` first, then
/// `[bond.pairs.PAIR]` (bond stiffness and strength, for the direct shear and UCS tests). The
/// lab puts both into the scene's pair table, which is where the runs set it.
pub fn param_form<'m>(model: &'m Model, p: &Param) -> Option<&'m toml::Value> {
    model
        .file
        .pairs
        .get(&p.pair)
        .and_then(|t| t.get(&p.key))
        .or_else(|| {
            model
                .file
                .bond
                .as_ref()
                .and_then(|b| b.pairs.get(&p.pair))
                .and_then(|t| t.get(&p.key))
        })
}

pub fn parse_param(s: &str) -> Result<Param> {
    let bad = || {
        anyhow!(
            "--param {s:?}: expected PAIR.KEY=LOW:HIGH, e.g. soil-soil.rolling_friction=0.05:0.45"
        )
    };
    let (path, range) = s.split_once('=').ok_or_else(bad)?;
    let (pair, key) = path.trim().split_once('.').ok_or_else(bad)?;
    let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
    let num = |t: &str| {
        t.trim()
            .parse::<f64>()
            .map_err(|_| anyhow!("--param {s:?}: {t:?} is not a number"))
    };
    let (low, high) = (num(lo)?, num(hi)?);
    if !(low.is_finite() && high.is_finite() && high > low) {
        bail!("--param {s:?}: the range must be LOW:HIGH with LOW < HIGH");
    }
    Ok(Param {
        name: key.to_string(),
        pair: pair.to_string(),
        key: key.to_string(),
        low,
        high,
    })
}

/// Per condition: the surface, the solution and the runs at the chosen setting.
#[derive(Debug, Clone, Serialize)]
pub struct ConditionResult {
    pub conditions: BTreeMap<String, f64>,
    pub measured: f64,
    pub start: Vec<f64>,
    pub surface_runs: usize,
    pub surface_failed: usize,
    pub r2: f64,
    pub residual_sd: Option<f64>,
    pub equation: String,
    pub ridge_statement: String,
    pub ridge_points: usize,
    /// Iterations: setting, runs' values, mean, sd, relative error %.
    pub iterations: Vec<Iteration>,
    pub calibrated: Vec<f64>,
    pub simulated_mean: f64,
    pub simulated_sd: Option<f64>,
    pub error_pct: f64,
    /// Standard error of `error_pct` from the scatter between seeds: sd / sqrt(n) / measured.
    pub error_se_pct: Option<f64>,
    /// The mean is within the tolerance.
    pub within_tolerance: bool,
    /// ... and stays within it two standard errors either side: the scatter between seeds
    /// cannot have put it there by chance.
    pub within_beyond_scatter: bool,
    pub linearised: Linearised,
    pub posterior: Posterior,
}

#[derive(Debug, Clone, Serialize)]
pub struct Iteration {
    pub setting: Vec<f64>,
    pub predicted: f64,
    pub values: Vec<f64>,
    pub mean: f64,
    pub sd: Option<f64>,
    pub error_pct: f64,
}

/// What every step of a one-test calibration reads: the options, the free parameters, the
/// model, the measurements kept, and the experiment and factors of the test's runs.
struct Setup<'a> {
    args: &'a CalibrateArgs,
    params: Vec<Param>,
    /// The model file, absolute.
    model_path: PathBuf,
    model: Model,
    rows: Vec<Measurement>,
    stop: Arc<AtomicBool>,
    factors: Vec<Factor>,
    /// The experiment file's text that every run of the test shares.
    text: String,
}

impl<'a> Setup<'a> {
    /// Reads the `--set` options, the parameters, the model and the measurements, and
    /// installs the signal handler that stops the runs.
    fn new(args: &'a CalibrateArgs) -> Result<Self> {
        let set = args.set.parse()?;
        let (params, model_path, model) = load_params(args)?;
        let rows = select_rows(args, &model, &[args.test.as_str()])?;
        let stop = execute::stop_on_signals()?;
        let factors = run_factors(&args.test, &params);
        let text = experiment_text(&args.test, &model_path, args.coarse, &set);
        Ok(Setup {
            args,
            params,
            model_path,
            model,
            rows,
            stop,
            factors,
            text,
        })
    }
}

/// `tilth calibrate`: with `--joint`, [`joint::joint`]; otherwise the
/// per-condition steps of the module's documentation, in order.
pub fn calibrate(args: &CalibrateArgs) -> Result<String> {
    crate::study::summary(|out| calibrate_into(args, out))
}

/// [`calibrate`], writing its summary to `out`.
fn calibrate_into(args: &CalibrateArgs, out: &mut dyn Write) -> Result<()> {
    if args.joint && args.per_test {
        bail!(
            "--per-test gives one test its own values; --joint shares one value across tests: choose one"
        );
    }
    if args.joint {
        if args.check_se.is_some() {
            bail!(
                "--check-se adds seeds to one condition's check; a --joint calibration checks every condition at one setting: leave it out"
            );
        }
        inputs::check_counts(args)?;
        return joint::joint(args, out);
    }
    inputs::check_single_test(args)?;
    let setup = Setup::new(args)?;
    // 1. The surface runs; 2. each condition's surface solved for its measurement.
    let (surface_plan, results) = surface::run_surfaces(&setup)?;
    let report: Vec<surface::Solved> = setup
        .rows
        .iter()
        .map(|m| surface::solve_condition(&setup, m, &surface_plan, &results))
        .collect::<Result<_>>()?;
    // 3. Refinement with direct runs.
    let iterations = refine::refine(&setup, &report)?;
    // 4. Uncertainty and plots, per condition; 5. the model and the report.
    let results_out: Vec<ConditionResult> = report
        .into_iter()
        .zip(iterations)
        .enumerate()
        .map(|(c, (cond, its))| outputs::condition_result(&setup, c, cond, its))
        .collect::<Result<_>>()?;
    outputs::write_outputs(&setup, &results_out, out)
}
