//! Ordinary least-squares straight line, the one fit every reducer uses.
//!
//! For points (x_i, y_i), i = 1..n, the line y = a + b x minimising sum (y_i - a - b x_i)^2 is
//!
//! ```text
//! b = S_xy / S_xx,   a = mean(y) - b mean(x),
//! S_xx = sum (x_i - mean(x))^2,   S_xy = sum (x_i - mean(x)) (y_i - mean(y)),
//! R^2 = 1 - SS_res / SS_tot,      SS_res = sum (y_i - a - b x_i)^2,  SS_tot = sum (y_i - mean(y))^2
//! ```
//!
//! (e.g. Montgomery & Runger, *Applied Statistics and Probability for Engineers*, ch. 11).
//! Sums are taken about the means, so coordinates in metres far from the origin lose no digits.

use super::error::ReduceError;
use serde::{Deserialize, Serialize};

/// A fitted line y = intercept + slope x (units of y and y per unit of x).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LineFit {
    pub slope: f64,
    pub intercept: f64,
    /// Coefficient of determination; 1 when every point lies on the line (including the
    /// case of all y equal, where SS_tot = 0).
    pub r_squared: f64,
    /// Number of points fitted.
    pub points: usize,
}

impl LineFit {
    /// y on the line at `x`.
    pub fn at(&self, x: f64) -> f64 {
        self.intercept + self.slope * x
    }
}

/// Fits y = a + b x to `points` by least squares. `what` names the fit in errors.
///
/// Needs at least 2 points with different x; with exactly 2 the line passes through both and
/// R^2 = 1 says nothing.
pub fn fit_line(points: &[(f64, f64)], what: &str) -> Result<LineFit, ReduceError> {
    let n = points.len();
    if n < 2 {
        return Err(ReduceError::TooFewPoints {
            what: what.to_string(),
            have: n,
            need: 2,
        });
    }
    let nf = n as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / nf;
    let my = points.iter().map(|p| p.1).sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for &(x, y) in points {
        let (dx, dy) = (x - mx, y - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    if sxx <= 0.0 || !sxx.is_finite() {
        return Err(ReduceError::Degenerate(format!(
            "{what}: all {n} points share one abscissa, no line through them has a slope"
        )));
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ss_res: f64 = points
        .iter()
        .map(|&(x, y)| (y - intercept - slope * x).powi(2))
        .sum();
    let r_squared = if syy > 0.0 { 1.0 - ss_res / syy } else { 1.0 };
    Ok(LineFit {
        slope,
        intercept,
        r_squared,
        points: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_line_is_recovered_with_r2_one() {
        let pts: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 2.0 + 0.5 * i as f64)).collect();
        let f = fit_line(&pts, "test").unwrap();
        assert!((f.slope - 0.5).abs() < 1e-12);
        assert!((f.intercept - 2.0).abs() < 1e-12);
        assert!((f.r_squared - 1.0).abs() < 1e-12);
        assert_eq!(f.points, 5);
    }

    #[test]
    fn hand_computed_fit() {
        // x = 0, 1, 2; y = 0, 2, 1: mean x 1, mean y 1, S_xx 2, S_xy 1 -> b = 0.5, a = 0.5;
        // residuals -0.5, 1, -0.5 -> SS_res 1.5, SS_tot 2 -> R^2 = 0.25.
        let f = fit_line(&[(0.0, 0.0), (1.0, 2.0), (2.0, 1.0)], "test").unwrap();
        assert!((f.slope - 0.5).abs() < 1e-12);
        assert!((f.intercept - 0.5).abs() < 1e-12);
        assert!((f.r_squared - 0.25).abs() < 1e-12);
    }

    #[test]
    fn refuses_too_few_and_vertical() {
        assert!(matches!(
            fit_line(&[(1.0, 1.0)], "t"),
            Err(ReduceError::TooFewPoints { have: 1, .. })
        ));
        assert!(matches!(
            fit_line(&[(1.0, 1.0), (1.0, 2.0)], "t"),
            Err(ReduceError::Degenerate(_))
        ));
    }
}
