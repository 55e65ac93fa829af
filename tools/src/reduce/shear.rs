//! Peak shear force of a direct shear run (Li et al. 2022; docs/experiments.md,
//! "Direct shear").
//!
//! The lower box is fixed and the upper box is pulled; `/scalars/shear_force` is the force of
//! the particles on the lower box along the shear direction (N, positive) and
//! `/scalars/shear_displacement` the upper box's travel (m). Pairing the two at equal log
//! times gives the force-displacement curve F(s). The study keeps the peak:
//!
//! ```text
//! F_peak = max_i F(s_i),   tau_peak = F_peak / A   (A = specimen area, m^2, from metadata)
//! ```
//!
//! The study's apparatus reads the force only every 0.8 mm of travel; the peak of those
//! readings (F linearly interpolated at s = 0.8, 1.6, ... mm) is reported beside the peak of
//! the full curve, because a force that peaks between two readings is under-read in the lab.
//! `tau_peak` against the applied normal pressure of several runs gives the Mohr-Coulomb
//! line ([`super::mohr_coulomb`]).

use super::error::ReduceError;
use super::read::{Run, RunSource};
use serde::{Deserialize, Serialize};

/// `tilth.experiment` type of a direct shear run.
pub const DIRECT_SHEAR: &str = "direct_shear";

/// The specimen and the applied load, from `tilth.experiment`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShearSpecimen {
    pub diameter_m: f64,
    /// Shear plane area, m^2 (3000 mm^2 in the study).
    pub area_m2: f64,
    /// Applied normal pressure, Pa.
    pub normal_pressure_pa: f64,
}

impl ShearSpecimen {
    /// Reads `diameter_m`, `area_m2` and `normal_pressure_pa`.
    pub fn from_run(run: &Run) -> Result<ShearSpecimen, ReduceError> {
        Ok(ShearSpecimen {
            diameter_m: run.experiment_number("diameter_m")?,
            area_m2: run.experiment_number("area_m2")?,
            normal_pressure_pa: run.experiment_number("normal_pressure_pa")?,
        })
    }
}

/// How to read the curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShearOptions {
    /// Travel between two readings of the lab apparatus, m (0.8 mm in the study).
    pub reading_interval_m: f64,
    /// Only points with displacement up to this are used (the study stops at 5 mm);
    /// `None`: the whole curve.
    pub max_displacement_m: Option<f64>,
}

impl Default for ShearOptions {
    fn default() -> Self {
        ShearOptions {
            reading_interval_m: 0.8e-3,
            max_displacement_m: None,
        }
    }
}

/// The measurement, independent of the file it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShearAnalysis {
    /// Largest shear force on the curve, N.
    pub peak_shear_force_n: f64,
    /// Shear displacement where it occurs, m.
    pub displacement_at_peak_m: f64,
    /// Peak shear stress F_peak / A, Pa.
    pub peak_shear_stress_pa: f64,
    /// Largest force at the apparatus's readings (every `reading_interval_m`), N; `None` if
    /// the curve does not reach the first reading.
    pub peak_at_readings_n: Option<f64>,
    pub reading_interval_m: f64,
    /// Largest displacement on the curve, m.
    pub max_displacement_m: f64,
    pub specimen: ShearSpecimen,
    /// Mean measured normal force over the curve divided by the area, Pa: should match
    /// `specimen.normal_pressure_pa`; `None` without `/scalars/normal_force`.
    pub mean_normal_stress_pa: Option<f64>,
    /// Largest inertial number over the curve (quasi-static below about 1e-3); `None`
    /// without `/scalars/inertial_number`.
    pub max_inertial_number: Option<f64>,
    /// The curve: (shear displacement m, shear force N), in time order.
    pub curve: Vec<(f64, f64)>,
}

/// A direct shear run's result (one flat JSON object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShearResult {
    #[serde(flatten)]
    pub source: RunSource,
    #[serde(flatten)]
    pub analysis: ShearAnalysis,
}

/// Reduces a direct shear run (scalars only; read it with [`super::CloudChoice::None`]).
pub fn shear(run: &Run, options: &ShearOptions) -> Result<ShearResult, ReduceError> {
    run.expect_experiment(DIRECT_SHEAR)?;
    let specimen = ShearSpecimen::from_run(run)?;
    let displacement = run.scalar("shear_displacement")?;
    let curve = displacement.paired(run.scalar("shear_force")?);
    let normal = run
        .scalar("normal_force")
        .ok()
        .map(|n| displacement.paired(n));
    let inertial = run
        .scalar("inertial_number")
        .ok()
        .map(|s| s.value.as_slice());
    let analysis = analyse_shear(curve, normal.as_deref(), inertial, &specimen, options)
        .map_err(|e| e.in_file(&run.file))?;
    Ok(ShearResult {
        source: run.source(),
        analysis,
    })
}

