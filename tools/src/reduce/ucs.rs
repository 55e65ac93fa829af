//! Unconfined compressive strength (Li et al. 2022; docs/experiments.md,
//! "Unconfined compression"; the rule is that of ASTM D2166).
//!
//! A cylinder of initial diameter d is compressed without lateral support. As it shortens it
//! bulges, so the stress uses the corrected area (constant volume):
//!
//! ```text
//! A_0 = pi d^2 / 4,   A_c = A_0 / (1 - eps),   sigma = F / A_c = F (1 - eps) / A_0
//! ```
//!
//! with eps the axial strain (-) and F the axial force (N, positive in compression), paired
//! at equal log times from `/scalars/axial_strain` and `/scalars/axial_force`. Failure is
//! the peak of sigma within eps <= 15 %, or sigma at 15 % strain if sigma still rises there:
//!
//! - the largest sigma at strains up to the limit (sigma at exactly the limit interpolated
//!   linearly between the samples on either side when the curve goes past it) is found;
//! - if it lies before the last point of that range, failure is that peak ([`Failure::Peak`]);
//! - if it is the last point and the curve reached the limit, failure is sigma at the limit
//!   ([`Failure::StrainLimit`]);
//! - if it is the last point and the curve stopped short of the limit, the specimen had not
//!   failed when the record ends: the value is a lower bound ([`Failure::EndOfData`]).
//!
//! `ucs_kpa` = sigma at failure / 1000.

use super::error::ReduceError;
use super::read::{Run, RunSource};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// `tilth.experiment` type of an unconfined compression run.
pub const UCS: &str = "ucs";

/// The specimen, from `tilth.experiment`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct UcsSpecimen {
    pub diameter_m: f64,
    pub height_m: f64,
}

impl UcsSpecimen {
    /// Reads `diameter_m` and `height_m`.
    pub fn from_run(run: &Run) -> Result<UcsSpecimen, ReduceError> {
        Ok(UcsSpecimen {
            diameter_m: run.experiment_number("diameter_m")?,
            height_m: run.experiment_number("height_m")?,
        })
    }

    /// A_0 = pi d^2 / 4, m^2.
    pub fn initial_area_m2(&self) -> f64 {
        PI * self.diameter_m * self.diameter_m / 4.0
    }
}

/// How failure was decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Failure {
    /// sigma peaked before the strain limit.
    Peak,
    /// sigma still rose at the strain limit: failure is sigma there.
    StrainLimit,
    /// The record ends before either: the value is the last sigma, a lower bound.
    EndOfData,
}

/// How to decide failure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UcsOptions {
    /// Axial strain at which a still-rising test is stopped (0.15 in the study).
    pub strain_limit: f64,
}

impl Default for UcsOptions {
    fn default() -> Self {
        UcsOptions { strain_limit: 0.15 }
    }
}

/// The measurement, independent of the file it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UcsAnalysis {
    /// Unconfined compressive strength, kPa.
    pub ucs_kpa: f64,
    pub failure: Failure,
    /// Axial strain at failure, -.
    pub strain_at_failure: f64,
    /// Axial force at failure, N.
    pub force_at_failure_n: f64,
    /// Corrected area at failure A_0 / (1 - eps), m^2.
    pub corrected_area_at_failure_m2: f64,
    /// Largest axial force within the strain limit, N (may come after the stress peak,
    /// since the corrected area grows with strain).
    pub peak_force_n: f64,
    pub strain_at_peak_force: f64,
    /// After a [`Failure::Peak`], how far sigma then fell within the strain limit, as a
    /// fraction of the peak (0 for the other rules): a drop within the noise of the curve
    /// means the "peak" is not a clear failure.
    pub post_peak_drop: f64,
    pub strain_limit: f64,
    pub initial_area_m2: f64,
    pub specimen: UcsSpecimen,
    /// Largest inertial number over the curve (quasi-static below about 1e-3); `None`
    /// without `/scalars/inertial_number`.
    pub max_inertial_number: Option<f64>,
    /// The curve: (axial strain -, sigma kPa), every sample in time order.
    pub curve: Vec<(f64, f64)>,
}

