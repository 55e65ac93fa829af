//! Mohr-Coulomb failure line through the peak shear stresses of direct shear runs at
//! several normal pressures (Li et al. 2022, table 2; docs/experiments.md).
//!
//! ```text
//! tau_f = c + sigma_n tan(phi)
//! ```
//!
//! tau_f (Pa) is each run's peak shear stress F_peak / A and sigma_n (Pa) its applied normal
//! pressure (`normal_pressure_pa` from metadata, the load the lab sets). A least-squares
//! line tau = a + b sigma gives the cohesion c = a (Pa) and the friction angle
//! phi = arctan(b) (degrees), with R^2 ([`super::line_fit`]). Two pressures give a line
//! but no check of it (R^2 = 1 always); the study used four.

use super::error::ReduceError;
use super::line_fit::fit_line;
use super::shear::ShearResult;
use serde::{Deserialize, Serialize};

/// One run on the Mohr-Coulomb plot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MohrPoint {
    pub file: String,
    pub complete: bool,
    /// Applied normal pressure, Pa.
    pub normal_stress_pa: f64,
    /// Peak shear stress, Pa.
    pub shear_strength_pa: f64,
}

/// The fitted line and the runs it went through.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MohrCoulombFit {
    /// c, Pa.
    pub cohesion_pa: f64,
    /// phi, degrees.
    pub friction_angle_deg: f64,
    pub r_squared: f64,
    /// True only if every run's file was complete.
    pub complete: bool,
    pub points: Vec<MohrPoint>,
}

/// Fits the line through the peaks of `runs` (at least two different normal pressures).
pub fn mohr_coulomb(runs: &[ShearResult]) -> Result<MohrCoulombFit, ReduceError> {
    let points: Vec<MohrPoint> = runs
        .iter()
        .map(|r| MohrPoint {
            file: r.source.file.clone(),
            complete: r.source.complete,
            normal_stress_pa: r.analysis.specimen.normal_pressure_pa,
            shear_strength_pa: r.analysis.peak_shear_stress_pa,
        })
        .collect();
    fit_mohr_coulomb(points)
}

/// Fits the line through `points` (at least two different normal stresses).
pub fn fit_mohr_coulomb(points: Vec<MohrPoint>) -> Result<MohrCoulombFit, ReduceError> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .map(|p| (p.normal_stress_pa, p.shear_strength_pa))
        .collect();
    let fit = fit_line(&xy, "Mohr-Coulomb fit over the runs' normal pressures")?;
    Ok(MohrCoulombFit {
        cohesion_pa: fit.intercept,
        friction_angle_deg: fit.slope.atan().to_degrees(),
        r_squared: fit.r_squared,
        complete: points.iter().all(|p| p.complete),
        points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(sigma: f64, tau: f64) -> MohrPoint {
        MohrPoint {
            file: format!("{sigma}.mcap"),
            complete: true,
            normal_stress_pa: sigma,
            shear_strength_pa: tau,
        }
    }

    #[test]
    fn three_pressures_on_an_exact_line() {
        // c = 12 kPa, phi = 31 deg: tau = 12e3 + sigma tan(31 deg) at 50, 100, 200 kPa.
        let (c, phi) = (12e3, 31f64.to_radians());
        let pts = [50e3, 100e3, 200e3]
            .iter()
            .map(|&s| point(s, c + s * phi.tan()))
            .collect();
        let f = fit_mohr_coulomb(pts).unwrap();
        assert!((f.cohesion_pa - 12e3).abs() < 1e-6, "{f:?}");
        assert!((f.friction_angle_deg - 31.0).abs() < 1e-9);
        assert!((f.r_squared - 1.0).abs() < 1e-12);
        assert!(f.complete);
    }

    #[test]
    fn one_pressure_is_refused() {
        let pts = vec![point(50e3, 40e3), point(50e3, 41e3)];
        assert!(matches!(
            fit_mohr_coulomb(pts),
            Err(ReduceError::Degenerate(_))
        ));
    }
}
