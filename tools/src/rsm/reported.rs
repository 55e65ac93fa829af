//! Checking a fit against a published ANOVA table, value by value.
//!
//! A paper prints its responses rounded (table 6 of the reference study: two decimals), so
//! its statistics, computed from the unrounded responses, need not be what the printed
//! responses give to every digit. The check therefore refits the model many times with each
//! response moved uniformly within its rounding (+-half a unit of its last printed digit),
//! and a published number agrees when its own rounding interval meets the range of those
//! refits. `<0.001` agrees with anything below 0.001. Disagreements are kept and shown, never
//! smoothed over: a paper's table can be wrong (table 7 of the reference study prints
//! p = 0.007 for x4 where its own data give 0.0022, and 0.0021-0.0023 within the rounding).

use super::terms::canonical;
use super::{Anova, Data, FitOptions, RsmError, SourceRow, Table, fit};
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use serde::Serialize;

/// Refits with rounding-perturbed responses.
const DRAWS: usize = 2000;

/// One reported value and ours.
#[derive(Debug, Clone, Serialize)]
pub struct Check {
    pub source: String,
    pub field: String,
    pub reported: String,
    pub computed: Option<f64>,
    /// Smallest and largest value over the refits within the responses' rounding.
    pub range: Option<(f64, f64)>,
    pub agrees: bool,
    pub note: Option<String>,
}

/// The fields a reported table may carry (column name -> our field).
fn field_of(column: &str) -> Option<&'static str> {
    Some(match column.to_ascii_lowercase().as_str() {
        "df" => "df",
        "sum_sq" | "sum_of_squares" | "ss" => "sum_sq",
        "mean_square" | "mean_sq" | "ms" => "mean_sq",
        "f" | "f_value" => "f",
        "p" | "p_value" | "prob_f" => "p",
        "contribution_pct" => "contribution_pct",
        "standardized_effect" | "t" => "t",
        "coefficient" | "estimate" => "coefficient",
        _ => return None,
    })
}

/// Compares `anova` with the published table `reported` (a `source` column and any of df,
/// sum_sq, mean_square, f, p_value, contribution_pct, standardized_effect, coefficient).
/// With `value_column`, that one column holds each source's p-value (and rows `r_squared`,
/// `adeq_precision`... their statistics), as in a table with one column per response.
///
/// `data` and `options` are what `anova` was fitted from; when the responses were read as
/// printed decimals, the refits within their rounding set each value's range.
pub fn compare_reported(
    anova: &Anova,
    data: &Data,
    options: FitOptions,
    reported: &Table,
    value_column: Option<&str>,
) -> Result<Vec<Check>, RsmError> {
    let perturbed: Vec<Anova> = match data.response_decimals {
        Some(d) => {
            let half = 0.5 * 10f64.powi(-(d as i32));
            let mut rng = ChaCha8Rng::seed_from_u64(0x7e11);
            let mut list = Vec::with_capacity(DRAWS);
            for _ in 0..DRAWS {
                let y = data
                    .y
                    .iter()
                    .map(|v| {
                        let u = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                        v + half * (2.0 * u - 1.0)
                    })
                    .collect();
                list.push(fit(&data.with_response(&data.response, y), options)?);
            }
            list
        }
        None => vec![],
    };
    let sources = reported.text("source")?;
    let columns: Vec<(usize, &'static str)> = match value_column {
        Some(c) => vec![(reported.column(c)?, "p")],
        None => reported
            .names
            .iter()
            .enumerate()
            .filter_map(|(k, n)| field_of(n).map(|f| (k, f)))
            .collect(),
    };
    if columns.is_empty() {
        return Err(RsmError::Request(format!(
            "{}: no column to compare (expected any of df, sum_sq, mean_square, f, p_value, contribution_pct, standardized_effect, coefficient)",
            reported.source
        )));
    }
    let mut out = Vec::new();
    for (r, source) in sources.iter().enumerate() {
        let key = canonical(source);
        for &(c, field) in &columns {
            let text = reported.rows[r].get(c).map_or("", |s| s.as_str()).trim();
            if text.is_empty() {
                continue;
            }
            let row = &reported.rows[r];
            let (computed, note, name) = lookup(anova, &key, field, row, reported);
            let values: Vec<f64> = perturbed
                .iter()
                .filter_map(|a| lookup(a, &key, field, row, reported).0)
                .chain(computed)
                .collect();
            let range = (!perturbed.is_empty() && computed.is_some()).then(|| {
                values
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                        (a.min(*v), b.max(*v))
                    })
            });
            let agrees = match (computed, range) {
                (None, _) => false,
                (Some(v), None) => matches_printed(v, text, (v, v)),
                (Some(v), Some(r)) => matches_printed(v, text, r),
            };
            out.push(Check {
                source: source.clone(),
                field: name.to_string(),
                reported: text.to_string(),
                computed,
                range,
                agrees,
                note,
            });
        }
    }
    Ok(out)
}