/// An unconfined compression run's result (one flat JSON object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UcsResult {
    #[serde(flatten)]
    pub source: RunSource,
    #[serde(flatten)]
    pub analysis: UcsAnalysis,
}

/// Reduces an unconfined compression run (scalars only; read it with
/// [`super::CloudChoice::None`]).
pub fn ucs(run: &Run, options: &UcsOptions) -> Result<UcsResult, ReduceError> {
    run.expect_experiment(UCS)?;
    let specimen = UcsSpecimen::from_run(run)?;
    let curve = run
        .scalar("axial_strain")?
        .paired(run.scalar("axial_force")?);
    let inertial = run
        .scalar("inertial_number")
        .ok()
        .map(|s| s.value.as_slice());
    let analysis =
        analyse_ucs(&curve, inertial, &specimen, options).map_err(|e| e.in_file(&run.file))?;
    Ok(UcsResult {
        source: run.source(),
        analysis,
    })
}

/// Finds failure on `curve` ((axial strain, axial force N) in time order).
pub fn analyse_ucs(
    curve: &[(f64, f64)],
    inertial_number: Option<&[f64]>,
    specimen: &UcsSpecimen,
    options: &UcsOptions,
) -> Result<UcsAnalysis, ReduceError> {
    let a0 = specimen.initial_area_m2();
    if !a0.is_finite() || a0 <= 0.0 {
        return Err(ReduceError::Degenerate(format!(
            "unconfined compression: diameter {} m gives no area",
            specimen.diameter_m
        )));
    }
    let limit = options.strain_limit;
    if limit.is_nan() || limit <= 0.0 || limit >= 1.0 {
        return Err(ReduceError::Degenerate(format!(
            "unconfined compression: strain limit {limit} is not between 0 and 1"
        )));
    }
    if let Some(&(eps, _)) = curve.iter().find(|p| p.0.is_nan() || p.0 >= 1.0) {
        return Err(ReduceError::Degenerate(format!(
            "unconfined compression: axial strain {eps} leaves no corrected area"
        )));
    }
    let stress = |(eps, f): (f64, f64)| f * (1.0 - eps) / a0;

    // (strain, force) points within the limit, closed at the limit if the curve passes it.
    let mut window: Vec<(f64, f64)> = Vec::with_capacity(curve.len());
    let mut reached = false;
    for (k, &p) in curve.iter().enumerate() {
        if p.0 <= limit {
            window.push(p);
            reached |= p.0 == limit;
        } else {
            if let Some(&q) = k.checked_sub(1).map(|j| &curve[j]).filter(|q| q.0 < limit) {
                let t = (limit - q.0) / (p.0 - q.0);
                window.push((limit, q.1 + t * (p.1 - q.1)));
            }
            reached = true;
            break;
        }
    }
    if window.is_empty() {
        return Err(ReduceError::TooFewPoints {
            what: format!("unconfined compression: points at axial strain up to {limit}"),
            have: 0,
            need: 1,
        });
    }
    let sigma: Vec<f64> = window.iter().map(|&p| stress(p)).collect();
    let peak = (0..sigma.len())
        .reduce(|a, b| if sigma[b] > sigma[a] { b } else { a })
        .unwrap_or(0);
    let last = sigma.len() - 1;
    let failure = match (peak < last, reached) {
        (true, _) => Failure::Peak,
        (false, true) => Failure::StrainLimit,
        (false, false) => Failure::EndOfData,
    };
    let post_peak_drop = if failure == Failure::Peak && sigma[peak] > 0.0 {
        let lowest = sigma[peak..].iter().copied().fold(f64::INFINITY, f64::min);
        (sigma[peak] - lowest) / sigma[peak]
    } else {
        0.0
    };
    let (eps_f, force_f) = window[peak];
    let peak_force = (0..window.len())
        .reduce(|a, b| if window[b].1 > window[a].1 { b } else { a })
        .unwrap_or(0);
    Ok(UcsAnalysis {
        ucs_kpa: sigma[peak] / 1000.0,
        failure,
        strain_at_failure: eps_f,
        force_at_failure_n: force_f,
        corrected_area_at_failure_m2: a0 / (1.0 - eps_f),
        peak_force_n: window[peak_force].1,
        strain_at_peak_force: window[peak_force].0,
        post_peak_drop,
        strain_limit: limit,
        initial_area_m2: a0,
        specimen: *specimen,
        max_inertial_number: inertial_number.and_then(|v| v.iter().copied().reduce(f64::max)),
        curve: curve.iter().map(|&p| (p.0, stress(p) / 1000.0)).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// d = 61.8 mm: A_0 = pi 0.0618^2 / 4 = 2.999624e-3 m^2.
    fn specimen() -> UcsSpecimen {
        UcsSpecimen {
            diameter_m: 0.0618,
            height_m: 0.04,
        }
    }

    #[test]
    fn initial_area_by_hand() {
        assert!((specimen().initial_area_m2() - 2.999_624e-3).abs() < 1e-9);
    }

    #[test]
    fn stress_peak_before_the_force_peak() {
        // sigma = F (1 - eps) / A_0: at eps 0.10, F 200 -> 180 / A_0; at 0.12, F 203 ->
        // 178.64 / A_0. The force still rises but the stress has peaked at 0.10:
        // 180 N / 2.999624e-3 m^2 = 60.0075 kPa.
        let curve = [
            (0.0, 0.0),
            (0.05, 150.0),
            (0.10, 200.0),
            (0.12, 203.0),
            (0.14, 180.0),
        ];
        let a = analyse_ucs(&curve, None, &specimen(), &UcsOptions::default()).unwrap();
        assert_eq!(a.failure, Failure::Peak);
        assert!((a.strain_at_failure - 0.10).abs() < 1e-12);
        assert!(
            (a.ucs_kpa - 180.0 / 2.999_624e-3 / 1000.0).abs() < 1e-3,
            "{}",
            a.ucs_kpa
        );
        assert!((a.ucs_kpa - 60.0075).abs() < 1e-4);
        assert_eq!(a.peak_force_n, 203.0);
        assert!((a.corrected_area_at_failure_m2 - 2.999_624e-3 / 0.9).abs() < 1e-8);
        // Lowest sigma after the peak: 180 * 0.86 = 154.8 -> drop (180 - 154.8) / 180 = 0.14.
        assert!((a.post_peak_drop - 0.14).abs() < 1e-9);
    }

    #[test]
    fn still_rising_at_fifteen_percent() {
        // F = 1000 N * eps to eps = 0.20: sigma = 1000 eps (1 - eps) / A_0 rises up to
        // eps = 0.5, so failure is at 15 %: 1000 * 0.15 * 0.85 = 127.5 N / A_0 = 42.5053 kPa.
        let curve: Vec<(f64, f64)> = (0..=20)
            .map(|k| {
                let eps = k as f64 * 0.01;
                (eps, 1000.0 * eps)
            })
            .collect();
        let a = analyse_ucs(&curve, None, &specimen(), &UcsOptions::default()).unwrap();
        assert_eq!(a.failure, Failure::StrainLimit);
        assert!((a.strain_at_failure - 0.15).abs() < 1e-12);
        assert!((a.ucs_kpa - 42.5053).abs() < 1e-4, "{}", a.ucs_kpa);
        assert!((a.force_at_failure_n - 150.0).abs() < 1e-9);
    }

    #[test]
    fn stopped_while_rising_is_a_lower_bound() {
        let curve = [(0.0, 0.0), (0.02, 50.0), (0.04, 90.0)];
        let a = analyse_ucs(&curve, None, &specimen(), &UcsOptions::default()).unwrap();
        assert_eq!(a.failure, Failure::EndOfData);
        // 90 N * 0.96 / 2.999624e-3 m^2 = 28.8036 kPa.
        assert!((a.ucs_kpa - 28.8036).abs() < 1e-4);
    }
}
