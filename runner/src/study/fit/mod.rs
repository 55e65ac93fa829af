//! `tilth fit --model M.toml --data D.csv --param ... --out DIR`: one set of parameters for
//! every measured row at once (all tests, conditions and observables), by weighted least
//! squares on simulations; a candidate effect's strength can be one of them.
//!
//! Where `tilth calibrate` fits each condition on its own (a parameter becomes a table over
//! the condition), `fit` moves each parameter by one amount everywhere, so that the
//! measurements together decide it: what "add the effect and recalibrate" needs after
//! `tilth diagnose`, and the joint calibration EDEM users do by hand.
//!
//! Parameters: `PAIR.KEY=LOW:HIGH` shifts the model's value (a number or every point of its
//! table) by one offset, keeping every point within [LOW, HIGH]; `candidate.NAME=LOW:HIGH`
//! is the strength of the model file's `[candidates.NAME]`, switched on (start 0, or
//! `LOW:HIGH@START`, e.g. diagnose's estimate).
//!
//! Levenberg-Marquardt with finite-difference Jacobians. Each iteration runs the current
//! setting and each parameter moved by a quarter of its range (`JACOBIAN_STEP`), all with
//! seeds 1..R (common random numbers, though the grains' chaos leaves two runs of one seed
//! little alike after the change). Residuals are standardised by
//! each row's standard error sqrt(uncertainty^2 + s^2 / R), s the current setting's scatter:
//! chi^2 = sum z^2. The step solves (J'J + lambda diag J'J) d = J'z, limited to a quarter of
//! each range; a step that raises chi^2 is taken back, lambda raised and the next step at most half as long (Marquardt 1963).
//! Standard errors from (J'J - N)^-1, scaled by chi^2 / dof when that is above 1, where N is
//! the noise the finite-difference Jacobian carries into J'J, measured from the per-seed
//! slopes (`jacobian_noise.rs`); the naive (J'J)^-1 is reported beside them as a lower
//! bound.
//!
//! The fit stops at the first setting at the noise (`stop.rs`): chi^2 <= dof, and the next
//! step's predicted chi^2 gain (the score statistic) under chi^2_P's 95 % quantile. A step
//! from there would follow the runs' scatter and costs 1 + P settings of DEM runs;
//! `--to-minimum` keeps stepping. It also stops when every step is under 1 % of its range,
//! or after `--iterations`.
//!
//! The misfit test at the estimate (`chi2_scores` and `p_value` in fit.json; diagnose's
//! refit reads them) maps each z to the normal score with its tail probability under
//! Student's t with the row's Welch-Satterthwaite degrees of freedom (R - 1 from the runs,
//! the measurement's `uncertainty_dof`), [`tilth_tools::compare::welch`]: with R = 4, sum
//! z^2 against chi^2(dof) rejects a right model far more often than its level says.
//!
//! Writes `DIR/fit.json` (estimate, standard errors, correlations, the history),
//! `DIR/fit.md`, and `DIR/model.toml`: the model with the fitted parameters, ready for
//! `tilth compare`. Runs go to `DIR/runs/iter-K/<variant>/` and resume.

mod from_diagnosis;
mod jacobian_noise;
mod levenberg_marquardt;
mod outputs;
mod params;
mod simulations;
mod stop;

use super::measurements::{Measurement, check_against_model, read_measurements};
use crate::lab::model::Model;
use crate::study::lab_runs::LabRunArgs;
use crate::sweep::execute;
use anyhow::{Context, Result, bail};
use clap::Args;
pub use levenberg_marquardt::Step;
use levenberg_marquardt::levenberg_marquardt;
use outputs::write_outputs;
use params::free_params;
pub use params::{FreeParam, Target};
use simulations::Problem;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Starting model file.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV): every row is fitted.
    #[arg(long)]
    pub data: PathBuf,
    /// A free parameter: `PAIR.KEY=LOW:HIGH` or `candidate.NAME=LOW:HIGH[@START]`
    /// (repeatable).
    #[arg(long = "param", required_unless_present = "from_diagnosis")]
    pub params: Vec<String>,
    /// Act on `tilth diagnose`'s verdict in DIR/diagnosis.json: its free parameters, and the
    /// strength of each effect it names (from its estimate). Refused unless the verdict is
    /// `effect`. Any --param is added.
    #[arg(long, value_name = "DIR")]
    pub from_diagnosis: Option<PathBuf>,
    /// Runs per row and setting (seeds 1..R, the same at every setting).
    #[arg(long, default_value_t = 3)]
    pub replicates: usize,
    /// Levenberg-Marquardt iterations, at most (each runs 1 + parameters settings).
    #[arg(long, default_value_t = 4)]
    pub iterations: usize,
    /// Keep stepping at the noise (chi^2 <= degrees of freedom and the next step's predicted
    /// chi^2 gain under chi^2_P's 95 % quantile), where the fit stops by default.
    #[arg(long)]
    pub to_minimum: bool,
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub lab: LabRunArgs,
}

/// `tilth fit`: checks the inputs, fits the free parameters by Levenberg-Marquardt on
/// simulations, and writes the fitted model and the report (see the module docs).
pub fn fit(args: &FitArgs) -> Result<String> {
    crate::study::summary(|out| fit_into(args, out))
}

/// [`fit`], writing its summary to `out`.
fn fit_into(args: &FitArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.lab.set.parse()?;
    check_counts(args)?;
    let model_path = std::path::absolute(&args.model)?;
    let model = Model::load(&model_path)?;
    let text = std::fs::read_to_string(&model_path)?;
    let doc: toml_edit::DocumentMut = text
        .parse()
        .with_context(|| format!("{}: not TOML", args.model.display()))?;
    let rows = read_measurements(&args.data)?;
    check_against_model(&rows, &model, &args.data)?;
    let params = free_params(args, &model, &doc)?;
    let n = params.len();
    let stop = execute::stop_on_signals()?;
    let runs = args.out.join("runs");
    let models = args.out.join("models");
    std::fs::create_dir_all(&models)?;
    let problem = Problem {
        args,
        model: &model,
        text: &text,
        rows: &rows,
        params: &params,
        set: &set,
        stop: &stop,
        runs,
        models,
    };
    let dof = rows.len().saturating_sub(n).max(1);
    let fitted = levenberg_marquardt(&problem, dof)?;
    write_outputs(&problem, &fitted, dof, out)
}

/// Refuses replicate and iteration counts a fit cannot work with, before any run.
fn check_counts(args: &FitArgs) -> Result<()> {
    if args.replicates < 2 {
        bail!(
            "--replicates {}: allowed 2 or more (the rows' standard errors need the runs' scatter)",
            args.replicates
        );
    }
    if args.iterations == 0 {
        bail!("--iterations 0: allowed 1 or more");
    }
    Ok(())
}

/// RMSE of simulated - measured per observable, in its unit.
fn rmse(rows: &[Measurement], sim: &[f64]) -> BTreeMap<String, f64> {
    let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    for (m, s) in rows.iter().zip(sim) {
        let e = acc.entry(m.observable.clone()).or_default();
        e.0 += (s - m.value).powi(2);
        e.1 += 1;
    }
    acc.into_iter()
        .map(|(k, (ss, n))| (k, (ss / n as f64).sqrt()))
        .collect()
}
