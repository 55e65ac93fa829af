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

use super::calibrate_report;
use super::compare::{
    Dispatch, Measurement, SetArgs, condition_factors, experiment_text, factor, mean_sd,
    read_measurements, run_generated,
};
use crate::lab::model::{At, Model, evaluate_at};
use crate::sweep::execute;
use crate::sweep::job::{Status, read_summary, run_dir};
use crate::sweep::plan::{Factor, Plan, PlannedRun};
use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tilth_tools::calibrate::{Check, Linearised, Posterior, linearised, next_from_checks, smc};
use tilth_tools::rsm::plot::CheckRuns;
use tilth_tools::rsm::{self, Anova, Data, FitOptions, Order, Table};

#[derive(Debug, Args)]
pub struct CalibrateArgs {
    /// Starting model file, e.g. models/li2022.toml.
    #[arg(long)]
    pub model: PathBuf,
    /// Measurements (CSV), e.g. data/li2022/measurements.csv.
    #[arg(long)]
    pub data: PathBuf,
    /// The test whose measurements to fit: repose, direct_shear or ucs (with `--joint`,
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

pub fn calibrate(args: &CalibrateArgs, out: &mut dyn Write) -> Result<()> {
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
        check_counts(args)?;
        return super::calibrate_joint::joint(args, out);
    }
    if args.test.contains(',') {
        bail!(
            "--test {}: several tests are calibrated together only with --joint (one value per parameter across them)",
            args.test
        );
    }
    if !["repose", "direct_shear", "ucs"].contains(&args.test.as_str()) {
        bail!(
            "--test {}: unknown, allowed repose, direct_shear, ucs",
            args.test
        );
    }
    check_counts(args)?;
    let set = args.set.parse()?;
    let (params, model_path, model) = load_params(args)?;
    let rows = select_rows(args, &model, &[args.test.as_str()])?;
    let stop = execute::stop_on_signals()?;
    let factors = run_factors(&args.test, &params);
    let text = experiment_text(&args.test, &model_path, args.coarse, &set);
    let real = |p: &Param, z: f64| 0.5 * (p.low + p.high) + z * 0.5 * (p.high - p.low);
    let conds_of = |m: &Measurement| cond_values(&args.test, m, &args.data);

    // 1. The surface runs.
    let grid = surface_grid(params.len());
    let mut runs = vec![];
    for m in &rows {
        for (g, z) in grid.iter().enumerate() {
            // The factorial shares its seeds (common random numbers: differences between
            // settings are not blurred by the packing); the two extra centre points take
            // fresh seeds, so that they measure the scatter between seeds.
            let first_seed = 1 + g.saturating_sub(grid.len() - 3) * args.seeds;
            for s in 0..args.seeds {
                let mut values = conds_of(m)?;
                for (p, zi) in params.iter().zip(z) {
                    values.insert(p.name.clone(), real(p, *zi));
                }
                runs.push(PlannedRun {
                    id: runs.len() + 1,
                    std: m.row,
                    replicate: s + 1,
                    coded: params
                        .iter()
                        .zip(z)
                        .map(|(p, v)| (p.name.clone(), *v))
                        .collect(),
                    values,
                    seed: (first_seed + s) as u64,
                });
            }
        }
    }
    let surface_plan = Plan::generated(
        &format!("{}-surface", args.test),
        text.clone(),
        Path::new("."),
        factors.clone(),
        runs,
    )?;
    let results = run_plan(&surface_plan, &args.out.join("surface"), args, &stop)?;

