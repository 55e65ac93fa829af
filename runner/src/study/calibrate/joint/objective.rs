//! The joint calibration's objective: the weighted residuals of every measurement's
//! surface, and the Gauss-Newton step between rounds of direct runs.

use super::MeasurementFit;
use crate::study::calibrate::Param;
use tilth_tools::calibrate::gauss_newton_step;

/// The weighted least-squares objective on the surfaces: residuals
/// r_i(theta) = (f_i(theta) - y_i) / sigma_i, with sigma_i^2 = s_i^2 + u_i^2 (the surface's
/// residual sd, the measurement's uncertainty), floored at 1e-6 of the measurement.
pub(super) struct Objective {
    pub(super) fits: Vec<MeasurementFit>,
    pub(super) sigma: Vec<f64>,
}

impl Objective {
    /// The objective of `fits`, each sigma_i computed once.
    pub(super) fn new(fits: Vec<MeasurementFit>) -> Self {
        let sigma: Vec<f64> = fits
            .iter()
            .map(|(m, fit, _, _)| {
                let s = fit.std_dev.unwrap_or(0.0);
                let u = m.uncertainty.unwrap_or(0.0);
                (s * s + u * u).sqrt().max(1e-6 * m.value.abs())
            })
            .collect();
        Objective { fits, sigma }
    }

    /// r_i(t) for every measurement.
    pub(super) fn residuals(&self, t: &[f64]) -> Vec<f64> {
        self.fits
            .iter()
            .zip(&self.sigma)
            .map(|((m, fit, _, _), s)| (fit.predict(t) - m.value) / s)
            .collect()
    }

    /// sum_i r_i(t)^2, the objective minimised.
    pub(super) fn sum_sq(&self, t: &[f64]) -> f64 {
        self.residuals(t).iter().map(|r| r * r).sum::<f64>()
    }

    /// The next shared setting from `setting`, where the direct runs' means are `means`: a
    /// Gauss-Newton step on the surfaces' Jacobian J_ij = df_i/dtheta_j / sigma_i with the
    /// direct runs' residuals (mean_i - y_i) / sigma_i, shortened so that no parameter moves
    /// more than a quarter of its range, and kept inside the ranges.
    pub(super) fn gauss_newton_next(
        &self,
        setting: &[f64],
        means: &[f64],
        params: &[Param],
    ) -> Vec<f64> {
        let fits = &self.fits;
        let jac: Vec<Vec<f64>> = fits
            .iter()
            .zip(&self.sigma)
            .map(|((_, fit, _, _), s)| {
                let z = fit.coding.code(setting);
                fit.gradient_coded(&z)
                    .iter()
                    .enumerate()
                    .map(|(j, d)| d / fit.coding.half(j) / s)
                    .collect()
            })
            .collect();
        let r: Vec<f64> = fits
            .iter()
            .zip(&self.sigma)
            .zip(means)
            .map(|(((m, ..), s), mean)| (mean - m.value) / s)
            .collect();
        let step = gauss_newton_step(&jac, &r);
        let worst = step
            .iter()
            .zip(params)
            .map(|(d, p)| d.abs() / (0.25 * (p.high - p.low)))
            .fold(1.0, f64::max);
        setting
            .iter()
            .zip(&step)
            .zip(params)
            .map(|((x, d), p)| (x + d / worst).clamp(p.low, p.high))
            .collect()
    }
}
