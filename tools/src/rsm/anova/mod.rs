//! Regression and analysis of variance as Design-Expert reports it.
//!
//! The model is fitted by least squares in coded units. Each term's sum of squares is its
//! Type III (partial) sum: the rise of the residual sum of squares when that term alone is
//! left out. F = MS_term / MS_residual and p = P(F(1, df_res) > F). Lack of fit compares the
//! residual with the pure error of replicated settings. Goodness of fit:
//! - R^2 = 1 - SS_res / SS_total, adjusted R^2 = 1 - (SS_res / df_res) / (SS_total / (n - 1));
//! - predicted R^2 = 1 - PRESS / SS_total, PRESS = sum (e_i / (1 - h_ii))^2 (Allen 1974);
//! - adequate precision = (max y_hat - min y_hat) / sqrt(p MS_res / n), the signal to the
//!   average prediction standard error over the design points (Design-Expert; above 4 is
//!   adequate);
//! - C.V. % = 100 sqrt(MS_res) / mean(y).
//!
//! References: Montgomery, *Design and Analysis of Experiments* (8th ed., 2013), ch. 6, 10, 11;
//! Myers, Montgomery & Anderson-Cook, *Response Surface Methodology* (4th ed., 2016).

mod goodness;
mod rows;

use super::ols::{Ols, full_rank, ols};
use super::terms::{Order, Term, is_centre};
use super::{Coding, Data, RsmError};
use goodness::goodness;
use nalgebra::DMatrix;
use rows::{PartialSums, ResidualTest, lack_of_fit, model_rows, term_rows};
use serde::Serialize;

/// What to fit.
#[derive(Debug, Clone, Copy)]
pub struct FitOptions {
    pub order: Order,
    /// Add the curvature indicator of the centre points (a screening design's check that a
    /// plane is enough).
    pub curvature: bool,
    /// Backward elimination: drop the least significant term while its p-value exceeds this
    /// (Design-Expert's default alpha out is 0.1), keeping the model hierarchical.
    pub backward: Option<f64>,
}

/// One model term's row.
#[derive(Debug, Clone, Serialize)]
pub struct TermRow {
    pub name: String,
    /// Coefficient in coded units.
    pub coefficient: f64,
    pub std_error: Option<f64>,
    /// Coefficient / standard error (the "standardized effect" of a Pareto chart).
    pub t: Option<f64>,
    pub sum_sq: f64,
    pub df: usize,
    pub mean_sq: f64,
    pub f: Option<f64>,
    pub p: Option<f64>,
    /// Share of the corrected total sum of squares, %.
    pub contribution_pct: f64,
}

/// A source row without a coefficient (model, curvature, residual, lack of fit...).
#[derive(Debug, Clone, Serialize)]
pub struct SourceRow {
    pub sum_sq: f64,
    pub df: usize,
    pub mean_sq: Option<f64>,
    pub f: Option<f64>,
    pub p: Option<f64>,
}

/// The fit, its ANOVA table and its statistics.
#[derive(Debug, Clone, Serialize)]
pub struct Anova {
    pub source: String,
    pub response: String,
    pub factors: Vec<String>,
    pub order: Order,
    pub runs: usize,
    /// Each factor's low and high levels (coded -1 and +1).
    pub coding: Coding,
    pub intercept: f64,
    pub terms: Vec<TermRow>,
    /// The model's terms together (without the curvature indicator, as Design-Expert).
    pub model: SourceRow,
    pub curvature: Option<SourceRow>,
    pub residual: SourceRow,
    pub lack_of_fit: Option<SourceRow>,
    pub pure_error: Option<SourceRow>,
    pub total: SourceRow,
    pub r2: f64,
    pub adj_r2: Option<f64>,
    pub pred_r2: Option<f64>,
    pub press: Option<f64>,
    pub adeq_precision: Option<f64>,
    pub std_dev: Option<f64>,
    pub mean: f64,
    pub cv_pct: Option<f64>,
    /// The fitted equation in coded units, and in real units (without the curvature term).
    pub equation_coded: String,
    pub equation_real: String,
    /// Real-unit coefficients by term name (`intercept` first).
    pub real_coefficients: Vec<(String, f64)>,
    /// Terms removed by backward elimination, in order, with their p-values then.
    pub removed: Vec<(String, f64)>,
    /// Things the reader should know (no pure error, a low predicted R^2...).
    pub notes: Vec<String>,
    /// Per run: actual, predicted, residual, leverage (Design-Expert's diagnostics table).
    pub diagnostics: Vec<RunDiagnostic>,
    #[serde(skip)]
    pub(crate) fit: FitState,
}

