//! Calibration uncertainty on problems with known answers.

use tilth_tools::calibrate::{linearised, smc};

/// A Gaussian likelihood well inside the prior box: the posterior is that Gaussian.
#[test]
fn smc_recovers_a_gaussian_posterior() {
    let p = smc(
        |t| -0.5 * ((t[0] - 0.3) / 0.05).powi(2),
        &[0.0],
        &[1.0],
        4000,
        7,
    );
    assert!((p.mean[0] - 0.3).abs() < 0.005, "mean {}", p.mean[0]);
    assert!((p.sd[0] / 0.05 - 1.0).abs() < 0.1, "sd {}", p.sd[0]);
    let (lo, hi) = (p.q025[0], p.q975[0]);
    assert!((lo - (0.3 - 1.96 * 0.05)).abs() < 0.01 && (hi - (0.3 + 1.96 * 0.05)).abs() < 0.01);
}

/// Two parameters that only enter as their sum: the posterior is a ridge along a + b = 1,
/// perfectly anticorrelated, spread over the whole box.
#[test]
fn smc_shows_a_ridge_as_anticorrelation() {
    let p = smc(
        |t| -0.5 * ((t[0] + t[1] - 1.0) / 0.01).powi(2),
        &[0.0, 0.0],
        &[1.0, 1.0],
        3000,
        3,
    );
    assert!(p.correlation[0][1] < -0.95, "corr {}", p.correlation[0][1]);
    assert!(
        p.q975[0] - p.q025[0] > 0.8,
        "spread {}..{}",
        p.q025[0],
        p.q975[0]
    );
    for s in &p.samples {
        assert!((s[0] + s[1] - 1.0).abs() < 0.05);
    }
}

/// Same seed, same sample.
#[test]
fn smc_is_deterministic() {
    let f = |t: &[f64]| -0.5 * ((t[0] - 0.5) / 0.1).powi(2);
    assert_eq!(
        smc(f, &[0.0], &[1.0], 500, 11).samples,
        smc(f, &[0.0], &[1.0], 500, 11).samples
    );
}

/// Linear residuals r = A theta - y: cov = (A'A)^-1 exactly.
#[test]
fn linearised_intervals_of_a_linear_model() {
    let a = [[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]];
    let r = |t: &[f64]| {
        a.iter()
            .map(|row| row[0] * t[0] + row[1] * t[1])
            .collect::<Vec<f64>>()
    };
    let l = linearised(r, &[0.2, 0.4], &[1e-3, 1e-3]);
    assert_eq!(l.rank, 2);
    // A'A = [[3, 3], [3, 5]], inverse = [[5, -3], [-3, 3]] / 6.
    let se = l.std_error.unwrap();
    assert!((se[0] - (5.0f64 / 6.0).sqrt()).abs() < 1e-9);
    assert!((se[1] - (3.0f64 / 6.0).sqrt()).abs() < 1e-9);
    assert!(l.null_directions.is_empty());
}

/// One residual, two parameters entering as a sum: rank 1, the ridge direction (1, -1).
#[test]
fn linearised_reports_the_ridge_direction() {
    let l = linearised(
        |t: &[f64]| vec![(t[0] + t[1] - 1.0) / 0.1],
        &[0.3, 0.7],
        &[1e-4, 1e-4],
    );
    assert_eq!(l.rank, 1);
    assert!(l.std_error.is_none());
    let d = &l.null_directions[0];
    assert!((d[0] + d[1]).abs() < 1e-9 && (d[0].abs() - 0.5f64.sqrt()).abs() < 1e-9);
    let (lo, hi) = l.conditional_ci95[0].unwrap();
    assert!((hi - lo - 2.0 * 1.959963984540054 * 0.1).abs() < 1e-6);
}