/// Our value for (source, field); statistics rows (r_squared...) map to the fit's statistics
/// whatever the column.
fn lookup(
    a: &Anova,
    key: &str,
    field: &'static str,
    row: &[String],
    table: &Table,
) -> (Option<f64>, Option<String>, &'static str) {
    let stat = match key {
        "r_squared" => Some(("r2", Some(a.r2))),
        "adj_r_squared" | "adj_r2" => Some(("adj_r2", a.adj_r2)),
        "pred_r_squared" | "pred_r2" => Some(("pred_r2", a.pred_r2)),
        "adeq_precision" => Some(("adeq_precision", a.adeq_precision)),
        _ => None,
    };
    if let Some((name, v)) = stat {
        return (v, None, name);
    }
    let sst = a.total.sum_sq;
    if let Some(t) = a.terms.iter().find(|t| canonical(&t.name) == key) {
        let v = match field {
            "df" => Some(t.df as f64),
            "sum_sq" => Some(t.sum_sq),
            "mean_sq" => Some(t.mean_sq),
            "f" => t.f,
            "p" => t.p,
            "contribution_pct" => Some(t.contribution_pct),
            "t" => t.t.map(f64::abs),
            "coefficient" => Some(t.coefficient),
            _ => None,
        };
        return (v, None, field);
    }
    let row_of = |s: &SourceRow| match field {
        "df" => Some(s.df as f64),
        "sum_sq" => Some(s.sum_sq),
        "mean_sq" => s.mean_sq,
        "f" => s.f,
        "p" => s.p,
        "contribution_pct" => Some(100.0 * s.sum_sq / sst),
        _ => None,
    };
    match key {
        "model" => {
            // A source may count the curvature indicator in its model row: its df says so.
            let df_reported = table
                .column("df")
                .ok()
                .and_then(|c| row.get(c))
                .and_then(|s| s.trim().parse::<f64>().ok());
            match (&a.curvature, df_reported) {
                (Some(c), Some(d)) if d as usize == a.model.df + c.df => {
                    let ss = a.model.sum_sq + c.sum_sq;
                    let df = a.model.df + c.df;
                    let mse = a.residual.mean_sq;
                    let f = mse.map(|m| ss / df as f64 / m);
                    let s = SourceRow {
                        sum_sq: ss,
                        df,
                        mean_sq: Some(ss / df as f64),
                        f,
                        p: f.and_then(|f| {
                            use statrs::distribution::{ContinuousCDF, FisherSnedecor};
                            FisherSnedecor::new(df as f64, a.residual.df as f64)
                                .ok()
                                .map(|d| d.sf(f))
                        }),
                    };
                    (
                        row_of(&s),
                        Some(
                            "the source's model row includes the curvature term (its df says so)"
                                .into(),
                        ),
                        field,
                    )
                }
                _ => (row_of(&a.model), None, field),
            }
        }
        "curvature" => (a.curvature.as_ref().and_then(row_of), None, field),
        "residual" => (row_of(&a.residual), None, field),
        "lack_of_fit" => (a.lack_of_fit.as_ref().and_then(row_of), None, field),
        "pure_error" => (a.pure_error.as_ref().and_then(row_of), None, field),
        "total" | "cor_total" => (row_of(&a.total), None, field),
        _ => (None, Some(format!("no source {key:?} in this fit")), field),
    }
}

/// Whether the printed `text` is consistent with our value `v`, whose refits within the
/// responses' rounding span `range`: the printed number's own rounding interval must meet
/// that range (`<0.001` style bounds: some value in the range beyond the bound).
pub fn matches_printed(v: f64, text: &str, range: (f64, f64)) -> bool {
    let (lo, hi) = (range.0.min(v), range.1.max(v));
    let t = text.trim();
    if let Some(bound) = t.strip_prefix('<') {
        return bound.trim().parse::<f64>().is_ok_and(|b| lo < b);
    }
    if let Some(bound) = t.strip_prefix('>') {
        return bound.trim().parse::<f64>().is_ok_and(|b| hi > b);
    }
    let Ok(printed) = t.parse::<f64>() else {
        return false;
    };
    let decimals = t.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    let half_unit = 0.5 * 10f64.powi(-decimals) * (1.0 + 1e-9) + 1e-12;
    printed + half_unit >= lo && printed - half_unit <= hi
}
