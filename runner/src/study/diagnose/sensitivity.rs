//! The residuals and the finite-difference sensitivities, standardised by each row's
//! standard error, and the noise of the sensitivities from the seeds.

use super::runs::{Simulations, Variant};
use crate::study::measurements::Measurement;
use nalgebra::DMatrix;
use tilth_tools::compare::mean_sd;
use tilth_tools::compare::welch::welch_dof;
use tilth_tools::diagnose::{Candidate, JacobianNoise};

/// Finite differences of the variants against "base-fd" (variant 1), paired by seed, over
/// the used rows (index in the rows, standard error `se`).
pub(super) struct Differences<'a> {
    pub variants: &'a [Variant],
    pub sims: &'a Simulations,
    pub used: &'a [(usize, f64)],
}

impl Differences<'_> {
    /// Variant `v`'s standardised sensitivity per used row, from the row means:
    /// (mean_v - mean_base-fd) / h / se, h the variant's step.
    pub fn sensitivity(&self, v: usize) -> Vec<f64> {
        let h = self.variants[v].step;
        let means = &self.sims.means;
        self.used
            .iter()
            .map(|&(i, s)| (means[v][i].unwrap() - means[1][i].unwrap()) / h / s)
            .collect()
    }

    /// Variant `v`'s standardised slopes per used row, seed by seed:
    /// (value_v,r - value_base-fd,r) / h / se. Their scatter is the noise of the finite
    /// difference.
    pub fn seed_slopes(&self, v: usize) -> Vec<Vec<f64>> {
        let h = self.variants[v].step;
        let values = &self.sims.values;
        self.used
            .iter()
            .map(|&(i, s)| {
                (values[v][i].iter().zip(&values[1][i]))
                    .map(|(a, b)| (a - b) / h / s)
                    .collect()
            })
            .collect()
    }

    /// The variance of each used row's mean difference: sd^2 / n of its seed slopes (0
    /// without a scatter).
    pub fn variance(&self, v: usize) -> Vec<f64> {
        self.seed_slopes(v)
            .iter()
            .map(|d| mean_sd(d).1.map_or(0.0, |sd| sd * sd / d.len() as f64))
            .collect()
    }
}

/// What the score tests take, in standard errors over the used rows.
pub(super) struct Standardised {
    /// (measured - simulated in "base") / se.
    pub residual: Vec<f64>,
    /// The degrees of freedom of each se^2 (Welch-Satterthwaite: the runs' pooled scatter
    /// and the measurement's `uncertainty_dof`; infinite when exact).
    pub residual_dof: Vec<f64>,
    /// The free parameters' Jacobian, a column per free parameter.
    pub x: DMatrix<f64>,
    /// The free parameters' slopes' covariances, and the candidates' with them.
    pub noise: JacobianNoise,
    /// The candidates' (then the probes') sensitivities and their variances.
    pub candidates: Vec<Candidate>,
}

/// The residuals, the free parameters' Jacobian and the candidates' columns. The variants
/// are base, base-fd, then `n_params` free parameters, then one per name of `names`.
pub(super) fn standardise(
    rows: &[Measurement],
    fd: &Differences,
    n_params: usize,
    names: &[String],
) -> Standardised {
    let means = &fd.sims.means;
    let residual: Vec<f64> = fd
        .used
        .iter()
        .map(|&(i, s)| (rows[i].value - means[0][i].unwrap()) / s)
        .collect();
    let residual_dof: Vec<f64> = fd
        .used
        .iter()
        .map(|&(i, _)| {
            let m = &rows[i];
            let runs = fd.sims.values[0][i].len() as f64;
            welch_dof(&[
                fd.sims.scatter[i].map_or((0.0, 0.0), |(s, dof)| (s * s / runs, dof)),
                (
                    m.uncertainty.map_or(0.0, |u| u * u),
                    m.uncertainty_dof.unwrap_or(f64::INFINITY),
                ),
            ])
        })
        .collect();
    let noise = JacobianNoise::from_seeds(
        &(0..n_params)
            .map(|c| fd.seed_slopes(2 + c))
            .collect::<Vec<_>>(),
        &(0..names.len())
            .map(|k| fd.seed_slopes(2 + n_params + k))
            .collect::<Vec<_>>(),
    );
    // Column by column (each sensitivity once, not once per element).
    let columns: Vec<f64> = (0..n_params).flat_map(|c| fd.sensitivity(2 + c)).collect();
    let x = DMatrix::from_column_slice(fd.used.len(), n_params, &columns);
    let candidates: Vec<Candidate> = names
        .iter()
        .enumerate()
        .map(|(k, n)| Candidate {
            name: n.clone(),
            sensitivity: fd.sensitivity(2 + n_params + k),
            sensitivity_var: fd.variance(2 + n_params + k),
        })
        .collect();
    Standardised {
        residual,
        residual_dof,
        x,
        noise,
        candidates,
    }
}
