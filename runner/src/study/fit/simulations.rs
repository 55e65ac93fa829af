//! The model evaluated at a setting of the free parameters: a model file with them set,
//! every measured row simulated with it, and the rows' standardised residuals.

use super::FitArgs;
use super::params::{FreeParam, apply, show};
use crate::lab::model::Model;
use crate::study::lab_runs::{Simulate, TestSetting, simulate};
use crate::study::measurements::Measurement;
use crate::study::model_edit::variant;
use anyhow::{Result, bail};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use tilth_tools::compare::welch::residual_dof;
use tilth_tools::compare::{mean_sd, std_error};

/// What every setting of one fit shares: the command's arguments, the starting model, the
/// measured rows and the free parameters, and where the settings' files go.
pub(super) struct Problem<'a> {
    pub(super) args: &'a FitArgs,
    pub(super) model: &'a Model,
    /// The model file's text: each setting edits it, so that comments are kept.
    pub(super) text: &'a str,
    pub(super) rows: &'a [Measurement],
    pub(super) params: &'a [FreeParam],
    /// `--set`, parsed.
    pub(super) set: &'a [TestSetting],
    /// Raised by SIGINT or SIGTERM: the runs stop.
    pub(super) stop: &'a Arc<AtomicBool>,
    /// `DIR/runs`: a setting's runs go to `iter-K/<variant>/`.
    pub(super) runs: PathBuf,
    /// `DIR/models`: a setting's model file.
    pub(super) models: PathBuf,
}

/// The simulated rows at one setting.
pub(super) struct Sims {
    /// Each row's mean, None where a run failed.
    pub(super) mean: Vec<Option<f64>>,
    /// Each row's scatter (sample standard deviation).
    pub(super) scatter: Vec<Option<f64>>,
    /// Each row's values, seed by seed (seeds 1..R in order, all of them where `mean` is
    /// Some).
    pub(super) seeds: Vec<Vec<f64>>,
}

/// One setting with every row's runs done: what chi^2 and the Jacobian are made of.
pub(super) struct Evaluated {
    /// Each row's simulated mean.
    pub(super) centre: Vec<f64>,
    /// Each row's standard error, sqrt(uncertainty^2 + s^2 / R) with s the runs' scatter
    /// (1 where that is not positive, so that a row never divides by zero).
    pub(super) se: Vec<f64>,
    /// Each row's standardised residual, z = (measured - simulated) / se.
    pub(super) z: Vec<f64>,
    /// Each row's degrees of freedom of se^2 (Welch-Satterthwaite; infinite when exact).
    pub(super) dof: Vec<f64>,
    /// chi^2 = sum z^2.
    pub(super) chi2: f64,
    /// Each row's values, seed by seed (for the Jacobian's noise).
    pub(super) seeds: Vec<Vec<f64>>,
}

/// The runs of every row with the model file `model`, in `out`: replicates 1..R.
pub(super) fn at<'a>(
    model: &'a Path,
    out: &'a Path,
    args: &'a FitArgs,
    set: &'a [TestSetting],
) -> Simulate<'a> {
    Simulate {
        model,
        data: &args.data,
        out,
        replicates: args.replicates,
        first_seed: 1,
        lab: &args.lab,
        set,
    }
}

/// Each row's standardised residual, (measured - simulated) / standard error.
pub(super) fn residuals(rows: &[Measurement], centre: &[f64], se: &[f64]) -> Vec<f64> {
    rows.iter()
        .zip(centre)
        .zip(se)
        .map(|((m, c), s)| (m.value - c) / s)
        .collect()
}

impl Problem<'_> {
    /// The model file and the run directory of variant `name` of iteration `it` (at
    /// `theta`); writes the model file.
    pub(super) fn setting(
        &self,
        it: usize,
        name: &str,
        theta: &[f64],
    ) -> Result<(PathBuf, PathBuf)> {
        let label = format!("iter-{it}-{name}");
        let path = variant(self.model, self.text, &self.models, &label, |d| {
            apply(d, self.model, self.params, theta)
        })?;
        Ok((path, self.runs.join(format!("iter-{it}")).join(name)))
    }

    /// Simulates every row with the model file `path`, into `out`.
    pub(super) fn run_at(&self, path: &Path, out: &Path) -> Result<Sims> {
        let args = self.args;
        let sims = simulate(self.rows, &at(path, out, args, self.set), self.stop)?;
        let (mean, scatter) = sims
            .iter()
            .map(|(v, _)| {
                if v.len() == args.replicates {
                    let (m, s) = mean_sd(v);
                    (Some(m), s)
                } else {
                    (None, None)
                }
            })
            .unzip();
        Ok(Sims {
            mean,
            scatter,
            seeds: sims.into_iter().map(|(v, _)| v).collect(),
        })
    }

    /// Simulates every row at `theta`, as variant `name` of iteration `it`.
    fn run(&self, it: usize, name: &str, theta: &[f64]) -> Result<Sims> {
        let (path, out) = self.setting(it, name, theta)?;
        self.run_at(&path, &out)
    }

    /// The setting `theta` of iteration `it` (its "centre", which the Jacobian's settings
    /// move from): every row simulated, its standard error and standardised residual, and
    /// chi^2. Refused when any row's runs failed, since chi^2 would then leave that row out.
    pub(super) fn evaluate(&self, it: usize, theta: &[f64]) -> Result<Evaluated> {
        let rows = self.rows;
        let Sims {
            mean: centre,
            scatter,
            seeds,
        } = self.run(it, "centre", theta)?;
        let failed: Vec<String> = rows
            .iter()
            .zip(&centre)
            .filter(|(_, c)| c.is_none())
            .map(|(m, _)| format!("row {}", m.row))
            .collect();
        if !failed.is_empty() {
            bail!(
                "iteration {it} ({}): runs failed at {}; see {}",
                show(self.params, theta),
                failed.join(", "),
                self.runs.join(format!("iter-{it}")).display()
            );
        }
        let centre: Vec<f64> = centre.into_iter().map(Option::unwrap).collect();
        let se: Vec<f64> = rows
            .iter()
            .zip(&scatter)
            .map(|(m, s)| {
                std_error(*s, self.args.replicates, m.uncertainty)
                    .filter(|e| *e > 0.0)
                    .unwrap_or(1.0)
            })
            .collect();
        let dof: Vec<f64> = rows
            .iter()
            .zip(&scatter)
            .map(|(m, s)| residual_dof(*s, self.args.replicates, m.uncertainty, m.uncertainty_dof))
            .collect();
        let z = residuals(rows, &centre, &se);
        let chi2: f64 = z.iter().map(|v| v * v).sum();
        Ok(Evaluated {
            centre,
            se,
            z,
            dof,
            chi2,
            seeds,
        })
    }
}