/// Finds the peak of `curve` ((displacement m, force N) in time order). `normal_force`
/// ((displacement m, normal force N), optional) and `inertial_number` (optional) are
/// summarised beside it.
pub fn analyse_shear(
    mut curve: Vec<(f64, f64)>,
    normal_force: Option<&[(f64, f64)]>,
    inertial_number: Option<&[f64]>,
    specimen: &ShearSpecimen,
    options: &ShearOptions,
) -> Result<ShearAnalysis, ReduceError> {
    if !specimen.area_m2.is_finite() || specimen.area_m2 <= 0.0 {
        return Err(ReduceError::Degenerate(format!(
            "direct shear: specimen area {} m^2 is not positive",
            specimen.area_m2
        )));
    }
    if let Some(limit) = options.max_displacement_m {
        curve.retain(|p| p.0 <= limit);
    }
    let &(displacement_at_peak_m, peak_shear_force_n) = curve
        .iter()
        .reduce(|a, b| if b.1 > a.1 { b } else { a })
        .ok_or_else(|| ReduceError::TooFewPoints {
            what: "direct shear: force-displacement points".to_string(),
            have: 0,
            need: 1,
        })?;
    let max_displacement_m = curve.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let limit = options.max_displacement_m.unwrap_or(f64::INFINITY);
    let mean_normal_force = normal_force.and_then(|n| {
        let used: Vec<f64> = n.iter().filter(|p| p.0 <= limit).map(|p| p.1).collect();
        (!used.is_empty()).then(|| used.iter().sum::<f64>() / used.len() as f64)
    });
    Ok(ShearAnalysis {
        peak_shear_force_n,
        displacement_at_peak_m,
        peak_shear_stress_pa: peak_shear_force_n / specimen.area_m2,
        peak_at_readings_n: peak_at_readings(&curve, options.reading_interval_m),
        reading_interval_m: options.reading_interval_m,
        max_displacement_m,
        specimen: *specimen,
        mean_normal_stress_pa: mean_normal_force.map(|f| f / specimen.area_m2),
        max_inertial_number: inertial_number.and_then(|v| v.iter().copied().reduce(f64::max)),
        curve,
    })
}

/// The largest force read at displacements k * `interval` (k = 1, 2, ...) along `curve`, the
/// force at each reading linearly interpolated on the first segment of the curve that
/// crosses it (the apparatus reads as the box passes the mark).
fn peak_at_readings(curve: &[(f64, f64)], interval: f64) -> Option<f64> {
    if !interval.is_finite() || interval <= 0.0 {
        return None;
    }
    let mut best: Option<f64> = None;
    let mut next = interval;
    // A curve that starts past the first marks (recorded late) is read from its start.
    if let Some(&(s0, _)) = curve.first().filter(|p| p.0 > interval) {
        next = interval * (s0 / interval).ceil();
    }
    for w in curve.windows(2) {
        let ((s0, f0), (s1, f1)) = (w[0], w[1]);
        while s0 <= next && next <= s1 && s1 > s0 {
            let f = f0 + (f1 - f0) * (next - s0) / (s1 - s0);
            best = Some(best.map_or(f, |b| b.max(f)));
            next += interval;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn specimen() -> ShearSpecimen {
        ShearSpecimen {
            diameter_m: 0.0618,
            area_m2: 3.0e-3,
            normal_pressure_pa: 50e3,
        }
    }

    #[test]
    fn peak_of_a_made_up_curve() {
        // F(s) = 120 N * (s / 2 mm) * exp(1 - s / 2 mm): peak 120 N at s = 2 mm exactly
        // (d/ds [x e^(1-x)] = (1 - x) e^(1-x) = 0 at x = 1), sampled every 0.01 mm to 5 mm.
        let curve: Vec<(f64, f64)> = (0..=500)
            .map(|k| {
                let s = k as f64 * 1e-5;
                let x = s / 2e-3;
                (s, 120.0 * x * (1.0 - x).exp())
            })
            .collect();
        let a = analyse_shear(curve, None, None, &specimen(), &ShearOptions::default()).unwrap();
        assert!((a.peak_shear_force_n - 120.0).abs() < 1e-9);
        assert!((a.displacement_at_peak_m - 2e-3).abs() < 1e-12);
        assert!((a.peak_shear_stress_pa - 40e3).abs() < 1e-6);
        // Readings at 0.8, 1.6, 2.4, 3.2, 4.0, 4.8 mm: the largest is at 2.4 mm (x = 1.2):
        // 120 * 1.2 * e^-0.2 = 117.8972 N (1.6 mm gives 117.2547 N), below the true peak.
        let read = a.peak_at_readings_n.unwrap();
        assert!((read - 117.8972).abs() < 1e-3, "{read}");
        assert!((a.max_displacement_m - 5e-3).abs() < 1e-12);
    }

    #[test]
    fn displacement_limit_cuts_the_curve() {
        let curve = vec![(0.0, 0.0), (1e-3, 10.0), (2e-3, 20.0), (6e-3, 30.0)];
        let options = ShearOptions {
            max_displacement_m: Some(5e-3),
            ..ShearOptions::default()
        };
        // The normal force after the limit (999 N) is left out of the mean like the curve.
        let normal = [(0.0, 150.0), (1e-3, 150.0), (2e-3, 150.0), (6e-3, 999.0)];
        let a = analyse_shear(curve, Some(&normal), None, &specimen(), &options).unwrap();
        assert_eq!(a.peak_shear_force_n, 20.0);
        assert_eq!(a.curve.len(), 3);
        assert!((a.mean_normal_stress_pa.unwrap() - 50e3).abs() < 1e-6);
    }

    #[test]
    fn empty_curve_is_an_error() {
        assert!(analyse_shear(vec![], None, None, &specimen(), &ShearOptions::default()).is_err());
    }
}
