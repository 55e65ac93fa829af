//! `tilth calibrate --joint`: one value per free parameter, shared by every selected
//! measurement (several conditions, several tests), fitted to all of them at once.
//!
//! 1. **Surfaces.** For each measurement, the same 3^k factorial plus two centre points as
//!    the per-condition calibration, `--seeds` seeds each, and a quadratic surface f_i(theta).
//! 2. **Weighted least squares** on the surfaces: minimise sum_i ((f_i(theta) - y_i) /
//!    sigma_i)^2 over the parameters' ranges, sigma_i^2 = s_i^2 + u_i^2 with s_i the surface's
//!    residual standard deviation (the scatter of the runs about it) and u_i the measurement's
//!    uncertainty when the file gives one. Dividing by sigma makes newtons, degrees and
//!    kilopascals commensurable.
//! 3. **Refine** with direct runs of every measurement at the shared setting (`--check-seeds`
//!    seeds, the same ones each time), and Gauss-Newton steps on the surfaces' Jacobian (at
//!    most a quarter of each range) while any mean misses its measurement by more than
//!    `--tolerance` %, up to `--refine` times.
//! 4. **Uncertainty**: linearised intervals from the Jacobian of all the residuals (a ridge is
//!    reported as such) and an SMC posterior on the surfaces.
//! 5. **Output**: `calibration.json` (`"joint": true`), `calibration.md`, posterior samples,
//!    and `model.toml` with each parameter set to its one calibrated value (where every
//!    measurement fitted shares a condition, at that condition only, the previous value
//!    kept for the others).

mod objective;
mod report;

use crate::lab::model::Model;
use crate::study::calibrate::report as calibrate_report;
use crate::study::calibrate::{
    CalibrateArgs, Param, cond_values, describe, load_params, push_surface_runs, run_and_read,
    run_factors, select_rows, surface, surface_grid,
};
use crate::study::check::PairCheck;
use crate::study::lab_runs::{TestSetting, experiment_text};
use crate::study::measurements::Measurement;
use crate::study::measurements::TESTS;
use crate::sweep::execute;
use crate::sweep::plan::{Plan, PlannedRun};
use anyhow::{Result, anyhow, bail};
use objective::Objective;
use report::{Fitted, rows_out};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tilth_tools::calibrate::{Linearised, Posterior, linearised, minimise_in_box, smc};
use tilth_tools::compare::mean_sd;
use tilth_tools::rsm::Anova;

/// One measurement's response surface: the measurement, the fitted surface, the points it was
/// fitted to (parameter values, reading) and how many runs were planned for it.
type MeasurementFit = (Measurement, Anova, Vec<(Vec<f64>, f64)>, usize);

/// A test's surface plan before it runs: the test, its measurements and the plan.
type SurfacePlan<'a> = (&'a str, Vec<&'a Measurement>, Plan);

/// One measurement in the joint fit.
#[derive(Debug, Clone, Serialize)]
pub struct JointRow {
    pub test: String,
    pub row: usize,
    pub conditions: BTreeMap<String, f64>,
    pub observable: String,
    pub measured: f64,
    /// sigma_i: the weight's scale.
    pub sigma: f64,
    pub surface_runs: usize,
    pub surface_failed: usize,
    pub r2: f64,
    pub residual_sd: Option<f64>,
    pub equation: String,
    /// The surface's design points (parameter values, run value): what the fit saw.
    pub surface_points: Vec<(Vec<f64>, f64)>,
    /// The surface at the calibrated setting.
    pub predicted: f64,
    pub simulated: Vec<f64>,
    pub simulated_mean: f64,
    pub simulated_sd: Option<f64>,
    pub error_pct: f64,
    pub error_se_pct: Option<f64>,
    pub within_tolerance: bool,
}

/// One refinement: the shared setting and each row's mean there.
#[derive(Debug, Clone, Serialize)]
pub struct JointIteration {
    pub setting: Vec<f64>,
    pub means: Vec<f64>,
    pub error_pct: Vec<f64>,
}

/// `tilth calibrate --joint`: the steps of the module's documentation, in order.
pub fn joint(args: &CalibrateArgs, out: &mut dyn Write) -> Result<()> {
    let job = Joint::new(args)?;
    let params = &job.params;

    // 1. Surfaces.
    let plans = job.surface_plans()?;
    let fits = job.run_surfaces(plans)?;
    let objective = Objective::new(fits);
    let fits = &objective.fits;
    let low: Vec<f64> = params.iter().map(|p| p.low).collect();
    let high: Vec<f64> = params.iter().map(|p| p.high).collect();

    // 2. The shared setting on the surfaces.
    let setting = minimise_in_box(|t| objective.sum_sq(t), &low, &high);
    if !args.quiet {
        eprintln!(
            "joint least squares on {} surfaces: ({})",
            fits.len(),
            fmt(&setting)
        );
    }

    // 3. Direct runs at the shared setting, Gauss-Newton on the surfaces between them.
    let (iterations, last_values) = job.refine(&objective, setting)?;
    let setting = iterations
        .last()
        .expect("one iteration at least")
        .setting
        .clone();

    // 4. Uncertainty on the surfaces.
    let lin: Linearised = linearised(
        |t| objective.residuals(t),
        &setting,
        &params
            .iter()
            .map(|p| 1e-4 * (p.high - p.low))
            .collect::<Vec<_>>(),
    );
    let post: Posterior = smc(|t| -0.5 * objective.sum_sq(t), &low, &high, 2000, 17);
    std::fs::create_dir_all(&args.out)?;
    calibrate_report::write_samples(&args.out.join("posterior.csv"), params, &post)?;

    // 5. Outputs.
    let rows_out = rows_out(&objective, &last_values, &setting, args);
    let fitted = Fitted {
        objective: &objective,
        setting: &setting,
        rows: &rows_out,
        iterations: &iterations,
        lin: &lin,
        post: &post,
    };
    job.write_outputs(&fitted, out)
}