    // 2-4 per condition.
    let mut report = vec![];
    for m in &rows {
        let conds = conds_of(m)?;
        let mine: Vec<(&PlannedRun, Option<f64>)> = surface_plan
            .runs
            .iter()
            .zip(&results)
            .filter(|(r, _)| r.std == m.row)
            .map(|(r, v)| (r, *v))
            .collect();
        let ok: Vec<(&PlannedRun, f64)> = mine
            .iter()
            .filter_map(|(r, v)| v.map(|v| (*r, v)))
            .collect();
        let pts: Vec<(Vec<f64>, f64)> = ok
            .iter()
            .map(|(r, v)| (params.iter().map(|p| r.values[&p.name]).collect(), *v))
            .collect();
        let fit = surface(&params, m, &pts, mine.len())?;
        let start: Vec<f64> = params
            .iter()
            .map(|p| {
                let form = param_form(&model, p).expect("checked above");
                evaluate_at(form, At::test(&conds, &args.test))
            })
            .collect::<Result<_>>()?;
        let solution = rsm::solve(&fit, &describe(&conds), m.value, &[])?;
        let zs = fit.coding.code(&start);
        let chosen = solution
            .settings
            .iter()
            .min_by(|a, b| {
                let d = |s: &rsm::Setting| {
                    fit.coding
                        .code(&s.values)
                        .iter()
                        .zip(&zs)
                        .map(|(x, y)| (x - y).powi(2))
                        .sum::<f64>()
                };
                d(a).total_cmp(&d(b))
            })
            .or(solution.closest.as_ref())
            .map(|s| s.values.clone())
            .unwrap_or_else(|| start.clone());
        if !args.quiet {
            eprintln!("{}: {}", describe(&conds), solution.statement);
        }
        report.push((
            m.clone(),
            conds,
            fit,
            solution,
            start,
            chosen,
            mine.len() - ok.len(),
            mine.len(),
        ));
    }

    // 3. Refine with direct runs, all conditions together per iteration.
    let mut settings: Vec<Vec<f64>> = report.iter().map(|r| r.5.clone()).collect();
    let mut iterations: Vec<Vec<Iteration>> = vec![vec![]; report.len()];
    let mut active: Vec<bool> = vec![true; report.len()];
    let targets: Vec<f64> = report.iter().map(|r| r.0.value).collect();
    for it in 0..=args.refine {
        if !active.iter().any(|a| *a) {
            break;
        }
        let mut all = check(
            it,
            &active,
            &settings,
            &report.iter().map(|r| r.1.clone()).collect::<Vec<_>>(),
            &targets,
            &params,
            (&text, &factors),
            args,
            &stop,
        )?;
        for c in 0..report.len() {
            if !active[c] {
                continue;
            }
            let got = std::mem::take(&mut all[c]);
            if got.is_empty() {
                bail!(
                    "{}: every run at the chosen setting failed (see {})",
                    describe(&report[c].1),
                    args.out.join(format!("check-{it}")).display()
                );
            }
            let (mean, sd) = mean_sd(&got);
            let target = report[c].0.value;
            let fit = &report[c].2;
            let err = 100.0 * (mean - target) / target;
            iterations[c].push(Iteration {
                setting: settings[c].clone(),
                predicted: fit.predict(&settings[c]),
                values: got,
                mean,
                sd,
                error_pct: err,
            });
            if err.abs() <= args.tolerance || it == args.refine {
                active[c] = false;
                continue;
            }
            // Newton step along the surface's gradient (real units), inside the ranges.
            let z = fit.coding.code(&settings[c]);
            let g: Vec<f64> = fit
                .gradient_coded(&z)
                .iter()
                .enumerate()
                .map(|(i, d)| d / fit.coding.half(i))
                .collect();
            let g2: f64 = g.iter().map(|v| v * v).sum();
            if g2 == 0.0 {
                active[c] = false;
                continue;
            }
            // With one parameter and checks at two settings or more, the step follows the
            // line through the checks themselves (measured where the calibration is, on the
            // same seeds) rather than the surface's slope there; see `next_from_checks`.
            let miss = mean - target;
            let from_checks = if params.len() == 1 {
                let checks: Vec<Check> = iterations[c]
                    .iter()
                    .map(|i| Check {
                        setting: i.setting[0],
                        mean: i.mean,
                        runs: i.values.len(),
                    })
                    .collect();
                next_from_checks(&checks, target, g[0])
            } else {
                None
            };
            let step: Vec<f64> = match from_checks {
                Some((x, slope)) => {
                    if !args.quiet {
                        eprintln!(
                            "{}: the checks' line ({slope:.4} per unit) puts the target at {x:.6}",
                            describe(&report[c].1)
                        );
                    }
                    vec![x - settings[c][0]]
                }
                None => g.iter().map(|gi| -miss * gi / g2).collect(),
            };
            // A trust region: the surface is a fit to noisy runs, so no step goes further than
            // a quarter of any parameter's range (half a coded unit).
            let worst = step
                .iter()
                .zip(&params)
                .map(|(d, p)| d.abs() / (0.25 * (p.high - p.low)))
                .fold(1.0, f64::max);
            settings[c] = settings[c]
                .iter()
                .zip(&step)
                .zip(&params)
                .map(|((x, d), p)| (x + d / worst).clamp(p.low, p.high))
                .collect();
        }
    }

