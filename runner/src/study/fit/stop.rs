//! When `tilth fit` stops stepping.
//!
//! At an accepted setting with standardised residuals z (rows) and Jacobian J (rows x P,
//! standardised the same way), the Gauss-Newton step d = (J'J)^-1 J'z is predicted to lower
//! chi^2 = z'z by
//!
//!   g = z'J (J'J)^-1 J'z,
//!
//! the score (Lagrange-multiplier) statistic of "the parameters are already at the
//! minimum". If they are, and the rows' errors are the standard errors they are scaled by,
//! g follows chi^2 with P degrees of freedom (Rao 1948; Seber & Wild, Nonlinear Regression,
//! 1989, sec. 5.9).
//!
//! The fit stops at the noise when nothing is left to gain by either measure: chi^2 is at
//! most its degrees of freedom (the residuals as a whole are the size of the noise:
//! Morozov's discrepancy principle, the stopping rule of Hanke's regularizing
//! Levenberg-Marquardt, Inverse Problems 13 (1997) 79-95) **and** g is under chi^2_P's 95 %
//! quantile (no direction the parameters can move is worth a step). A further step then
//! follows the runs' scatter, and it costs 1 + P settings of DEM runs.
//!
//! Each test alone stops too soon (docs/discovery-proof.md, "The stop rule and the seeds"):
//! - chi^2 <= dof alone tests the whole residual vector, so a
//!   miss all rows share along one parameter can hide among the rows' noise: 30 rows each
//!   0.9 standard errors off give chi^2 = 24.3 on 29 degrees of freedom, and a step would
//!   remove all of it (a test below). On the seven-level plastic-adhesion study it stopped
//!   with g = 6.5.
//! - g alone stopped the CI proof's wall-adhesion fit at chi^2 29.3 on 14 degrees of
//!   freedom, with a step predicted to gain 4.7 of it.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// The quantile of chi^2_P under which a predicted gain is within the noise.
pub const LEVEL: f64 = 0.95;

/// The chi^2 the Gauss-Newton step from here is predicted to remove, g = z'J (J'J)^-1 J'z;
/// None when J'J is singular (a parameter moves no reading).
pub fn predicted_gain(jac: &DMatrix<f64>, z: &[f64]) -> Option<f64> {
    let jtz = jac.transpose() * DVector::from_column_slice(z);
    let d = (jac.transpose() * jac).cholesky()?.solve(&jtz);
    Some(jtz.dot(&d))
}

/// The gain a setting at the minimum would show in 95 % of draws: chi^2_P's quantile.
pub fn noise_gain(parameters: usize) -> f64 {
    ChiSquared::new(parameters.max(1) as f64)
        .expect("positive degrees of freedom")
        .inverse_cdf(LEVEL)
}

/// At the noise: chi^2 <= dof and the next step's predicted gain under chi^2_P's 95 %
/// quantile (a singular J'J, no gain to predict, counts as under it).
pub fn at_noise(chi2: f64, dof: usize, gain: Option<f64>, parameters: usize) -> bool {
    chi2 <= dof as f64 && gain.is_none_or(|g| g < noise_gain(parameters))
}

/// Why the fit ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Stop {
    /// chi^2 <= dof and the step's predicted chi^2 gain under chi^2_P's 95 % quantile.
    AtNoise,
    /// Every step under 1 % of its range.
    Converged,
    /// `--iterations` used up.
    Iterations,
}

impl Stop {
    pub fn say(self, iterations: usize) -> String {
        match self {
            Stop::AtNoise => "Stopped at the noise: chi^2 is at most its degrees of freedom and the next step's predicted chi^2 gain is under the 95 % quantile of chi^2 with one degree of freedom per parameter, so a step would follow the runs' scatter; `--to-minimum` steps on.".into(),
            Stop::Converged => "Converged: every step under 1 % of its range.".into(),
            Stop::Iterations => format!("Stopped after --iterations {iterations}."),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One parameter that shifts every row alike: the gain is (sum z)^2 / n, from the
    /// formula with J a column of ones.
    #[test]
    fn a_common_shift_gives_the_squared_sum_over_the_rows() {
        let z = [0.9, 1.1, 0.7, 1.3];
        let jac = DMatrix::from_element(4, 1, 1.0);
        let g = predicted_gain(&jac, &z).unwrap();
        assert!((g - 4.0f64.powi(2) / 4.0).abs() < 1e-12, "{g}");
    }

    /// A miss of 0.9 standard errors on each of 30 rows, all one sign: chi^2 = 24.3 is under
    /// its 29 degrees of freedom (the old rule would stop), but the step would remove all of
    /// it, far above chi^2_1's 95 % quantile (3.84).
    #[test]
    fn a_one_signed_miss_within_the_dof_is_not_at_the_noise() {
        let z = vec![0.9; 30];
        let chi2: f64 = z.iter().map(|v| v * v).sum();
        assert!(chi2 <= 29.0);
        let jac = DMatrix::from_element(30, 1, -2.0);
        let g = predicted_gain(&jac, &z).unwrap();
        assert!((g - chi2).abs() < 1e-9, "{g} against {chi2}");
        assert!(g > noise_gain(1));
    }

    /// Residuals with no component along J: nothing to gain.
    #[test]
    fn residuals_orthogonal_to_the_jacobian_are_at_the_noise() {
        let z = [1.5, -1.5, 2.0, -2.0];
        let jac = DMatrix::from_column_slice(4, 1, &[1.0, 1.0, 1.0, 1.0]);
        let g = predicted_gain(&jac, &z).unwrap();
        assert!(g.abs() < 1e-12, "{g}");
        assert!(g < noise_gain(1));
    }

    #[test]
    fn the_noise_gain_is_the_chi2_quantile() {
        // Tabulated 95 % quantiles of chi^2 with 1 and 2 degrees of freedom.
        assert!((noise_gain(1) - 3.841).abs() < 1e-3);
        assert!((noise_gain(2) - 5.991).abs() < 1e-3);
    }

    /// Both tests must pass: the CI proof's wall-adhesion fit (chi^2 29.3 on 14, g 4.7)
    /// and the seven-level plastic-adhesion fit (chi^2 24.1 on 26, g 6.5) step on; the
    /// seven-level fine-fraction fit (chi^2 24.6 on 26, g 2.0) stops.
    #[test]
    fn at_the_noise_needs_both_the_chi2_and_the_gain_at_the_noise() {
        assert!(!at_noise(29.3, 14, Some(4.7), 2));
        assert!(!at_noise(24.1, 26, Some(6.5), 2));
        assert!(at_noise(24.6, 26, Some(2.0), 2));
        assert!(at_noise(10.0, 14, None, 1));
        assert!(!at_noise(15.0, 14, None, 1));
    }

    #[test]
    fn a_parameter_that_moves_nothing_has_no_gain() {
        let jac = DMatrix::from_element(3, 1, 0.0);
        assert_eq!(predicted_gain(&jac, &[1.0, 2.0, 3.0]), None);
    }
}