/// What every step of a joint calibration reads: the options, the tests, the free
/// parameters, the model, the measurements kept and their shear/UCS consistency.
struct Joint<'a> {
    args: &'a CalibrateArgs,
    tests: Vec<&'a str>,
    set: Vec<TestSetting>,
    params: Vec<Param>,
    /// The model file, absolute.
    model_path: PathBuf,
    model: Model,
    rows: Vec<Measurement>,
    /// Each (direct shear, UCS) pair of the rows, checked for one material.
    shear_ucs: Vec<PairCheck>,
    /// `shear_ucs` in words (empty when there is no pair).
    allowed: String,
    stop: Arc<AtomicBool>,
}

impl<'a> Joint<'a> {
    /// Reads and checks the options, the parameters, the model and the measurements, warns
    /// when the shear and UCS rows cannot come from one material, and installs the signal
    /// handler that stops the runs.
    fn new(args: &'a CalibrateArgs) -> Result<Self> {
        let set = args.set.parse()?;
        let tests: Vec<&str> = args.test.split(',').map(str::trim).collect();
        if let Some(t) = tests.iter().find(|t| !TESTS.contains(t)) {
            bail!(
                "--test {t}: unknown, allowed {} (comma-separated with --joint)",
                TESTS.join(", ")
            );
        }
        let (params, model_path, model) = load_params(args)?;
        let rows = select_rows(args, &model, &tests)?;
        // Before hours of runs: can the selected shear and UCS rows come from one material?
        let shear_ucs = crate::study::check::shear_ucs_pairs(&rows);
        let allowed = crate::study::check::describe(&shear_ucs);
        if !args.quiet && shear_ucs.iter().any(|p| !p.check.compatible) {
            eprintln!("warning: {allowed}");
        }
        let stop = execute::stop_on_signals()?;
        Ok(Joint {
            args,
            tests,
            set,
            params,
            model_path,
            model,
            rows,
            shear_ucs,
            allowed,
            stop,
        })
    }

    /// The observable a run of measurement `std` reads: each run reads its own
    /// measurement's.
    fn observable(&self, std: usize) -> Option<&str> {
        self.rows
            .iter()
            .find(|m| m.row == std)
            .map(|m| m.observable.as_str())
    }