    // 4. Uncertainty, and the outputs.
    let mut results_out = vec![];
    for (c, (m, conds, fit, solution, start, _, failed, total)) in report.into_iter().enumerate() {
        let last = iterations[c]
            .last()
            .cloned()
            .expect("at least one iteration");
        let se_pct = last
            .sd
            .map(|sd| 100.0 * sd / (last.values.len() as f64).sqrt() / m.value.abs());
        let meas_sd = 0.0;
        let sigma = (fit.std_dev.unwrap_or(0.0).powi(2) + meas_sd)
            .sqrt()
            .max(1e-9 * m.value.abs());
        let lin = linearised(
            |t| vec![(fit.predict(t) - m.value) / sigma],
            &last.setting,
            &params
                .iter()
                .map(|p| 1e-4 * (p.high - p.low))
                .collect::<Vec<_>>(),
        );
        let low: Vec<f64> = params.iter().map(|p| p.low).collect();
        let high: Vec<f64> = params.iter().map(|p| p.high).collect();
        let post = smc(
            |t| -0.5 * ((fit.predict(t) - m.value) / sigma).powi(2),
            &low,
            &high,
            2000,
            17 + c as u64,
        );
        std::fs::create_dir_all(&args.out)?;
        // Per-condition files: posterior-SLUG.csv, curve-SLUG.svg, contour-SLUG.svg.
        let slug = super::rsm_plot::slug(&describe(&conds));
        let file = |kind: &str, ext: &str| args.out.join(format!("{kind}-{slug}.{ext}"));
        calibrate_report::write_samples(&file("posterior", "csv"), &params, &post)?;
        let marks = vec![
            (start.clone(), "starting model".to_string()),
            (
                last.setting.clone(),
                format!(
                    "calibrated: {:.2} +- {:.2} over {} seeds",
                    last.mean,
                    last.sd.unwrap_or(0.0),
                    last.values.len()
                ),
            ),
        ];
        // One free parameter: the fitted curve with its runs, the target, and every direct
        // check (Design-Expert's one-factor plot, with the checks that decided).
        let checks: Vec<CheckRuns> = iterations[c]
            .iter()
            .enumerate()
            .map(|(k, it)| CheckRuns {
                x: it.setting[0],
                values: it.values.clone(),
                label: format!(
                    "check {}: {:.4} +- {:.4} over {} seeds",
                    k + 1,
                    it.mean,
                    it.sd.unwrap_or(0.0),
                    it.values.len()
                ),
            })
            .collect();
        let curve = if params.len() == 1 {
            tilth_tools::rsm::plot::response_curve_checked_svg(
                &fit,
                std::slice::from_ref(&solution),
                &[],
                &checks,
            )?
        } else {
            None
        };
        if let Some(svg) = curve {
            std::fs::write(file("curve", "svg"), svg)?;
        }
        if let Some(svg) = tilth_tools::rsm::plot::contour_marked_svg(&fit, &solution, &[], &marks)?
        {
            std::fs::write(file("contour", "svg"), svg)?;
        }
        results_out.push(ConditionResult {
            conditions: conds,
            measured: m.value,
            start,
            surface_runs: total,
            surface_failed: failed,
            r2: fit.r2,
            residual_sd: fit.std_dev,
            equation: fit.equation_real.clone(),
            ridge_statement: solution.statement.clone(),
            ridge_points: solution.settings.len(),
            calibrated: last.setting.clone(),
            simulated_mean: last.mean,
            simulated_sd: last.sd,
            error_pct: last.error_pct,
            error_se_pct: se_pct,
            within_tolerance: last.error_pct.abs() <= args.tolerance,
            within_beyond_scatter: se_pct
                .is_some_and(|se| last.error_pct.abs() + 2.0 * se <= args.tolerance),
            iterations: iterations[c].clone(),
            linearised: lin,
            posterior: post,
        });
    }
    let model_out = args.out.join("model.toml");
    let test = args.per_test.then_some(args.test.as_str());
    calibrate_report::write_model(&model_path, &model_out, &params, &results_out, test)?;
    let json = serde_json::json!({
        "test": args.test,
        "model": args.model,
        "coarse": args.coarse,
        "set": args.set.set,
        "seeds": args.seeds,
        "check_seeds": args.check_seeds.unwrap_or(args.seeds),
        "check_se_pct": args.check_se,
        "max_check_seeds": args.check_se.map(|_| args
            .max_check_seeds
            .unwrap_or(4 * args.check_seeds.unwrap_or(args.seeds))),
        "tolerance_pct": args.tolerance,
        "params": params,
        "conditions": results_out,
        "calibrated_model": model_out,
    });
    std::fs::write(
        args.out.join("calibration.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let md = calibrate_report::markdown(args, &params, &results_out);
    std::fs::write(args.out.join("calibration.md"), &md)?;
    write!(out, "{md}")?;
    Ok(())
}

/// One direct check of every active condition at its setting: `--check-seeds` seeds (1001
/// on), in `DIR/check-IT`; with `--check-se`, more batches of as many seeds (in
/// `DIR/check-IT-K`) for each condition whose mean is not yet precise enough
/// ([`wants_more_seeds`]). Returns every condition's values (empty for inactive ones).
#[allow(clippy::too_many_arguments)]
fn check(
    it: usize,
    active: &[bool],
    settings: &[Vec<f64>],
    conditions: &[BTreeMap<String, f64>],
    targets: &[f64],
    params: &[Param],
    (text, factors): (&str, &[Factor]),
    args: &CalibrateArgs,
    stop: &Arc<AtomicBool>,
) -> Result<Vec<Vec<f64>>> {
    let batch = args.check_seeds.unwrap_or(args.seeds);
    let most = match args.check_se {
        Some(_) => args.max_check_seeds.unwrap_or(4 * batch),
        None => batch,
    };
    let mut got: Vec<Vec<f64>> = vec![vec![]; active.len()];
    let mut planned = vec![0usize; active.len()];
    let mut want = active.to_vec();
    for k in 0.. {
        let mut runs = vec![];
        for c in (0..active.len()).filter(|c| want[*c]) {
            for s in planned[c]..(planned[c] + batch).min(most) {
                let mut values = conditions[c].clone();
                for (p, v) in params.iter().zip(&settings[c]) {
                    values.insert(p.name.clone(), *v);
                }
                runs.push(PlannedRun {
                    id: runs.len() + 1,
                    std: c,
                    replicate: s + 1,
                    coded: BTreeMap::new(),
                    values,
                    seed: 1001 + s as u64,
                });
            }
        }
        if runs.is_empty() {
            break;
        }
        // The first batch keeps the name and place a check always had, so that an earlier
        // calibration's runs are reused.
        let name = match k {
            0 => format!("check-{it}"),
            k => format!("check-{it}-{k}"),
        };
        let plan = Plan::generated(
            &format!("{}-{name}", args.test),
            text.to_string(),
            Path::new("."),
            factors.to_vec(),
            runs,
        )?;
        let values = run_plan(&plan, &args.out.join(&name), args, stop)?;
        let ran: Vec<usize> = (0..active.len()).filter(|c| want[*c]).collect();
        for c in ran {
            got[c].extend(
                plan.runs
                    .iter()
                    .zip(&values)
                    .filter(|(r, _)| r.std == c)
                    .filter_map(|(_, v)| *v),
            );
            planned[c] = (planned[c] + batch).min(most);
            want[c] = planned[c] < most && wants_more_seeds(&got[c], targets[c], args);
        }
    }
    Ok(got)
}

/// Whether a check's mean needs more seeds under `--check-se PCT`: its standard error is
/// above PCT % of the measurement (or unknown, with one run), and it does not already miss
/// by more than the tolerance plus two standard errors.
pub fn wants_more_seeds(values: &[f64], target: f64, args: &CalibrateArgs) -> bool {
    let Some(pct) = args.check_se else {
        return false;
    };
    let (mean, sd) = mean_sd(values);
    let Some(sd) = sd else {
        return true;
    };
    let se = 100.0 * sd / (values.len() as f64).sqrt() / target.abs();
    let err = 100.0 * (mean - target) / target;
    se > pct && err.abs() - 2.0 * se <= args.tolerance
}

fn check_counts(args: &CalibrateArgs) -> Result<()> {
    if args.check_seeds == Some(0) {
        bail!("--check-seeds 0 is out of range: allowed 1 or more");
    }
    if args.seeds == 0 {
        bail!("--seeds 0 is out of range: allowed 1 or more");
    }
    if let Some(se) = args.check_se {
        if !(se > 0.0 && se.is_finite()) {
            bail!("--check-se {se} is out of range: allowed > 0 (percent of the measurement)");
        }
    }
    let batch = args.check_seeds.unwrap_or(args.seeds);
    match args.max_check_seeds {
        Some(_) if args.check_se.is_none() => {
            bail!("--max-check-seeds is the cap of --check-se; give --check-se PCT too")
        }
        Some(max) if max < batch => bail!(
            "--max-check-seeds {max} is out of range: allowed at least --check-seeds ({batch})"
        ),
        _ => {}
    }
    if !(args.tolerance > 0.0) {
        bail!(
            "--tolerance {} is out of range: allowed > 0 (percent)",
            args.tolerance
        );
    }
    Ok(())
}

/// Runs `plan` into `dir`; each run's value of the test's own observable (None when it
/// failed).
fn run_plan(
    plan: &Plan,
    dir: &Path,
    args: &CalibrateArgs,
    stop: &Arc<AtomicBool>,
) -> Result<Vec<Option<f64>>> {
    let observable = match args.test.as_str() {
        "repose" => "repose_angle_deg",
        "direct_shear" => "peak_shear_force_n",
        _ => "ucs_kpa",
    };
    run_and_read(plan, dir, args, stop, |_| Some(observable))
}

/// Runs `plan` into `dir`; each run's value of `observable(run.std)` (None when the run
/// failed or has no such reading).
pub fn run_and_read<'a>(
    plan: &Plan,
    dir: &Path,
    args: &CalibrateArgs,
    stop: &Arc<AtomicBool>,
    observable: impl Fn(usize) -> Option<&'a str>,
) -> Result<Vec<Option<f64>>> {
    run_generated(plan, dir, &Dispatch::Local(args.cores), args.quiet, stop)?;
    Ok(plan
        .runs
        .iter()
        .map(|r| {
            let observable = observable(r.std)?;
            let s = read_summary(&run_dir(dir, r.id))?;
            if s.status != Status::Done {
                return None;
            }
            s.reduced.as_ref()?.get(observable)?.as_f64()
        })
        .collect())
}

/// The free parameters, the model file (absolute) and the model, each parameter checked to
/// be in it.
pub fn load_params(args: &CalibrateArgs) -> Result<(Vec<Param>, PathBuf, Model)> {
    let params: Vec<Param> = args
        .params
        .iter()
        .map(|p| parse_param(p))
        .collect::<Result<_>>()?;
    let model_path = std::path::absolute(&args.model)?;
    let model = Model::load(&model_path)?;
    for p in &params {
        if param_form(&model, p).is_none() {
            bail!(
                "--param {}.{}: the model {} has no pairs.{}.{} (nor bond.pairs.{}.{})",
                p.pair,
                p.key,
                args.model.display(),
                p.pair,
                p.key,
                p.pair,
                p.key
            );
        }
    }
    Ok((params, model_path, model))
}

/// The measurements of `tests` that every `--where` keeps, checked against the model.
pub fn select_rows(
    args: &CalibrateArgs,
    model: &Model,
    tests: &[&str],
) -> Result<Vec<Measurement>> {
    let all = read_measurements(&args.data)?;
    super::measurements::check_against_model(&all, model, &args.data)?;
    let mut rows: Vec<Measurement> = all
        .into_iter()
        .filter(|m| tests.contains(&m.test.as_str()))
        .collect();
    for f in &args.filters {
        let (k, v) = f
            .split_once('=')
            .ok_or_else(|| anyhow!("--where {f:?}: expected NAME=VALUE"))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| anyhow!("--where {f:?}: {v:?} is not a number"))?;
        rows.retain(|m| m.conditions.get(k.trim()) == Some(&v));
    }
    if rows.is_empty() {
        bail!(
            "{}: no {} measurement to calibrate against",
            args.data.display(),
            args.test
        );
    }
    Ok(rows)
}

