//! Two fits that are not nested in each other, compared on the same rows: Vuong's test.
//!
//! With standardised residuals z_a and z_b of fits a and b on n rows (normal errors, known
//! standard errors, as many free parameters each), the log-likelihood ratio of row i is
//! l_i = (z_b,i^2 - z_a,i^2) / 2, and
//!
//!   V = sum_i l_i / (sqrt(n) w),   w^2 = (1/n) sum_i (l_i - mean l)^2,
//!
//! is asymptotically standard normal when the two fit equally well; V large favours a. A
//! chi^2 difference that a few rows make moves V less than one spread over many rows, so a
//! rival that loses on one unlucky row is not excluded by it.
//!
//! Reference: Vuong (1989) Econometrica 57:307, "Likelihood ratio tests for model selection
//! and non-nested hypotheses".

use statrs::distribution::{ContinuousCDF, Normal};

/// V for fit a against fit b; 0 when they fit every row alike, +/-inf when they differ by
/// the same amount on every row.
pub fn vuong(z_a: &[f64], z_b: &[f64]) -> f64 {
    assert_eq!(z_a.len(), z_b.len(), "the same rows");
    let n = z_a.len() as f64;
    let l: Vec<f64> = z_a
        .iter()
        .zip(z_b)
        .map(|(a, b)| (b * b - a * a) / 2.0)
        .collect();
    let sum: f64 = l.iter().sum();
    let mean = sum / n;
    let w = (l.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    if sum == 0.0 {
        0.0
    } else if w <= 1e-12 * mean.abs() {
        // The same difference on every row, up to rounding.
        sum.signum() * f64::INFINITY
    } else {
        sum / (n.sqrt() * w)
    }
}

/// P(Z > v): the one-sided p-value that fit a is no better than fit b.
pub fn vuong_p(v: f64) -> f64 {
    Normal::new(0.0, 1.0).expect("standard normal").sf(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_statistic_is_the_mean_log_likelihood_ratio_over_its_spread() {
        // l = (0, 1.5, 4): sum 5.5, mean 11/6, w^2 = ((11/6)^2 + (1/3)^2 + (13/6)^2) / 3.
        let a = [1.0, 1.0, 0.0];
        let b = [1.0, 2.0, 8f64.sqrt()];
        let w = (((11.0f64 / 6.0).powi(2) + (1.0f64 / 3.0).powi(2) + (13.0f64 / 6.0).powi(2))
            / 3.0)
            .sqrt();
        let want = 5.5 / (3f64.sqrt() * w);
        assert!((vuong(&a, &b) - want).abs() < 1e-12);
        assert!((vuong(&b, &a) + want).abs() < 1e-12, "antisymmetric");
        assert_eq!(vuong(&a, &a), 0.0);
        assert_eq!(vuong(&[0.0, 0.0], &[1.0, 1.0]), f64::INFINITY);
        assert!((vuong_p(0.0) - 0.5).abs() < 1e-15);
    }

    #[test]
    fn one_bad_row_weighs_less_than_the_same_chi2_over_all_rows() {
        let a = vec![1.0; 16];
        let mut one_row = a.clone();
        one_row[0] = 17f64.sqrt(); // chi^2 16 more, on one row
        let spread: Vec<f64> = a.iter().map(|_| 2f64.sqrt()).collect(); // 16 more, 1 per row
        // l = (8, 0 x 15): V = 8 / (4 sqrt(3.75)) = 1.03, p 0.15: not excluded.
        assert!((vuong(&a, &one_row) - 8.0 / (4.0 * 3.75f64.sqrt())).abs() < 1e-12);
        assert_eq!(vuong(&a, &spread), f64::INFINITY);
    }
}