    /// The surfaces' plans, one per test, every plan built (and each of its runs checked)
    /// before the first run: a parameter one of the tests cannot take (a bond key in the
    /// funnel test) is refused in seconds, not after the other tests' surfaces ran.
    fn surface_plans(&self) -> Result<Vec<SurfacePlan<'_>>> {
        let (args, params) = (self.args, &self.params);
        let grid = surface_grid(params.len());
        let mut plans: Vec<SurfacePlan> = vec![];
        for test in &self.tests {
            let mine: Vec<&Measurement> = self.rows.iter().filter(|m| m.test == *test).collect();
            if mine.is_empty() {
                continue;
            }
            let mut runs = vec![];
            for m in &mine {
                push_surface_runs(&mut runs, test, m, &grid, params, args)?;
            }
            let plan = Plan::generated(
                &format!("{test}-surface"),
                experiment_text(test, &self.model_path, args.coarse, &self.set),
                Path::new("."),
                run_factors(test, params),
                runs,
            )
            .map_err(|e| not_taken(e, test, params))?;
            plans.push((test, mine, plan));
        }
        Ok(plans)
    }

    /// Runs each plan in `DIR/surface-TEST` and fits every measurement's surface.
    fn run_surfaces(&self, plans: Vec<SurfacePlan>) -> Result<Vec<MeasurementFit>> {
        let (args, params) = (self.args, &self.params);
        let mut fits: Vec<MeasurementFit> = vec![];
        for (test, mine, plan) in plans {
            let values = run_and_read(
                &plan,
                &args.out.join(format!("surface-{test}")),
                args,
                &self.stop,
                |std| self.observable(std),
            )?;
            for m in mine {
                let pts: Vec<(Vec<f64>, f64)> = plan
                    .runs
                    .iter()
                    .zip(&values)
                    .filter(|(r, _)| r.std == m.row)
                    .filter_map(|(r, v)| {
                        v.map(|v| (params.iter().map(|p| r.values[&p.name]).collect(), v))
                    })
                    .collect();
                let total = plan.runs.iter().filter(|r| r.std == m.row).count();
                let fit = surface(params, m, &pts, total)?;
                fits.push((m.clone(), fit, pts, total));
            }
        }
        Ok(fits)
    }

    /// Direct runs of every measurement at the shared `setting`, and a Gauss-Newton step on
    /// the surfaces while any mean misses by more than `--tolerance` %, up to `--refine`
    /// times. Returns the rounds (one at least) and each measurement's values in the last.
    fn refine(
        &self,
        objective: &Objective,
        mut setting: Vec<f64>,
    ) -> Result<(Vec<JointIteration>, Vec<Vec<f64>>)> {
        let args = self.args;
        let fits = &objective.fits;
        let mut iterations: Vec<JointIteration> = vec![];
        let mut last_values: Vec<Vec<f64>> = vec![];
        for it in 0..=args.refine {
            let per_row = self.check(it, fits, &setting)?;
            let means: Vec<f64> = per_row.iter().map(|v| mean_sd(v).0).collect();
            let errors: Vec<f64> = fits
                .iter()
                .zip(&means)
                .map(|((m, ..), mean)| 100.0 * (mean - m.value) / m.value)
                .collect();
            iterations.push(JointIteration {
                setting: setting.clone(),
                means: means.clone(),
                error_pct: errors.clone(),
            });
            last_values = per_row;
            if errors.iter().all(|e| e.abs() <= args.tolerance) || it == args.refine {
                break;
            }
            let next = objective.gauss_newton_next(&setting, &means, &self.params);
            // Pinned at the ranges' edges (or a zero step): more runs there would only repeat
            // these.
            if next == setting {
                if !args.quiet {
                    eprintln!(
                        "the step stays at ({}): the ranges' edge; refinement stops",
                        fmt(&setting)
                    );
                }
                break;
            }
            setting = next;
        }
        Ok((iterations, last_values))
    }

    /// Round `it`'s direct runs: `--check-seeds` seeds (1001 on, the same each round) of
    /// every measurement at `setting`, one plan per test in `DIR/check-IT-TEST`. Returns
    /// each measurement's values; an error when all of one's runs failed.
    fn check(&self, it: usize, fits: &[MeasurementFit], setting: &[f64]) -> Result<Vec<Vec<f64>>> {
        let (args, params) = (self.args, &self.params);
        let n_check = args.check_seeds.unwrap_or(args.seeds);
        let mut per_row: Vec<Vec<f64>> = vec![vec![]; fits.len()];
        for test in &self.tests {
            let idx: Vec<usize> = (0..fits.len())
                .filter(|i| fits[*i].0.test == *test)
                .collect();
            if idx.is_empty() {
                continue;
            }
            let mut runs = vec![];
            for &i in &idx {
                for s in 0..n_check {
                    let mut values = cond_values(test, &fits[i].0, &args.data)?;
                    for (p, v) in params.iter().zip(setting) {
                        values.insert(p.name.clone(), *v);
                    }
                    runs.push(PlannedRun {
                        id: runs.len() + 1,
                        std: fits[i].0.row,
                        replicate: s + 1,
                        coded: BTreeMap::new(),
                        values,
                        seed: 1001 + s as u64,
                    });
                }
            }
            let plan = Plan::generated(
                &format!("{test}-check-{it}"),
                experiment_text(test, &self.model_path, args.coarse, &self.set),
                Path::new("."),
                run_factors(test, params),
                runs,
            )?;
            let dir = args.out.join(format!("check-{it}-{test}"));
            let values = run_and_read(&plan, &dir, args, &self.stop, |std| self.observable(std))?;
            for &i in &idx {
                per_row[i] = plan
                    .runs
                    .iter()
                    .zip(&values)
                    .filter(|(r, _)| r.std == fits[i].0.row)
                    .filter_map(|(_, v)| *v)
                    .collect();
                if per_row[i].is_empty() {
                    bail!(
                        "{} at {}: every run at the shared setting failed (see {})",
                        test,
                        describe(&fits[i].0.conditions),
                        dir.display()
                    );
                }
            }
        }
        Ok(per_row)
    }
}

/// A plan of `test` refused: says which free parameter it cannot take when that is the cause
/// (bond keys exist only in the tests with bonds).
fn not_taken(e: anyhow::Error, test: &str, params: &[Param]) -> anyhow::Error {
    let text = format!("{e:#}");
    match params
        .iter()
        .find(|p| text.contains(&format!("unknown key '{}'", p.key)))
    {
        Some(p) => anyhow!(
            "--param {}.{}: the {test} test does not take it ({text}); calibrate it jointly with the tests that do (a bond parameter: direct_shear, ucs)",
            p.pair,
            p.key
        ),
        None => e,
    }
}

/// Values to 4 decimals, comma-separated: a setting in messages and the report.
fn fmt(x: &[f64]) -> String {
    x.iter()
        .map(|v| format!("{v:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}
