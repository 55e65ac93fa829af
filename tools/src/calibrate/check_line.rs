//! The next setting of a one-parameter calibration from its direct checks: the straight line
//! through every check so far, solved for the target.
//!
//! A check is the mean of n seeded runs at one setting x. Its variance is sigma^2 / n, so the
//! line y = a + b x is fitted by least squares with weights n_i (Montgomery, *Design and
//! Analysis of Experiments*, weighted least squares), and the next setting is
//!
//! ```text
//!     x_next = x_w + (target - y_w) / b,   x_w = sum(n x) / sum(n),  y_w = sum(n y) / sum(n)
//! ```
//!
//! With two checks that is the secant through them. Why the checks and not the response
//! surface: the surface is a quadratic fitted over the whole range to a few seeds per setting,
//! and its slope at one point can be off by a factor of two where the curve bends (the 9 %
//! heap's surface said 40 degrees per unit of rolling friction; its checks measured 66-91).
//! A Newton step along a wrong slope overshoots both ways, and with checks on the same seeds
//! (common random numbers) their own slope is measured where the calibration is.
//!
//! The checks' slope is only used when it agrees in sign with the surface's (`prior_slope`):
//! checks close together whose scatter swamps their difference give a slope of either sign,
//! and a step along the wrong sign moves away from the target.

/// One direct check: its setting, the mean of its runs and how many runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Check {
    pub setting: f64,
    pub mean: f64,
    pub runs: usize,
}

/// The weighted line through `checks` solved for `target`; its slope too. None when the
/// checks have fewer than two distinct settings, or their slope is zero or of the other sign
/// than `prior_slope`.
///
/// ```
/// use tilth_tools::calibrate::{Check, next_from_checks};
/// let checks = [
///     Check { setting: 0.10, mean: 36.0, runs: 10 },
///     Check { setting: 0.14, mean: 40.0, runs: 10 },
/// ];
/// let (x, slope) = next_from_checks(&checks, 38.0, 40.0).unwrap();
/// assert!((slope - 100.0).abs() < 1e-9 && (x - 0.12).abs() < 1e-12);
/// ```
pub fn next_from_checks(checks: &[Check], target: f64, prior_slope: f64) -> Option<(f64, f64)> {
    let n: f64 = checks.iter().map(|c| c.runs as f64).sum();
    if n == 0.0 {
        return None;
    }
    let xw = checks
        .iter()
        .map(|c| c.runs as f64 * c.setting)
        .sum::<f64>()
        / n;
    let yw = checks.iter().map(|c| c.runs as f64 * c.mean).sum::<f64>() / n;
    let sxx: f64 = checks
        .iter()
        .map(|c| c.runs as f64 * (c.setting - xw).powi(2))
        .sum();
    let sxy: f64 = checks
        .iter()
        .map(|c| c.runs as f64 * (c.setting - xw) * (c.mean - yw))
        .sum();
    // Settings that differ by less than a part in 1e12 of their size are one setting.
    let scale = checks
        .iter()
        .map(|c| c.setting.abs())
        .fold(0.0, f64::max)
        .max(1e-300);
    if sxx <= n * (1e-12 * scale).powi(2) {
        return None;
    }
    let slope = sxy / sxx;
    if !(slope * prior_slope > 0.0) {
        return None;
    }
    Some((xw + (target - yw) / slope, slope))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(setting: f64, mean: f64, runs: usize) -> Check {
        Check {
            setting,
            mean,
            runs,
        }
    }

    #[test]
    fn three_checks_on_a_line_give_its_root() {
        // y = 30 + 70 x: the target 37.89 is at x = 7.89 / 70.
        let line = |x: f64| 30.0 + 70.0 * x;
        let checks = [
            check(0.137, line(0.137), 10),
            check(0.0925, line(0.0925), 10),
            check(0.121, line(0.121), 20),
        ];
        let (x, slope) = next_from_checks(&checks, 37.89, 40.0).unwrap();
        assert!((slope - 70.0).abs() < 1e-9);
        assert!((x - 7.89 / 70.0).abs() < 1e-12);
    }

    #[test]
    fn a_check_with_more_runs_weighs_more() {
        // Two checks at one setting (10 runs reading 35, 30 runs reading 37: the pooled
        // mean is 36.5) and one at another: the line passes through the pooled mean.
        let checks = [
            check(0.2, 35.0, 10),
            check(0.2, 37.0, 30),
            check(0.3, 38.5, 10),
        ];
        let (x, slope) = next_from_checks(&checks, 36.5, 1.0).unwrap();
        assert!((slope - 20.0).abs() < 1e-9, "{slope}");
        assert!((x - 0.2).abs() < 1e-12, "{x}");
    }

    #[test]
    fn one_setting_or_a_slope_against_the_surface_gives_nothing() {
        assert_eq!(next_from_checks(&[check(0.3, 32.9, 10)], 32.76, 20.0), None);
        assert_eq!(
            next_from_checks(&[check(0.3, 32.9, 10), check(0.3, 32.1, 10)], 32.76, 20.0),
            None
        );
        // The checks say the angle falls with the setting; the surface says it rises.
        assert_eq!(
            next_from_checks(&[check(0.3, 33.0, 10), check(0.32, 32.5, 10)], 32.76, 20.0),
            None
        );
        assert_eq!(
            next_from_checks(&[check(0.3, 33.0, 10), check(0.32, 33.0, 10)], 32.76, 20.0),
            None
        );
        assert_eq!(next_from_checks(&[], 32.76, 20.0), None);
    }
}