/// The surface design in coded units: the 3^k factorial, then two more centre points.
pub fn surface_grid(k: usize) -> Vec<Vec<f64>> {
    let mut grid: Vec<Vec<f64>> = (0..3usize.pow(k as u32))
        .map(|mut g| {
            (0..k)
                .map(|_| {
                    let v = (g % 3) as f64 - 1.0;
                    g /= 3;
                    v
                })
                .collect()
        })
        .collect();
    grid.push(vec![0.0; k]);
    grid.push(vec![0.0; k]);
    grid
}

/// The factors of a test's runs: its conditions, then the free parameters in the scene.
pub fn run_factors(test: &str, params: &[Param]) -> Vec<Factor> {
    let mut f = condition_factors(test);
    for p in params {
        let mut x = factor(&p.name, &format!("scene:pairs[{}].{}", p.pair, p.key));
        x.low = p.low;
        x.high = p.high;
        f.push(x);
    }
    f
}

/// A measurement's conditions, as the test's condition factors take them.
pub fn cond_values(test: &str, m: &Measurement, data: &Path) -> Result<BTreeMap<String, f64>> {
    condition_factors(test)
        .iter()
        .map(|f| {
            m.conditions
                .get(&f.name)
                .map(|v| (f.name.clone(), *v))
                .ok_or_else(|| {
                    anyhow!(
                        "{}:{}: a {test} row needs `{}`",
                        data.display(),
                        m.row,
                        f.name
                    )
                })
        })
        .collect()
}

