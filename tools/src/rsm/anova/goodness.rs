//! R^2, adjusted and predicted R^2, PRESS, adequate precision, standard deviation and C.V.,
//! with notes on the warning signs.

use crate::rsm::ols::Ols;

/// The goodness-of-fit statistics (the module documentation gives their formulas).
pub(super) struct Goodness {
    pub(super) r2: f64,
    pub(super) adj_r2: Option<f64>,
    pub(super) press: Option<f64>,
    pub(super) pred_r2: Option<f64>,
    pub(super) adeq_precision: Option<f64>,
    pub(super) std_dev: Option<f64>,
    pub(super) cv_pct: Option<f64>,
}

/// The goodness of the fit `full` of `y` with `p` coefficients, adding a note for each
/// warning sign (leverage 1, a predicted R^2 far below the adjusted one or negative).
pub(super) fn goodness(
    full: &Ols,
    y: &[f64],
    p: usize,
    mse: Option<f64>,
    mean: f64,
    sst: f64,
    notes: &mut Vec<String>,
) -> Goodness {
    let n = y.len();
    let r2 = if sst > 0.0 { 1.0 - full.sse / sst } else { 1.0 };
    let adj_r2 = mse.map(|m| 1.0 - m / (sst / (n - 1) as f64));
    let press = press(full, y, notes);
    let pred_r2 = press.map(|p| 1.0 - p / sst);
    if let (Some(a), Some(pr)) = (adj_r2, pred_r2) {
        if a - pr > 0.2 {
            notes.push(format!(
                "predicted R^2 {pr:.4} is more than 0.2 below adjusted R^2 {a:.4}: consider reducing the model, a response transformation, or an outlier"
            ));
        }
        if pr < 0.0 {
            notes.push(
                "a negative predicted R^2: the overall mean predicts better than this model".into(),
            );
        }
    }
    let (lo, hi) = full
        .fitted
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    let adeq_precision = mse
        .filter(|m| *m > 0.0)
        .map(|m| (hi - lo) / (p as f64 * m / n as f64).sqrt());
    let std_dev = mse.map(f64::sqrt);
    let cv_pct = std_dev
        .filter(|_| mean != 0.0)
        .map(|s| 100.0 * s / mean.abs());
    Goodness {
        r2,
        adj_r2,
        press,
        pred_r2,
        adeq_precision,
        std_dev,
        cv_pct,
    }
}

/// PRESS = sum (e_i / (1 - h_ii))^2, the leave-one-out prediction error; undefined (with a
/// note) when a run has leverage 1.
fn press(full: &Ols, y: &[f64], notes: &mut Vec<String>) -> Option<f64> {
    if full.leverage.iter().all(|h| *h < 1.0 - 1e-9) {
        Some(
            full.fitted
                .iter()
                .zip(y)
                .zip(&full.leverage)
                .map(|((f, v), h)| ((v - f) / (1.0 - h)).powi(2))
                .sum::<f64>(),
        )
    } else {
        notes.push(
            "a run has leverage 1 (the model must pass through it): predicted R^2 is not defined"
                .into(),
        );
        None
    }
}
