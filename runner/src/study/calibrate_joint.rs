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

use super::calibrate::{
    CalibrateArgs, Param, cond_values, describe, load_params, param_form, run_and_read,
    run_factors, select_rows, surface, surface_grid,
};
use super::calibrate_report;
use super::compare::{Measurement, experiment_text, mean_sd};
use super::measurements::TESTS;
use crate::lab::model::{At, evaluate_at};
use crate::sweep::execute;
use crate::sweep::plan::{Plan, PlannedRun};
use anyhow::{Result, anyhow, bail};
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;
use tilth_tools::calibrate::{
    Linearised, Posterior, gauss_newton_step, linearised, minimise_in_box, smc,
};
use tilth_tools::rsm::Anova;

/// One measurement's response surface: the measurement, the fitted surface, the points it was
/// fitted to (parameter values, reading) and how many runs were planned for it.
type MeasurementFit = (Measurement, Anova, Vec<(Vec<f64>, f64)>, usize);

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

pub fn joint(args: &CalibrateArgs, out: &mut dyn Write) -> Result<()> {
    let set = args.set.parse()?;
    let tests: Vec<&str> = args.test.split(',').map(str::trim).collect();
    if let Some(t) = tests.iter().find(|t| !TESTS.contains(t)) {
        bail!(
            "--test {t}: unknown, allowed repose, direct_shear, ucs (comma-separated with --joint)"
        );
    }
    let (params, model_path, model) = load_params(args)?;
    let rows = select_rows(args, &model, &tests)?;
    // Before hours of runs: can the selected shear and UCS rows come from one material?
    let shear_ucs = super::check::shear_ucs_pairs(&rows);
    let allowed = super::check::describe(&shear_ucs);
    if !args.quiet && shear_ucs.iter().any(|p| !p.check.compatible) {
        eprintln!("warning: {allowed}");
    }
    let stop = execute::stop_on_signals()?;
    // Each run reads its own measurement's observable.
    let observable = |std: usize| {
        rows.iter()
            .find(|m| m.row == std)
            .map(|m| m.observable.as_str())
    };
    let k = params.len();
    let real = |p: &Param, z: f64| 0.5 * (p.low + p.high) + z * 0.5 * (p.high - p.low);
    let grid = surface_grid(k);

    // 1. Surfaces, one plan per test, every plan built (and each of its runs checked)
    // before the first run: a parameter one of the tests cannot take (a bond key in the
    // funnel test) is refused in seconds, not after the other tests' surfaces ran.
    let mut plans: Vec<(&str, Vec<&Measurement>, Plan)> = vec![];
    for test in &tests {
        let mine: Vec<&Measurement> = rows.iter().filter(|m| m.test == *test).collect();
        if mine.is_empty() {
            continue;
        }
        let mut runs = vec![];
        for m in &mine {
            for (g, z) in grid.iter().enumerate() {
                let first_seed = 1 + g.saturating_sub(grid.len() - 3) * args.seeds;
                for s in 0..args.seeds {
                    let mut values = cond_values(test, m, &args.data)?;
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
        let plan = Plan::generated(
            &format!("{test}-surface"),
            experiment_text(test, &model_path, args.coarse, &set),
            Path::new("."),
            run_factors(test, &params),
            runs,
        )
        .map_err(|e| not_taken(e, test, &params))?;
        plans.push((test, mine, plan));
    }
    let mut fits: Vec<MeasurementFit> = vec![];
    for (test, mine, plan) in plans {
        let values = run_and_read(
            &plan,
            &args.out.join(format!("surface-{test}")),
            args,
            &stop,
            observable,
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
            let fit = surface(&params, m, &pts, total)?;
            fits.push((m.clone(), fit, pts, total));
        }
    }
    let sigma: Vec<f64> = fits
        .iter()
        .map(|(m, fit, _, _)| {
            let s = fit.std_dev.unwrap_or(0.0);
            let u = m.uncertainty.unwrap_or(0.0);
            (s * s + u * u).sqrt().max(1e-6 * m.value.abs())
        })
        .collect();
    let residuals = |t: &[f64]| -> Vec<f64> {
        fits.iter()
            .zip(&sigma)
            .map(|((m, fit, _, _), s)| (fit.predict(t) - m.value) / s)
            .collect()
    };
    let sum_sq = |t: &[f64]| residuals(t).iter().map(|r| r * r).sum::<f64>();
    let low: Vec<f64> = params.iter().map(|p| p.low).collect();
    let high: Vec<f64> = params.iter().map(|p| p.high).collect();

    // 2. The shared setting on the surfaces.
    let mut setting = minimise_in_box(sum_sq, &low, &high);
    if !args.quiet {
        eprintln!(
            "joint least squares on {} surfaces: ({})",
            fits.len(),
            fmt(&setting)
        );
    }

    // 3. Direct runs at the shared setting, Gauss-Newton on the surfaces between them.
    let n_check = args.check_seeds.unwrap_or(args.seeds);
    let mut iterations: Vec<JointIteration> = vec![];
    let mut last_values: Vec<Vec<f64>> = vec![];
    for it in 0..=args.refine {
        let mut per_row: Vec<Vec<f64>> = vec![vec![]; fits.len()];
        for test in &tests {
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
                    for (p, v) in params.iter().zip(&setting) {
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
                experiment_text(test, &model_path, args.coarse, &set),
                Path::new("."),
                run_factors(test, &params),
                runs,
            )?;
            let dir = args.out.join(format!("check-{it}-{test}"));
            let values = run_and_read(&plan, &dir, args, &stop, observable)?;
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
        // Gauss-Newton on the surfaces' Jacobian with the direct runs' residuals.
        let jac: Vec<Vec<f64>> = fits
            .iter()
            .zip(&sigma)
            .map(|((_, fit, _, _), s)| {
                let z = fit.coding.code(&setting);
                fit.gradient_coded(&z)
                    .iter()
                    .enumerate()
                    .map(|(j, d)| d / fit.coding.half(j) / s)
                    .collect()
            })
            .collect();
        let r: Vec<f64> = fits
            .iter()
            .zip(&sigma)
            .zip(&means)
            .map(|(((m, ..), s), mean)| (mean - m.value) / s)
            .collect();
        let step = gauss_newton_step(&jac, &r);
        let worst = step
            .iter()
            .zip(&params)
            .map(|(d, p)| d.abs() / (0.25 * (p.high - p.low)))
            .fold(1.0, f64::max);
        let next: Vec<f64> = setting
            .iter()
            .zip(&step)
            .zip(&params)
            .map(|((x, d), p)| (x + d / worst).clamp(p.low, p.high))
            .collect();
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
    let setting = iterations
        .last()
        .expect("one iteration at least")
        .setting
        .clone();

    // 4. Uncertainty on the surfaces.
    let lin: Linearised = linearised(
        residuals,
        &setting,
        &params
            .iter()
            .map(|p| 1e-4 * (p.high - p.low))
            .collect::<Vec<_>>(),
    );
    let post: Posterior = smc(|t| -0.5 * sum_sq(t), &low, &high, 2000, 17);
    std::fs::create_dir_all(&args.out)?;
    calibrate_report::write_samples(&args.out.join("posterior.csv"), &params, &post)?;

    // 5. Outputs.
    let rows_out: Vec<JointRow> = fits
        .iter()
        .zip(&sigma)
        .zip(&last_values)
        .map(|(((m, fit, pts, total), s), values)| {
            let (mean, sd) = mean_sd(values);
            let error_pct = 100.0 * (mean - m.value) / m.value;
            JointRow {
                test: m.test.clone(),
                row: m.row,
                conditions: m.conditions.clone(),
                observable: m.observable.clone(),
                measured: m.value,
                sigma: *s,
                surface_runs: *total,
                surface_failed: total - pts.len(),
                r2: fit.r2,
                residual_sd: fit.std_dev,
                equation: fit.equation_real.clone(),
                surface_points: pts.clone(),
                predicted: fit.predict(&setting),
                simulated: values.clone(),
                simulated_mean: mean,
                simulated_sd: sd,
                error_pct,
                error_se_pct: sd
                    .map(|sd| 100.0 * sd / (values.len() as f64).sqrt() / m.value.abs()),
                within_tolerance: error_pct.abs() <= args.tolerance,
            }
        })
        .collect();
    let model_out = args.out.join("model.toml");
    let fixed = calibrate_report::shared_conditions(rows.iter().map(|m| &m.conditions));
    calibrate_report::write_constants(&model_path, &model_out, &params, &setting, &fixed)?;
    let start: Vec<Option<f64>> = params
        .iter()
        .map(|p| {
            let form = param_form(&model, p).expect("checked above");
            rows.first()
                .and_then(|m| evaluate_at(form, At::test(&m.conditions, &m.test)).ok())
        })
        .collect();
    let json = serde_json::json!({
        "joint": true,
        "tests": tests,
        "model": args.model,
        "coarse": args.coarse,
        "set": args.set.set,
        "seeds": args.seeds,
        "check_seeds": n_check,
        "tolerance_pct": args.tolerance,
        "params": params,
        "start": start,
        "calibrated": setting,
        "objective": sum_sq(&setting),
        "iterations": iterations,
        "rows": rows_out,
        "linearised": lin,
        "posterior": post,
        "calibrated_model": model_out,
        "shear_ucs": shear_ucs,
    });
    std::fs::write(
        args.out.join("calibration.json"),
        serde_json::to_string_pretty(&json)?,
    )?;
    let mut md = markdown(args, &params, &setting, &rows_out, &iterations, &lin, &post);
    if !allowed.is_empty() {
        md += &format!("\n## What the measurements allow\n\n{allowed}");
    }
    std::fs::write(args.out.join("calibration.md"), &md)?;
    write!(out, "{md}")?;
    Ok(())
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

fn fmt(x: &[f64]) -> String {
    x.iter()
        .map(|v| format!("{v:.4}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn markdown(
    args: &CalibrateArgs,
    params: &[Param],
    setting: &[f64],
    rows: &[JointRow],
    iterations: &[JointIteration],
    lin: &Linearised,
    post: &Posterior,
) -> String {
    let mut s = format!(
        "# Joint calibration of {} against {}\n\n{} free parameter(s) shared by all {} measurements: {}; \
         {} seeds per surface setting, {} per check; tolerance {} %{}.\n\n\
         Weighted least squares on one quadratic surface per measurement, each residual divided by \
         sigma = sqrt(surface residual sd^2 + measurement uncertainty^2).\n\n",
        args.test,
        args.data.display(),
        params.len(),
        rows.len(),
        params
            .iter()
            .map(|p| format!("{}.{} in [{}, {}]", p.pair, p.key, p.low, p.high))
            .collect::<Vec<_>>()
            .join(", "),
        args.seeds,
        args.check_seeds.unwrap_or(args.seeds),
        args.tolerance,
        if args.coarse { "; coarse preset" } else { "" }
    );
    s += &format!(
        "**Calibrated: {}** after {} round(s) of direct runs.\n\n",
        params
            .iter()
            .zip(setting)
            .map(|(p, v)| format!("{} = {v:.6}", p.name))
            .collect::<Vec<_>>()
            .join(", "),
        iterations.len()
    );
    s += "| test | conditions | measured | sigma | surface R^2 | predicted | simulated (mean +- sd) | error +- s.e. | within |\n|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {:.3} | {:.3} | {:.2} | {:.2} +- {} (n={}) | {:+.2} +- {} % | {} |\n",
            r.test,
            describe(&r.conditions),
            r.measured,
            r.sigma,
            r.r2,
            r.predicted,
            r.simulated_mean,
            r.simulated_sd.map_or("-".into(), |v| format!("{v:.2}")),
            r.simulated.len(),
            r.error_pct,
            r.error_se_pct.map_or("-".into(), |v| format!("{v:.2}")),
            if r.within_tolerance { "yes" } else { "NO" }
        );
    }
    s += "\n";
    for (k, it) in iterations.iter().enumerate() {
        s += &format!(
            "- round {k}: setting ({}), errors {} %\n",
            fmt(&it.setting),
            it.error_pct
                .iter()
                .map(|e| format!("{e:+.2}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    if lin.rank < params.len() {
        s += &format!(
            "- linearised: the measurements fix {} of {} parameter combinations; the parameters trade off along ({}) without changing the fit\n",
            lin.rank,
            params.len(),
            lin.null_directions
                .first()
                .map_or(String::new(), |d| fmt(d))
        );
    } else if let Some(ci) = &lin.ci95 {
        for (p, (a, b)) in params.iter().zip(ci) {
            s += &format!("- {}: linearised 95 % interval [{a:.6}, {b:.6}]\n", p.name);
        }
    }
    s += &format!(
        "- posterior (SMC, {} stages): {}\n",
        post.stages,
        calibrate_report::posterior_intervals(params, post)
    );
    s
}
