//! Steps 4 and 5 of a per-condition calibration: each condition's uncertainty and plots,
//! then the calibrated model, `calibration.json` and `calibration.md`.

use super::surface::Solved;
use super::{ConditionResult, Iteration, Param, Setup, describe};
use crate::study::calibrate::report as calibrate_report;
use anyhow::Result;
use std::io::Write;
use tilth_tools::calibrate::{Linearised, Posterior, linearised, smc};
use tilth_tools::rsm::Anova;
use tilth_tools::rsm::plot::CheckRuns;

/// Condition `c`'s result: its uncertainty at the last check's setting, its files
/// (posterior samples, curve, contour) and what the report shows of it.
pub(super) fn condition_result(
    setup: &Setup,
    c: usize,
    cond: Solved,
    iterations: Vec<Iteration>,
) -> Result<ConditionResult> {
    let (args, params) = (setup.args, &setup.params);
    let Solved {
        m,
        conds,
        fit,
        solution,
        start,
        failed,
        total,
        ..
    } = cond;
    let last = iterations.last().cloned().expect("at least one iteration");
    let se_pct = last
        .sd
        .map(|sd| 100.0 * sd / (last.values.len() as f64).sqrt() / m.value.abs());
    let (lin, post) = uncertainty(&fit, m.value, &last.setting, params, c);
    std::fs::create_dir_all(&args.out)?;
    // Per-condition files: posterior-SLUG.csv, curve-SLUG.svg, contour-SLUG.svg.
    let slug = crate::study::rsm::plot::slug(&describe(&conds));
    let file = |kind: &str, ext: &str| args.out.join(format!("{kind}-{slug}.{ext}"));
    calibrate_report::write_samples(&file("posterior", "csv"), params, &post)?;
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
    let curve = if params.len() == 1 {
        tilth_tools::rsm::plot::response_curve_checked_svg(
            &fit,
            std::slice::from_ref(&solution),
            &[],
            &check_runs(&iterations),
        )?
    } else {
        None
    };
    if let Some(svg) = curve {
        std::fs::write(file("curve", "svg"), svg)?;
    }
    if let Some(svg) = tilth_tools::rsm::plot::contour_marked_svg(&fit, &solution, &[], &marks)? {
        std::fs::write(file("contour", "svg"), svg)?;
    }
    Ok(ConditionResult {
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
        iterations,
        linearised: lin,
        posterior: post,
    })
}

/// Linearised intervals at `setting` and a posterior sample (SMC, seed 17 + c) on the
/// surface, the likelihood exp(-((f(theta) - measured) / sigma)^2 / 2) with sigma the
/// surface's residual standard deviation (floored at 1e-9 of the measurement).
fn uncertainty(
    fit: &Anova,
    measured: f64,
    setting: &[f64],
    params: &[Param],
    c: usize,
) -> (Linearised, Posterior) {
    // The measurement's own uncertainty does not enter a per-condition fit.
    let meas_sd = 0.0;
    let sigma = (fit.std_dev.unwrap_or(0.0).powi(2) + meas_sd)
        .sqrt()
        .max(1e-9 * measured.abs());
    let lin = linearised(
        |t| vec![(fit.predict(t) - measured) / sigma],
        setting,
        &params
            .iter()
            .map(|p| 1e-4 * (p.high - p.low))
            .collect::<Vec<_>>(),
    );
    let low: Vec<f64> = params.iter().map(|p| p.low).collect();
    let high: Vec<f64> = params.iter().map(|p| p.high).collect();
    let post = smc(
        |t| -0.5 * ((fit.predict(t) - measured) / sigma).powi(2),
        &low,
        &high,
        2000,
        17 + c as u64,
    );
    (lin, post)
}

/// Every direct check of a condition for its one-parameter plot (Design-Expert's one-factor
/// plot, with the checks that decided).
fn check_runs(iterations: &[Iteration]) -> Vec<CheckRuns> {
    iterations
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
        .collect()
}

/// Writes `DIR/model.toml` (the calibrated values as tables over the condition),
/// `calibration.json` and `calibration.md`, and prints the latter to `out`.
pub(super) fn write_outputs(
    setup: &Setup,
    results_out: &[ConditionResult],
    out: &mut dyn Write,
) -> Result<()> {
    let (args, params) = (setup.args, &setup.params);
    let model_out = args.out.join("model.toml");
    let test = args.per_test.then_some(args.test.as_str());
    calibrate_report::write_model(&setup.model_path, &model_out, params, results_out, test)?;
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
    let md = calibrate_report::markdown(args, params, results_out);
    std::fs::write(args.out.join("calibration.md"), &md)?;
    write!(out, "{md}")?;
    Ok(())
}