/// One run's fit.
#[derive(Debug, Clone, Serialize)]
pub struct RunDiagnostic {
    /// The run's factor settings, real units, in the order of `factors`.
    pub settings: Vec<f64>,
    pub actual: f64,
    pub predicted: f64,
    pub residual: f64,
    pub leverage: f64,
}

/// What prediction needs.
#[derive(Debug, Clone, Default)]
pub(crate) struct FitState {
    pub(crate) terms: Vec<Term>,
    /// Intercept first, then the terms.
    pub(crate) coef: Vec<f64>,
    pub(crate) xtx_inv: Option<DMatrix<f64>>,
    pub(crate) mse: Option<f64>,
    pub(crate) dfe: usize,
}

/// Fits `data` with `options` and analyses the fit.
pub fn fit(data: &Data, options: FitOptions) -> Result<Anova, RsmError> {
    let k = data.factors.len();
    let mut terms = Term::all(options.order, k);
    let z = data.coded();
    if options.curvature {
        if !z.iter().any(|r| is_centre(r)) {
            return Err(RsmError::Request(format!(
                "{}: --centre-curvature needs centre points (runs with every factor at its centre); there are none",
                data.source
            )));
        }
        terms.push(Term::Curvature);
    }
    // Coefficients plus one residual degree of freedom, without which nothing can be tested.
    let need = terms.len() + 2;
    if data.y.len() < need {
        return Err(RsmError::TooFewRuns {
            file: data.source.clone(),
            runs: data.y.len(),
            model: options.order.name().into(),
            factors: k,
            terms: terms.len() + 1,
            need,
        });
    }
    check_aliasing(data, &z, &terms)?;
    let mut removed = Vec::new();
    loop {
        let a = analyse(data, &z, &terms, removed.clone())?;
        let Some(alpha) = options.backward else {
            return Ok(a);
        };
        match weakest_removable(&terms, &a) {
            Some((idx, p)) if p > alpha => {
                removed.push((a.terms[idx].name.clone(), p));
                terms.remove(idx);
            }
            _ => return Ok(a),
        }
    }
}

fn matrix(z: &[Vec<f64>], terms: &[Term]) -> DMatrix<f64> {
    DMatrix::from_fn(z.len(), terms.len() + 1, |r, c| {
        if c == 0 {
            1.0
        } else {
            terms[c - 1].value(&z[r])
        }
    })
}

fn check_aliasing(data: &Data, z: &[Vec<f64>], terms: &[Term]) -> Result<(), RsmError> {
    if full_rank(&matrix(z, terms)) {
        return Ok(());
    }
    for n in 1..=terms.len() {
        if !full_rank(&matrix(z, &terms[..n])) {
            return Err(RsmError::Aliased {
                file: data.source.clone(),
                term: terms[n - 1].name(&data.factors),
            });
        }
    }
    Ok(())
}

