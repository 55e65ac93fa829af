//! Where a model fails: the statistics behind `tilth compare`'s plain-language summary, and
//! its plots ([`plot`]).
//!
//! For each observable (one test), from the rows' residuals r = simulated mean - measured
//! and their standard errors s = sqrt(scatter^2 / replicates + uncertainty^2):
//!
//! - **bias**: the mean residual and a one-sample t-test against zero (n - 1 degrees of
//!   freedom); with standard errors known, also chi^2 = sum (r/s)^2 on n degrees of freedom,
//!   the test that residuals are no larger than their noise;
//! - **trend** along each condition with at least three distinct values: the least-squares
//!   slopes of the residual on those conditions together (with an intercept) and their
//!   two-sided t-tests (n - k - 1 degrees of freedom), "the error grows with moisture";
//!   one condition at a time when there are too few rows to fit them together;
//! - the rows whose |z| = |r|/s exceeds 2.
//!
//! Reference: any regression text (e.g. Montgomery & Runger, Applied Statistics and
//! Probability for Engineers, ch. 11 for the slope test).

pub mod plot;
pub mod welch;

use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF, StudentsT};
use std::collections::BTreeMap;

/// Mean and sample standard deviation (`None` below two values) of `v`.
pub fn mean_sd(v: &[f64]) -> (f64, Option<f64>) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let sd =
        (v.len() > 1).then(|| (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt());
    (m, sd)
}

/// Standard error of (simulated mean - measured): sqrt(scatter^2 / replicates +
/// uncertainty^2), when either is known.
pub fn std_error(scatter: Option<f64>, replicates: usize, uncertainty: Option<f64>) -> Option<f64> {
    let var = scatter.map_or(0.0, |s| s * s / replicates.max(1) as f64)
        + uncertainty.map_or(0.0, |u| u * u);
    (var > 0.0).then(|| var.sqrt())
}

/// One compared row, as the analysis needs it.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub test: String,
    pub observable: String,
    pub unit: String,
    pub conditions: BTreeMap<String, f64>,
    pub measured: f64,
    /// `None` when no replicate finished.
    pub simulated: Option<f64>,
    /// Standard error of the residual, when known.
    pub std_error: Option<f64>,
}

impl Row {
    pub fn residual(&self) -> Option<f64> {
        self.simulated.map(|s| s - self.measured)
    }

    pub fn z(&self) -> Option<f64> {
        self.residual()
            .zip(self.std_error.filter(|s| *s > 0.0))
            .map(|(r, s)| r / s)
    }
}

/// A test of a mean or a slope.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    pub value: f64,
    pub std_error: f64,
    /// Two-sided p-value of value = 0.
    pub p: f64,
}

/// The residuals' trend along one condition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trend {
    pub condition: String,
    /// Residual per unit of the condition.
    pub slope: Estimate,
}

/// One observable's verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    pub test: String,
    pub observable: String,
    pub unit: String,
    /// Rows with a simulated value.
    pub n: usize,
    pub failed_rows: usize,
    pub rmse: f64,
    pub mean_relative_error: f64,
    /// Mean residual (simulated - measured), t-tested against 0 (needs 2 rows).
    pub bias: Option<Estimate>,
    /// chi^2 of the z-scores and its p-value, when every row has a standard error.
    pub chi2: Option<(f64, f64)>,
    pub trends: Vec<Trend>,
    /// Rows (indices into the input) with |z| > 2.
    pub outliers: Vec<usize>,
}

/// Significance level of the summary's words.
pub const ALPHA: f64 = 0.05;

/// Two-sided p-value of t on `df` degrees of freedom. t = 0/0 (a zero estimate with zero
/// scatter) is no evidence at all: p = 1; a non-zero estimate with zero scatter: p = 0.
fn p_two_sided(t: f64, df: f64) -> f64 {
    if !t.is_finite() {
        return if t.is_nan() { 1.0 } else { 0.0 };
    }
    match StudentsT::new(0.0, 1.0, df) {
        Ok(d) => 2.0 * d.sf(t.abs()),
        Err(_) => f64::NAN,
    }
}

/// The verdict of each observable, in order of first appearance.
pub fn analyse(rows: &[Row]) -> Vec<Verdict> {
    let mut order: Vec<&str> = vec![];
    for r in rows {
        if !order.contains(&r.observable.as_str()) {
            order.push(&r.observable);
        }
    }
    order
        .into_iter()
        .map(|obs| {
            let idx: Vec<usize> = (0..rows.len())
                .filter(|&k| rows[k].observable == obs)
                .collect();
            verdict(rows, &idx)
        })
        .collect()
}

