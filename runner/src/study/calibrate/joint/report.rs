//! The joint calibration's outputs: each measurement's row, the calibrated model,
//! `calibration.json` and `calibration.md`.

use super::objective::Objective;
use super::{Joint, JointIteration, JointRow, fmt};
use crate::lab::model::{At, evaluate_at};
use crate::study::calibrate::report as calibrate_report;
use crate::study::calibrate::{CalibrateArgs, Param, describe, param_form, params_text};
use anyhow::Result;
use std::io::Write;
use tilth_tools::calibrate::{Linearised, Posterior};
use tilth_tools::compare::mean_sd;

impl Joint<'_> {
    /// Writes `DIR/model.toml` (each parameter its one calibrated value), `calibration.json`
    /// and `calibration.md`, and prints the latter to `out`.
    pub(super) fn write_outputs(&self, fitted: &Fitted, out: &mut dyn Write) -> Result<()> {
        let (args, params) = (self.args, &self.params);
        let setting = fitted.setting;
        let model_out = args.out.join("model.toml");
        let fixed = calibrate_report::shared_conditions(self.rows.iter().map(|m| &m.conditions));
        calibrate_report::write_constants(&self.model_path, &model_out, params, setting, &fixed)?;
        let start: Vec<Option<f64>> = params
            .iter()
            .map(|p| {
                let form = param_form(&self.model, p).expect("checked above");
                self.rows
                    .first()
                    .and_then(|m| evaluate_at(form, At::test(&m.conditions, &m.test)).ok())
            })
            .collect();
        let json = serde_json::json!({
            "joint": true,
            "tests": self.tests,
            "model": args.model,
            "coarse": args.coarse,
            "set": args.set.set,
            "seeds": args.seeds,
            "check_seeds": args.check_seeds.unwrap_or(args.seeds),
            "tolerance_pct": args.tolerance,
            "params": params,
            "start": start,
            "calibrated": setting,
            "objective": fitted.objective.sum_sq(setting),
            "iterations": fitted.iterations,
            "rows": fitted.rows,
            "linearised": fitted.lin,
            "posterior": fitted.post,
            "calibrated_model": model_out,
            "shear_ucs": self.shear_ucs,
        });
        std::fs::write(
            args.out.join("calibration.json"),
            serde_json::to_string_pretty(&json)?,
        )?;
        let mut md = markdown(args, params, fitted);
        if !self.allowed.is_empty() {
            md += &format!("\n## What the measurements allow\n\n{}", self.allowed);
        }
        std::fs::write(args.out.join("calibration.md"), &md)?;
        write!(out, "{md}")?;
        Ok(())
    }
}

/// The joint calibration's result, as the outputs show it.
pub(super) struct Fitted<'f> {
    pub(super) objective: &'f Objective,
    pub(super) setting: &'f [f64],
    pub(super) rows: &'f [JointRow],
    pub(super) iterations: &'f [JointIteration],
    pub(super) lin: &'f Linearised,
    pub(super) post: &'f Posterior,
}

/// Each measurement's row of the report: its surface, the surface at `setting`, and the
/// last round's direct runs (`last_values`) against the measurement.
pub(super) fn rows_out(
    objective: &Objective,
    last_values: &[Vec<f64>],
    setting: &[f64],
    args: &CalibrateArgs,
) -> Vec<JointRow> {
    objective
        .fits
        .iter()
        .zip(&objective.sigma)
        .zip(last_values)
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
                predicted: fit.predict(setting),
                simulated: values.clone(),
                simulated_mean: mean,
                simulated_sd: sd,
                error_pct,
                error_se_pct: sd
                    .map(|sd| 100.0 * sd / (values.len() as f64).sqrt() / m.value.abs()),
                within_tolerance: error_pct.abs() <= args.tolerance,
            }
        })
        .collect()
}

/// `calibration.md`: the setup, the calibrated values, each measurement's fit, the rounds
/// and the parameters' uncertainty.
fn markdown(args: &CalibrateArgs, params: &[Param], fitted: &Fitted) -> String {
    let (setting, rows, iterations) = (fitted.setting, fitted.rows, fitted.iterations);
    let (lin, post) = (fitted.lin, fitted.post);
    let mut s = format!(
        "# Joint calibration of {} against {}\n\n{} free parameter(s) shared by all {} measurements: {}; \
         {} seeds per surface setting, {} per check; tolerance {} %{}.\n\n\
         Weighted least squares on one quadratic surface per measurement, each residual divided by \
         sigma = sqrt(surface residual sd^2 + measurement uncertainty^2).\n\n",
        args.test,
        args.data.display(),
        params.len(),
        rows.len(),
        params_text(params),
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
