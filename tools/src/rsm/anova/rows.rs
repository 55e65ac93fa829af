//! The ANOVA table's rows: each term's Type III sum of squares, the model, the curvature
//! indicator, lack of fit and pure error, each tested by F.

use super::{SourceRow, TermRow, matrix};
use crate::rsm::ols::{Ols, ols};
use crate::rsm::terms::Term;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// Type III sums of squares: what the residual sum of squares rises by when terms are left
/// out of the model, SS = SSE(reduced) - SSE(full), never below 0.
pub(super) struct PartialSums<'a> {
    pub(super) z: &'a [Vec<f64>],
    pub(super) y: &'a [f64],
    pub(super) terms: &'a [Term],
    /// The corrected total sum of squares: the reduced model's SSE when it cannot be fitted.
    pub(super) sst: f64,
    /// SSE of the full model.
    pub(super) sse: f64,
}

impl PartialSums<'_> {
    /// The sum of squares of the terms at indices `drop`, together.
    fn without(&self, drop: &[usize]) -> f64 {
        let keep: Vec<Term> = self
            .terms
            .iter()
            .enumerate()
            .filter(|(k, _)| !drop.contains(k))
            .map(|(_, t)| *t)
            .collect();
        let reduced = ols(&matrix(self.z, &keep), self.y).map_or(self.sst, |o| o.sse);
        (reduced - self.sse).max(0.0)
    }
}

/// F test of a row against the residual: F = (SS / df) / MS_res on (df, df_res) degrees of
/// freedom; no F when MS_res is missing or zero.
pub(super) struct ResidualTest {
    pub(super) mse: Option<f64>,
    pub(super) dfe: usize,
}

impl ResidualTest {
    fn f(&self, ss: f64, df: usize) -> Option<f64> {
        self.mse.filter(|m| *m > 0.0).map(|m| ss / df as f64 / m)
    }

    /// A source row with `ss` on `df` degrees of freedom, tested.
    fn row(&self, ss: f64, df: usize) -> SourceRow {
        let f = self.f(ss, df);
        SourceRow {
            sum_sq: ss,
            df,
            mean_sq: (df > 0).then(|| ss / df as f64),
            f,
            p: f.and_then(|f| p_value(f, df, self.dfe)),
        }
    }
}

/// Each term's row: coefficient, standard error sqrt(MS_res (X'X)^-1_kk), t, and its Type III
/// sum of squares tested on one degree of freedom.
pub(super) fn term_rows(
    full: &Ols,
    terms: &[Term],
    names: &[String],
    partial: &PartialSums,
    test: &ResidualTest,
) -> Vec<TermRow> {
    let sst = partial.sst;
    terms
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let ss = partial.without(&[k]);
            let coefficient = full.coef[k + 1];
            let se = test.mse.map(|m| (m * full.xtx_inv[(k + 1, k + 1)]).sqrt());
            let f = test.f(ss, 1);
            TermRow {
                name: t.name(names),
                coefficient,
                std_error: se,
                t: se.filter(|s| *s > 0.0).map(|s| coefficient / s),
                sum_sq: ss,
                df: 1,
                mean_sq: ss,
                f,
                p: f.and_then(|f| p_value(f, 1, test.dfe)),
                contribution_pct: if sst > 0.0 { 100.0 * ss / sst } else { 0.0 },
            }
        })
        .collect()
}

/// The model's row and the curvature indicator's, if it is a term. The model's sum of
/// squares is what its terms explain beyond the mean (and beyond the curvature indicator
/// when there is one).
pub(super) fn model_rows(
    terms: &[Term],
    rows: &[TermRow],
    partial: &PartialSums,
    test: &ResidualTest,
) -> (SourceRow, Option<SourceRow>) {
    let curv_idx = terms.iter().position(|t| *t == Term::Curvature);
    let model_idx: Vec<usize> = (0..terms.len()).filter(|k| Some(*k) != curv_idx).collect();
    let model_ss = match curv_idx {
        Some(_) => partial.without(&model_idx),
        None => (partial.sst - partial.sse).max(0.0),
    };
    let model = test.row(model_ss, model_idx.len());
    let curvature = curv_idx.map(|k| test.row(rows[k].sum_sq, 1));
    (model, curvature)
}

/// Pure error: the scatter of the responses within groups of identical coded settings, as
/// (degrees of freedom, sum of squares about each group's mean).
fn pure_error(z: &[Vec<f64>], y: &[f64]) -> (usize, f64) {
    let mut groups: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    for (zr, &yr) in z.iter().zip(y) {
        match groups
            .iter_mut()
            .find(|(g, _)| g.iter().zip(zr).all(|(a, b)| (a - b).abs() < 1e-9))
        {
            Some((_, ys)) => ys.push(yr),
            None => groups.push((zr.clone(), vec![yr])),
        }
    }
    let pe_df: usize = groups.iter().map(|(_, ys)| ys.len() - 1).sum();
    let pe_ss: f64 = groups
        .iter()
        .map(|(_, ys)| {
            let m = ys.iter().sum::<f64>() / ys.len() as f64;
            ys.iter().map(|v| (v - m).powi(2)).sum::<f64>()
        })
        .sum();
    (pe_df, pe_ss)
}

/// The lack-of-fit and pure-error rows: the residual split into pure error and the rest,
/// F = MS_lof / MS_pe. Neither when there is no pure error or nothing else in the residual
/// (a note says which).
pub(super) fn lack_of_fit(
    z: &[Vec<f64>],
    y: &[f64],
    sse: f64,
    dfe: usize,
    notes: &mut Vec<String>,
) -> (Option<SourceRow>, Option<SourceRow>) {
    let (pe_df, pe_ss) = pure_error(z, y);
    if pe_df > 0 && dfe > pe_df {
        let lof_df = dfe - pe_df;
        let lof_ss = (sse - pe_ss).max(0.0);
        let pe_ms = pe_ss / pe_df as f64;
        let f = (pe_ms > 0.0).then(|| lof_ss / lof_df as f64 / pe_ms);
        (
            Some(SourceRow {
                sum_sq: lof_ss,
                df: lof_df,
                mean_sq: Some(lof_ss / lof_df as f64),
                f,
                p: f.and_then(|f| p_value(f, lof_df, pe_df)),
            }),
            Some(SourceRow {
                sum_sq: pe_ss,
                df: pe_df,
                mean_sq: Some(pe_ms),
                f: None,
                p: None,
            }),
        )
    } else {
        notes.push(if pe_df == 0 {
            "no replicated settings: pure error and lack of fit cannot be estimated".to_string()
        } else {
            "every residual degree of freedom is pure error: lack of fit cannot be tested"
                .to_string()
        });
        (None, None)
    }
}

/// P(F(d1, d2) > f); none without degrees of freedom or for an infinite or NaN f.
fn p_value(f: f64, d1: usize, d2: usize) -> Option<f64> {
    if d1 == 0 || d2 == 0 || !f.is_finite() {
        return None;
    }
    let dist = FisherSnedecor::new(d1 as f64, d2 as f64).ok()?;
    Some(dist.sf(f.max(0.0)))
}