fn verdict(rows: &[Row], idx: &[usize]) -> Verdict {
    let first = &rows[idx[0]];
    let done: Vec<usize> = idx
        .iter()
        .copied()
        .filter(|&k| rows[k].simulated.is_some())
        .collect();
    let res: Vec<f64> = done.iter().map(|&k| rows[k].residual().unwrap()).collect();
    let n = res.len();
    let nf = n as f64;
    let rmse = (res.iter().map(|r| r * r).sum::<f64>() / nf).sqrt();
    let mean_relative_error = done
        .iter()
        .map(|&k| (rows[k].residual().unwrap() / rows[k].measured).abs())
        .sum::<f64>()
        / nf;
    let bias = (n >= 2).then(|| {
        let mean = res.iter().sum::<f64>() / nf;
        let var = res.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / (nf - 1.0);
        let se = (var / nf).sqrt();
        Estimate {
            value: mean,
            std_error: se,
            p: p_two_sided(mean / se, nf - 1.0),
        }
    });
    let zs: Vec<Option<f64>> = done.iter().map(|&k| rows[k].z()).collect();
    let chi2 = (n >= 1 && zs.iter().all(Option::is_some)).then(|| {
        let c: f64 = zs.iter().map(|z| z.unwrap().powi(2)).sum();
        let p = ChiSquared::new(nf).map_or(f64::NAN, |d| d.sf(c));
        (c, p)
    });
    let mut names: Vec<&String> = vec![];
    for &k in &done {
        for c in rows[k].conditions.keys() {
            if !names.contains(&c) {
                names.push(c);
            }
        }
    }
    // Conditions with three or more distinct values, fitted together so that a cross design
    // (one condition varied at a fixed level of the other) does not lend one condition's
    // trend to the other; one at a time when there are too few rows for that.
    let varying: Vec<&String> = names
        .into_iter()
        .filter(|c| {
            let mut xs: Vec<f64> = done
                .iter()
                .filter_map(|&k| rows[k].conditions.get(*c).copied())
                .collect();
            xs.sort_by(f64::total_cmp);
            xs.dedup();
            xs.len() >= 3
        })
        .collect();
    let complete: Vec<usize> = done
        .iter()
        .copied()
        .filter(|&k| varying.iter().all(|c| rows[k].conditions.contains_key(*c)))
        .collect();
    let joint = (varying.len() > 1)
        .then(|| {
            let x: Vec<Vec<f64>> = complete
                .iter()
                .map(|&k| varying.iter().map(|c| rows[k].conditions[*c]).collect())
                .collect();
            let y: Vec<f64> = complete
                .iter()
                .map(|&k| rows[k].residual().unwrap())
                .collect();
            slopes(&x, &y)
        })
        .flatten();
    let trends = match joint {
        Some(est) => varying
            .iter()
            .zip(est)
            .map(|(c, slope)| Trend {
                condition: (*c).clone(),
                slope,
            })
            .collect(),
        None => varying
            .into_iter()
            .filter_map(|c| {
                let pts: Vec<(f64, f64)> = done
                    .iter()
                    .filter_map(|&k| Some((*rows[k].conditions.get(c)?, rows[k].residual()?)))
                    .collect();
                slope(&pts).map(|slope| Trend {
                    condition: c.clone(),
                    slope,
                })
            })
            .collect(),
    };
    let outliers = done
        .iter()
        .copied()
        .filter(|&k| rows[k].z().is_some_and(|z| z.abs() > 2.0))
        .collect();
    Verdict {
        test: first.test.clone(),
        observable: first.observable.clone(),
        unit: first.unit.clone(),
        n,
        failed_rows: idx.len() - n,
        rmse,
        mean_relative_error,
        bias,
        chi2,
        trends,
        outliers,
    }
}

/// Least-squares slopes of y on several regressors at once (with an intercept), each with
/// its t-test on n - k - 1 degrees of freedom; `None` with fewer than two residual degrees
/// of freedom or collinear regressors.
pub fn slopes(x: &[Vec<f64>], y: &[f64]) -> Option<Vec<Estimate>> {
    use nalgebra::{DMatrix, DVector};
    let n = y.len();
    let k = x.first()?.len();
    if n < k + 3 {
        return None;
    }
    let a = DMatrix::from_fn(n, k + 1, |i, j| if j == 0 { 1.0 } else { x[i][j - 1] });
    let ata = a.transpose() * &a;
    let inv = ata.try_inverse()?;
    let b = &inv * a.transpose() * DVector::from_column_slice(y);
    let resid = DVector::from_column_slice(y) - &a * &b;
    let df = (n - k - 1) as f64;
    let s2 = resid.dot(&resid) / df;
    Some(
        (1..=k)
            .map(|j| {
                let se = (s2 * inv[(j, j)]).sqrt();
                Estimate {
                    value: b[j],
                    std_error: se,
                    p: p_two_sided(b[j] / se, df),
                }
            })
            .collect(),
    )
}

