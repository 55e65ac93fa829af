//! The fit of the free parameters before a diagnosis (the restricted estimate of the score
//! test), and what it moved.

use super::DiagnoseArgs;
use crate::study::measurements::Measurement;
use anyhow::Result;
use serde::Serialize;
use std::path::PathBuf;

/// Fits the free parameters to the rows with `tilth fit` into `DIR/fit/` and returns the
/// fitted model's path; None without free parameters or without `--fit-first`.
pub(super) fn fit_first(args: &DiagnoseArgs, rows: &[Measurement]) -> Result<Option<PathBuf>> {
    if args.params.is_empty() || !args.fit_first {
        return Ok(None);
    }
    let dir = args.out.join("fit");
    std::fs::create_dir_all(&dir)?;
    let data = data_for(args, rows, &dir)?;
    if !args.lab.quiet {
        eprintln!(
            "fitting the free parameters to the data first: {}",
            dir.display()
        );
    }
    let fit = crate::study::fit::FitArgs {
        model: args.model.clone(),
        data,
        params: args.params.clone(),
        from_diagnosis: None,
        replicates: args.replicates,
        iterations: args.fit_iterations,
        to_minimum: false,
        out: dir.clone(),
        lab: args.lab.clone(),
    };
    crate::study::fit::fit(&fit)?;
    Ok(Some(std::path::absolute(dir.join("model.toml"))?))
}

/// The data a fit inside the diagnosis reads: the data file, or with `--tests` its rows of
/// those tests written into `dir`.
pub(super) fn data_for(
    args: &DiagnoseArgs,
    rows: &[Measurement],
    dir: &std::path::Path,
) -> Result<PathBuf> {
    if args.tests.is_empty() {
        return Ok(args.data.clone());
    }
    let only = dir.join("data.csv");
    crate::study::measurements::write_measurements(&only, rows)?;
    Ok(only)
}

/// What the fit before the diagnosis moved: each free parameter's shift from the model's
/// value with its standard error, and chi^2 before and after.
#[derive(Debug, Clone, Serialize)]
pub struct FitFirst {
    pub parameters: Vec<String>,
    pub shift: Vec<f64>,
    pub standard_error: Vec<Option<f64>>,
    pub chi2_start: f64,
    pub chi2: f64,
    pub dof: f64,
}

pub(super) fn fit_summary(dir: &std::path::Path) -> Result<FitFirst> {
    let path = dir.join("fit/fit.json");
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&path)?)?;
    let nums = |v: &serde_json::Value| -> Vec<Option<f64>> {
        v.as_array()
            .map(|a| a.iter().map(serde_json::Value::as_f64).collect())
            .unwrap_or_default()
    };
    Ok(FitFirst {
        parameters: (j["parameters"].as_array().into_iter().flatten())
            .map(|p| p["label"].as_str().unwrap_or_default().to_string())
            .collect(),
        shift: nums(&j["estimate"])
            .into_iter()
            .map(|x| x.unwrap_or(0.0))
            .collect(),
        standard_error: nums(&j["standard_error"]),
        chi2_start: j["history"][0]["chi2"].as_f64().unwrap_or(f64::NAN),
        chi2: j["chi2"].as_f64().unwrap_or(f64::NAN),
        dof: j["dof"].as_f64().unwrap_or(f64::NAN),
    })
}
