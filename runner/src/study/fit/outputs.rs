//! What a fit leaves: the estimate's uncertainty, `DIR/model.toml` (the model with the
//! fitted parameters), `DIR/fit.json` and `DIR/fit.md`.

use super::jacobian_noise::covariance;
use super::levenberg_marquardt::{Best, Fitted};
use super::params::{apply, describe, show};
use super::rmse;
use super::simulations::{Problem, residuals};
use crate::lab::model::Model;
use anyhow::{Context, Result};
use nalgebra::DMatrix;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::io::Write;
use std::path::PathBuf;
use tilth_tools::compare::welch::normal_chi2;

/// The estimate's uncertainty, from the covariance (J'J - N)^-1 scale, with N the noise the
/// finite-difference Jacobian carries into J'J and scale = max(1, chi^2 / dof).
struct Uncertainty {
    /// Each parameter's standard error, sqrt of the covariance's diagonal; None where
    /// J'J - N is not positive definite.
    sd: Vec<Option<f64>>,
    /// The same from (J'J)^-1 scale: a lower bound, since it leaves the noise in J'J.
    sd_naive: Vec<Option<f64>>,
    /// The correlations, cov_ab / sqrt(cov_aa cov_bb).
    corr: Option<Vec<Vec<f64>>>,
}

/// The uncertainty of the fit's estimate; `dof` = rows - P (at least 1).
fn uncertainty(fitted: &Fitted, n: usize, dof: usize) -> Uncertainty {
    let best = &fitted.best;
    let scale = (best.chi2 / dof as f64).max(1.0);
    let cov = covariance(&best.jac, &best.noise, scale);
    let naive = covariance(&best.jac, &DMatrix::zeros(n, n), scale);
    let sd_of = |cov: &Option<DMatrix<f64>>| -> Vec<Option<f64>> {
        (0..n)
            .map(|k| cov.as_ref().map(|c| c[(k, k)].max(0.0).sqrt()))
            .collect()
    };
    let (sd, sd_naive) = (sd_of(&cov), sd_of(&naive));
    let corr: Option<Vec<Vec<f64>>> = cov.as_ref().map(|c| {
        (0..n)
            .map(|a| {
                (0..n)
                    .map(|b| c[(a, b)] / (c[(a, a)] * c[(b, b)]).sqrt())
                    .collect()
            })
            .collect()
    });
    Uncertainty { sd, sd_naive, corr }
}

/// Writes `DIR/model.toml`, `DIR/fit.json` and `DIR/fit.md`, and prints the report.
pub(super) fn write_outputs(
    p: &Problem,
    fitted: &Fitted,
    dof: usize,
    out: &mut dyn Write,
) -> Result<()> {
    let args = p.args;
    let unc = uncertainty(fitted, p.params.len(), dof);
    let model_out = write_model(p, &fitted.best.theta)?;
    let json = json(p, fitted, &unc, dof, &model_out);
    std::fs::write(args.out.join("fit.json"), serde_json::to_vec_pretty(&json)?)?;
    let md = report(p, fitted, &unc, dof, &model_out);
    std::fs::write(args.out.join("fit.md"), &md)?;
    out.write_all(md.as_bytes())?;
    writeln!(
        out,
        "\nwritten: {}/fit.{{json,md}}, model.toml",
        args.out.display()
    )?;
    Ok(())
}

/// Writes the fitted model, comments kept, to `DIR/model.toml` and checks that it loads;
/// returns its path.
fn write_model(p: &Problem, theta: &[f64]) -> Result<PathBuf> {
    let mut fitted: toml_edit::DocumentMut = p.text.parse()?;
    apply(&mut fitted, p.model, p.params, theta)?;
    let header = format!(
        "# Fitted by `tilth fit` to {} ({} rows): {}\n",
        p.args.data.display(),
        p.rows.len(),
        show(p.params, theta)
    );
    let model_out = p.args.out.join("model.toml");
    std::fs::write(&model_out, header + &fitted.to_string())?;
    Model::load(&model_out).context("the fitted model")?;
    Ok(model_out)
}

/// The misfit test at the estimate: sum of the rows' normal scores squared, and
/// P(chi^2_dof > it).
fn misfit(rows: &[crate::study::measurements::Measurement], best: &Best, dof: usize) -> (f64, f64) {
    let z = residuals(rows, &best.centre, &best.se);
    let x = normal_chi2(&z, &best.dof);
    let p = ChiSquared::new(dof.max(1) as f64).map_or(f64::NAN, |d| d.sf(x));
    (x, p)
}