/// Least-squares slope of y on x with its t-test; needs three distinct x.
pub fn slope(pts: &[(f64, f64)]) -> Option<Estimate> {
    let mut xs: Vec<f64> = pts.iter().map(|p| p.0).collect();
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    if xs.len() < 3 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let b = sxy / sxx;
    let sse: f64 = pts
        .iter()
        .map(|p| (p.1 - my - b * (p.0 - mx)).powi(2))
        .sum();
    let se = (sse / (n - 2.0) / sxx).sqrt();
    Some(Estimate {
        value: b,
        std_error: se,
        p: p_two_sided(b / se, n - 2.0),
    })
}

/// A p-value for "p {}": `= 0.034` in two significant digits, or `< 1e-6`.
pub fn p_text(p: f64) -> String {
    if p < 1e-6 {
        "< 1e-6".into()
    } else {
        format!("= {}", crate::rsm::significant(p, 2))
    }
}

/// The verdicts in words: one paragraph per observable, failures first.
pub fn summary(rows: &[Row], verdicts: &[Verdict]) -> String {
    let mut v: Vec<&Verdict> = verdicts.iter().collect();
    // Worst first: by mean relative error.
    v.sort_by(|a, b| b.mean_relative_error.total_cmp(&a.mean_relative_error));
    let mut out = String::new();
    for d in v {
        let u = &d.unit;
        out += &format!(
            "- **{}** ({}): RMSE {:.3} {u}, mean relative error {:.1} % over {} condition{}",
            d.test,
            d.observable,
            d.rmse,
            100.0 * d.mean_relative_error,
            d.n,
            if d.n == 1 { "" } else { "s" }
        );
        if d.failed_rows > 0 {
            out += &format!(
                "; {} condition{} had no simulated value",
                d.failed_rows,
                if d.failed_rows == 1 { "" } else { "s" }
            );
        }
        out += ".";
        if let Some(b) = d.bias {
            if b.p < ALPHA {
                out += &format!(
                    " The model {} it throughout: mean residual {:+.3} {u} (p {}).",
                    if b.value > 0.0 {
                        "over-predicts"
                    } else {
                        "under-predicts"
                    },
                    b.value,
                    p_text(b.p)
                );
            } else {
                out += &format!(
                    " No overall bias (mean residual {:+.3} {u}, p {}).",
                    b.value,
                    p_text(b.p)
                );
            }
        }
        for t in &d.trends {
            let s = t.slope;
            if s.p < ALPHA {
                out += &format!(
                    " The residual {} with {} ({:+.3} {u} per unit, p {}): the model misses how {} depends on it.",
                    if s.value > 0.0 { "grows" } else { "falls" },
                    t.condition,
                    s.value,
                    p_text(s.p),
                    d.observable
                );
            } else {
                out += &format!(
                    " No significant trend with {} (p {}).",
                    t.condition,
                    p_text(s.p)
                );
            }
        }
        if let Some((c, p)) = d.chi2 {
            out += &if p < ALPHA {
                format!(
                    " The residuals are larger than the measurement and simulation noise (chi^2 = {c:.1} on {} df, p {}).",
                    d.n,
                    p_text(p)
                )
            } else {
                format!(
                    " The residuals are within the measurement and simulation noise (chi^2 = {c:.1} on {} df, p {}).",
                    d.n,
                    p_text(p)
                )
            };
        }
        if !d.outliers.is_empty() {
            let list: Vec<String> = d
                .outliers
                .iter()
                .map(|&k| {
                    let r = &rows[k];
                    let conds: Vec<String> = r
                        .conditions
                        .iter()
                        .map(|(c, x)| format!("{c} {x}"))
                        .collect();
                    format!(
                        "{} (z = {:+.1})",
                        conds.join(", "),
                        r.z().unwrap_or(f64::NAN)
                    )
                })
                .collect();
            out += &format!(" Beyond 2 standard errors: {}.", list.join("; "));
        }
        out += "\n";
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(m: f64, sim: f64, x: f64, se: Option<f64>) -> Row {
        Row {
            test: "repose".into(),
            observable: "repose_angle_deg".into(),
            unit: "deg".into(),
            conditions: [("moisture_pct".to_string(), x)].into_iter().collect(),
            measured: m,
            simulated: Some(sim),
            std_error: se,
        }
    }

    #[test]
    fn the_slope_test_matches_a_hand_calculation() {
        // y = 2 x + e, e = (+1, -1, -1, +1) at x = 0..3: b = 2 + (sum (x - 1.5) e) / 5
        // = 2 + (-1.5 + 0.5 - 0.5 + 1.5) / 5 = 2; SSE = 4, se = sqrt(4 / 2 / 5).
        let pts = [(0.0, 1.0), (1.0, 1.0), (2.0, 3.0), (3.0, 7.0)];
        let s = slope(&pts).unwrap();
        assert!((s.value - 2.0).abs() < 1e-12);
        assert!((s.std_error - (0.4f64).sqrt()).abs() < 1e-12);
        // t = 2 / sqrt(0.4) = 3.1623 on 2 df: two-sided p = 0.0871 (t tables).
        assert!((s.p - 0.0871).abs() < 5e-4, "{}", s.p);
    }

    #[test]
    fn a_trend_with_moisture_is_found_and_said() {
        // Residuals 0, 1, 2, 3 (+/- 0.1) along moisture 3, 6, 9, 12.
        let rows: Vec<Row> = [(3.0, 0.1), (6.0, 0.9), (9.0, 2.1), (12.0, 2.9)]
            .iter()
            .map(|&(x, r)| row(30.0, 30.0 + r, x, Some(0.5)))
            .collect();
        let v = analyse(&rows);
        assert_eq!(v.len(), 1);
        let t = &v[0].trends[0];
        assert!(t.slope.p < 0.01 && t.slope.value > 0.0);
        let text = summary(&rows, &v);
        assert!(text.contains("grows with moisture_pct"), "{text}");
        assert!(text.contains("larger than the measurement"), "{text}");
    }

    /// A cross design: firmness varied at 6 % moisture, moisture varied at 1.55 MPa. The
    /// residual depends on firmness only; fitted together, moisture gets no trend.
    #[test]
    fn a_cross_design_keeps_each_condition_to_its_own_trend() {
        let mut rows = vec![];
        let noise = [0.3, -0.2, 0.1, -0.3, 0.2, 0.1, -0.1, 0.2];
        let pts = [
            (6.0, 0.34),
            (6.0, 0.945),
            (6.0, 1.55),
            (6.0, 2.155),
            (6.0, 2.76),
            (3.0, 1.55),
            (9.0, 1.55),
            (12.0, 1.55),
        ];
        for (k, &(m, f)) in pts.iter().enumerate() {
            let mut r = row(100.0, 100.0 - 40.0 * f + noise[k], m, Some(1.0));
            r.conditions.insert("firmness_mpa".into(), f);
            rows.push(r);
        }
        let v = analyse(&rows);
        let t = |c: &str| v[0].trends.iter().find(|t| t.condition == c).unwrap().slope;
        assert!(
            (t("firmness_mpa").value + 40.0).abs() < 1.0,
            "{:?}",
            t("firmness_mpa")
        );
        assert!(t("firmness_mpa").p < 1e-6);
        assert!(t("moisture_pct").p > 0.05, "{:?}", t("moisture_pct"));
        // Against a hand-checkable case: with one regressor, slopes() is slope().
        let x: Vec<Vec<f64>> = [0.0, 1.0, 2.0, 3.0].iter().map(|v| vec![*v]).collect();
        let one = slopes(&x, &[1.0, 1.0, 3.0, 7.0]).unwrap();
        let s = slope(&[(0.0, 1.0), (1.0, 1.0), (2.0, 3.0), (3.0, 7.0)]).unwrap();
        assert!((one[0].value - s.value).abs() < 1e-12 && (one[0].p - s.p).abs() < 1e-12);
    }

    #[test]
    fn residuals_within_noise_are_said_to_be() {
        let rows: Vec<Row> = [(3.0, 0.3), (6.0, -0.4), (9.0, 0.2), (12.0, -0.1)]
            .iter()
            .map(|&(x, r)| row(30.0, 30.0 + r, x, Some(0.5)))
            .collect();
        let v = analyse(&rows);
        let text = summary(&rows, &v);
        assert!(text.contains("within the measurement"), "{text}");
        assert!(text.contains("No overall bias"), "{text}");
        assert!(v[0].outliers.is_empty());
    }
}