/// A quadratic surface of one measurement's observable over the parameters, from the runs
/// that finished (`pts`: parameter values, value) out of `total`.
pub fn surface(
    params: &[Param],
    m: &Measurement,
    pts: &[(Vec<f64>, f64)],
    total: usize,
) -> Result<Anova> {
    let mut columns: Vec<(&str, Vec<f64>)> = params
        .iter()
        .enumerate()
        .map(|(j, p)| (p.name.as_str(), pts.iter().map(|(x, _)| x[j]).collect()))
        .collect();
    columns.push((m.observable.as_str(), pts.iter().map(|(_, v)| *v).collect()));
    let origin = format!("{} surface at {}", m.test, describe(&m.conditions));
    let table = Table::from_columns(&origin, &columns);
    let names: Vec<String> = params.iter().map(|p| p.name.clone()).collect();
    let ranges: Vec<(f64, f64)> = params.iter().map(|p| (p.low, p.high)).collect();
    let data = Data::from_table(&table, &names, &m.observable, Some(&ranges))?;
    rsm::fit(
        &data,
        FitOptions {
            order: Order::Quadratic,
            curvature: false,
            backward: None,
        },
    )
    .with_context(|| format!("{origin}: {} of {total} runs finished", pts.len()))
}

pub fn describe(c: &BTreeMap<String, f64>) -> String {
    c.iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(",")
}