/// `fit.json`: the estimate, its uncertainty and the history.
fn json(
    p: &Problem,
    fitted: &Fitted,
    unc: &Uncertainty,
    dof: usize,
    model_out: &std::path::Path,
) -> serde_json::Value {
    let (args, rows, n) = (p.args, p.rows, p.params.len());
    let best = &fitted.best;
    let noise = &best.noise;
    let first = &fitted.history[0];
    let misfit = misfit(rows, best, dof);
    serde_json::json!({
        "model": args.model.display().to_string(),
        "data": args.data.display().to_string(),
        "replicates": args.replicates,
        "coarse": args.lab.coarse,
        "set": args.lab.set.set,
        "parameters": p.params,
        "estimate": best.theta,
        "standard_error": unc.sd,
        "standard_error_uncorrected": unc.sd_naive,
        "jacobian_noise": (0..n).map(|j| (0..n).map(|k| noise[(j, k)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
        "correlation": unc.corr,
        "chi2": best.chi2,
        // Each row's (measured - simulated) / standard error at the estimate: chi2 is their
        // sum of squares (diagnose's refit compares fits row by row).
        "z": residuals(rows, &best.centre, &best.se),
        "dof": dof,
        // Each z's degrees of freedom (its standard error is estimated from the runs'
        // scatter and, for synthetic data, the truth's): the misfit test is on the normal
        // scores of the z, sum q^2 (`tilth_tools::compare::welch`).
        "z_dof": best.dof.iter().map(|d| d.is_finite().then_some(*d)).collect::<Vec<_>>(),
        "chi2_scores": misfit.0,
        "p_value": misfit.1,
        "rmse_start": first.rmse,
        "rmse": rmse(rows, &best.centre),
        "history": fitted.history,
        "stopped": fitted.stopped,
        "fitted_model": model_out.display().to_string(),
    })
}

/// `fit.md`: the estimates with their standard errors, chi^2 and each observable's RMSE at
/// the start and fitted.
fn report(
    p: &Problem,
    fitted: &Fitted,
    unc: &Uncertainty,
    dof: usize,
    model_out: &std::path::Path,
) -> String {
    let (args, rows, n) = (p.args, p.rows, p.params.len());
    let best = &fitted.best;
    let first = &fitted.history[0];
    let mut md = format!(
        "# Fit of {} to {}\n\n{} rows, {} replicates per setting, {} free parameter{}.\n\n| parameter | start | estimate | standard error | uncorrected (a lower bound) | range |\n|---|---|---|---|---|---|\n",
        args.model.display(),
        args.data.display(),
        rows.len(),
        args.replicates,
        n,
        if n == 1 { "" } else { "s" }
    );
    for (k, p) in p.params.iter().enumerate() {
        md += &format!(
            "| {} | {:.4} | {:.4} | {} | {} | [{:.4}, {:.4}] |\n",
            describe(p),
            p.start,
            best.theta[k],
            unc.sd[k].map_or("not determined".into(), |s| format!("{s:.4}")),
            unc.sd_naive[k].map_or("-".into(), |s| format!("{s:.4}")),
            p.low,
            p.high
        );
    }
    md += "\nThe standard errors take off J'J the noise the finite-difference Jacobian carries (the runs' chaos, measured from the per-seed slopes); the uncorrected ones, (J'J)^-1, understate the uncertainty.";
    if unc.sd.iter().any(Option::is_none) {
        md += " Not determined: once that noise is taken off, the runs do not show how the readings move with the parameters; more replicates (`--replicates`) would.";
    }
    md += "\n";
    let (scores, p_value) = misfit(rows, best, dof);
    md += &format!(
        "\nchi^2 {:.2} on {dof} degrees of freedom (start {:.2}); the misfit test, which allows for standard errors estimated from {} runs (the normal scores' sum of squares, {scores:.2}): p {}. {}\n\n| observable | RMSE at the start | RMSE fitted |\n|---|---|---|\n",
        best.chi2,
        first.chi2,
        args.replicates,
        tilth_tools::compare::p_text(p_value),
        fitted.stopped.say(args.iterations)
    );
    let end = rmse(rows, &best.centre);
    for (k, v) in &end {
        md += &format!("| {k} | {:.4} | {:.4} |\n", first.rmse[k], v);
    }
    md += &format!(
        "\nThe fitted model: `{}` (for `tilth compare`).\n",
        model_out.display()
    );
    md
}