/// The removable term with the largest p-value: not the curvature indicator, and not a main
/// effect that an interaction or square still contains (hierarchy).
fn weakest_removable(terms: &[Term], a: &Anova) -> Option<(usize, f64)> {
    let needed = |i: usize| {
        terms.iter().any(|t| {
            matches!(t, Term::Interaction(..) | Term::Square(_)) && t.factors().contains(&i)
        })
    };
    terms
        .iter()
        .enumerate()
        .filter(|(_, t)| match t {
            Term::Curvature => false,
            Term::Linear(i) => !needed(*i),
            _ => true,
        })
        .filter_map(|(k, _)| a.terms[k].p.map(|p| (k, p)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

fn analyse(
    data: &Data,
    z: &[Vec<f64>],
    terms: &[Term],
    removed: Vec<(String, f64)>,
) -> Result<Anova, RsmError> {
    let names = &data.factors;
    let y = &data.y;
    let n = y.len();
    let x = matrix(z, terms);
    let full: Ols = ols(&x, y).ok_or_else(|| RsmError::Aliased {
        file: data.source.clone(),
        term: "the model".into(),
    })?;
    let p = terms.len() + 1;
    let dfe = n - p;
    let mse = (dfe > 0).then(|| full.sse / dfe as f64);
    let mean = y.iter().sum::<f64>() / n as f64;
    let sst: f64 = y.iter().map(|v| (v - mean).powi(2)).sum();
    let mut notes = Vec::new();

    let partial = PartialSums {
        z,
        y,
        terms,
        sst,
        sse: full.sse,
    };
    let test = ResidualTest { mse, dfe };
    let rows = term_rows(&full, terms, names, &partial, &test);
    let (model, curvature) = model_rows(terms, &rows, &partial, &test);
    let (lack_of_fit, pure_error) = lack_of_fit(z, y, full.sse, dfe, &mut notes);
    if dfe == 0 {
        notes.push(
            "no residual degrees of freedom: the model goes through every run; F and p-values cannot be computed"
                .into(),
        );
    }
    let fit = goodness(&full, y, p, mse, mean, sst, &mut notes);

    let state = FitState {
        terms: terms.to_vec(),
        coef: full.coef.clone(),
        xtx_inv: Some(full.xtx_inv.clone()),
        mse,
        dfe,
    };
    let real = super::equation::real_coefficients(&state, &data.coding, names);
    Ok(Anova {
        source: data.source.clone(),
        response: data.response.clone(),
        factors: names.clone(),
        order: order_of(terms),
        runs: n,
        coding: data.coding.clone(),
        intercept: full.coef[0],
        equation_coded: super::equation::coded(&data.response, &state, names),
        equation_real: super::equation::format(&data.response, &real),
        real_coefficients: real,
        terms: rows,
        model,
        curvature,
        residual: SourceRow {
            sum_sq: full.sse,
            df: dfe,
            mean_sq: mse,
            f: None,
            p: None,
        },
        lack_of_fit,
        pure_error,
        total: SourceRow {
            sum_sq: sst,
            df: n - 1,
            mean_sq: None,
            f: None,
            p: None,
        },
        r2: fit.r2,
        adj_r2: fit.adj_r2,
        pred_r2: fit.pred_r2,
        press: fit.press,
        adeq_precision: fit.adeq_precision,
        std_dev: fit.std_dev,
        mean,
        cv_pct: fit.cv_pct,
        removed,
        notes,
        diagnostics: run_diagnostics(data, &full),
        fit: state,
    })
}

/// Each run's settings, response, fitted value, residual and leverage.
fn run_diagnostics(data: &Data, full: &Ols) -> Vec<RunDiagnostic> {
    data.y
        .iter()
        .zip(&data.x)
        .zip(&full.fitted)
        .zip(&full.leverage)
        .map(|(((a, x), f), h)| RunDiagnostic {
            settings: x.clone(),
            actual: *a,
            predicted: *f,
            residual: a - f,
            leverage: *h,
        })
        .collect()
}

/// The highest order among the terms (after elimination the model may be partial).
fn order_of(terms: &[Term]) -> Order {
    if terms.iter().any(|t| matches!(t, Term::Square(_))) {
        Order::Quadratic
    } else if terms.iter().any(|t| matches!(t, Term::Interaction(..))) {
        Order::TwoFi
    } else {
        Order::Linear
    }
}

impl Anova {
    /// The fitted response at coded settings `z` (the curvature indicator off: the surface).
    pub fn predict_coded(&self, z: &[f64]) -> f64 {
        let s = &self.fit;
        s.coef[0]
            + s.terms
                .iter()
                .zip(&s.coef[1..])
                .map(|(t, b)| match t {
                    Term::Curvature => 0.0,
                    t => b * t.value(z),
                })
                .sum::<f64>()
    }

    /// The fitted response at real settings `x`.
    pub fn predict(&self, x: &[f64]) -> f64 {
        self.predict_coded(&self.coding.code(x))
    }

    /// Standard error of the fitted mean at coded settings `z`: sqrt(MS_res x0' (X'X)^-1 x0).
    pub fn mean_std_error(&self, z: &[f64]) -> Option<f64> {
        let s = &self.fit;
        let (inv, m) = (s.xtx_inv.as_ref()?, s.mse?);
        let mut x0 = vec![1.0];
        x0.extend(s.terms.iter().map(|t| match t {
            Term::Curvature => 0.0,
            t => t.value(z),
        }));
        let v = nalgebra::DVector::from_vec(x0);
        Some((m * (v.transpose() * inv * &v)[(0, 0)]).sqrt())
    }

    /// Residual degrees of freedom.
    pub fn residual_df(&self) -> usize {
        self.fit.dfe
    }

    /// Gradient of the fitted surface in coded units at `z`.
    pub fn gradient_coded(&self, z: &[f64]) -> Vec<f64> {
        let s = &self.fit;
        let mut g = vec![0.0; z.len()];
        for (t, b) in s.terms.iter().zip(&s.coef[1..]) {
            match *t {
                Term::Linear(i) => g[i] += b,
                Term::Interaction(i, j) => {
                    g[i] += b * z[j];
                    g[j] += b * z[i];
                }
                Term::Square(i) => g[i] += 2.0 * b * z[i],
                Term::Curvature => {}
            }
        }
        g
    }
}
