//! The verdict: which candidates the data call for, each tested against the others.
//!
//! The parent module tests every candidate against "no effect". That cannot tell candidates
//! apart: when their signatures are nearly alike, whichever is the most flexible absorbs the
//! misfit and ranks first. Here a candidate is tested *given* another, an encompassing test
//! in score form (Davidson and MacKinnon 1981, Econometrica 49:781; Mizon and Richard 1986,
//! Econometrica 54:657). With the columns S in the model (the free parameters, and
//! candidates already added, each at its least-squares value), is column t still needed?
//!
//!   T(t | S) = (g . r)^2 / (g . g + n),   g = M_S ĵ_t,   M_S = I - X_S X_S^+,
//!
//! n the variance that the finite differences' noise adds to g . r: the parent module's n
//! with S's columns in place of the free parameters' (row covariances of every estimated
//! column, from the per-seed slopes). T is chi^2(1) when t adds nothing beyond S.
//!
//! The verdict, forward from the free parameters alone (S = X):
//! 1. the best identifiable candidate left by T(k | S); if it is not significant (Holm over
//!    the candidates left) stop;
//! 2. its rivals: every other candidate B left with T(best | S + B) not significant at
//!    alpha: B explains what the best explains. The test is uncorrected on purpose: a rival
//!    kept by mistake costs one measurement, a rival dropped by mistake names the wrong
//!    effect. Any rival makes the verdict `ambiguous` with the set {best} + rivals;
//! 3. no rival: the best joins S, and step 1 runs again, so a second effect is named only
//!    when it is needed beyond the first;
//! 4. the misfit left by S (with the first of an ambiguous set in it): |M_S r|^2, each row's
//!    e_i = (M_S r)_i taken to its normal score as sqrt(h_i) q(e_i / sqrt(h_i), nu_i), h_i =
//!    (M_S)_ii and nu_i the degrees of freedom of the row's standard error (a row's
//!    standard error estimated from a few runs gives its z Student's t tails:
//!    [`crate::compare::welch`]), against chi^2(m - rank X_S). Significant:
//!    `none_of_the_candidates` (what is left is no candidate's signature), before any
//!    ambiguity; otherwise `ambiguous`, `effect` with the candidates added, or `no_effect`.
//!
//! Everything is linearised at the model's point: a candidate's "least-squares value" is a
//! one-step estimate from its finite difference, and the misfit is what that linear model
//! leaves. `tilth fit` then fits the verdict's effects on simulations and tests its chi^2.

use super::{Candidate, JacobianNoise, ResidualMaker, Score, holm_adjust};
use crate::compare::welch::normal_score;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// What the data call for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// The candidates in `effects`, each needed beyond the others and no rival.
    Effect,
    /// The first candidate has rivals the data cannot tell from it: `ambiguous` lists them.
    Ambiguous,
    /// What is left after the free parameters (and any candidate needed) is significant and
    /// no candidate explains it.
    NoneOfTheCandidates,
    /// No candidate is needed and nothing significant is left: the free parameters and the
    /// noise explain the residuals.
    NoEffect,
}

/// An effect the verdict names, at its least-squares strength given the free parameters and
/// the other effects named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Named {
    pub name: String,
    pub strength: f64,
    /// Linear standard error of the strength (unit noise in the standardised residuals).
    pub standard_error: f64,
    /// T(name | free parameters and the effects named before it).
    pub statistic: f64,
    /// Holm-corrected over the candidates left at its step.
    pub p_value: f64,
}

/// One encompassing test: is `needed` still needed once `given` is in the model (with the
/// free parameters)?
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Encompassing {
    pub needed: String,
    pub given: String,
    pub statistic: f64,
    /// Uncorrected.
    pub p_value: f64,
}

/// The misfit the named effects and the free parameters leave (linearised).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Misfit {
    /// |M_S r|^2 in normal scores (equal to it when every row's standard error is exact).
    pub chi2: f64,
    /// What the free parameters' finite-difference noise would leak into it if their shift
    /// b were real: sum_i b'C_i b (m - q) / m. Reported, not taken off: b is fitted with
    /// the noisy columns, so when they are noise b is too, and taking the leak off would
    /// hide a real misfit.
    pub noise: f64,
    pub dof: usize,
    /// P(chi^2_dof > chi2).
    pub p_value: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Verdict {
    pub verdict: Kind,
    /// The effects named, in the order they were added (empty unless `effect`; for
    /// `ambiguous` and `none_of_the_candidates`, those needed before the ambiguity or the
    /// misfit).
    pub effects: Vec<Named>,
    /// The candidates the data cannot tell apart (`ambiguous` only), the first best.
    pub ambiguous: Vec<String>,
    /// Among the candidates significant on their own: each tested given each other.
    pub encompassing: Vec<Encompassing>,
    pub misfit: Misfit,
    pub alpha: f64,
}

/// The free parameters' and the candidates' columns with their estimates' row covariances.
struct Columns {
    /// m x (p + K): X, then each candidate's sensitivity.
    values: DMatrix<f64>,
    /// Per row, (p + K) x (p + K); empty when exact.
    cov: Vec<DMatrix<f64>>,
    params: usize,
}

impl Columns {
    fn new(x: &DMatrix<f64>, noise: &JacobianNoise, candidates: &[Candidate]) -> Columns {
        let (m, p, k) = (x.nrows(), x.ncols(), candidates.len());
        let mut values = DMatrix::zeros(m, p + k);
        values.columns_mut(0, p).copy_from(x);
        for (c, cand) in candidates.iter().enumerate() {
            values.set_column(p + c, &DVector::from_column_slice(&cand.sensitivity));
        }
        let cov = (0..m)
            .map(|i| {
                let mut v = DMatrix::zeros(p + k, p + k);
                if let Some(c) = noise.cov.get(i) {
                    v.view_mut((0, 0), (p, p)).copy_from(c);
                }
                if let Some(c) = noise.cross.get(i) {
                    v.view_mut((p, 0), (k, p)).copy_from(c);
                    v.view_mut((0, p), (p, k)).copy_from(&c.transpose());
                }
                if let Some(c) = noise.among.get(i) {
                    v.view_mut((p, p), (k, k)).copy_from(c);
                }
                // The candidates' own variances as the score tests used them.
                for (c, cand) in candidates.iter().enumerate() {
                    v[(p + c, p + c)] = cand.sensitivity_var.get(i).copied().unwrap_or(0.0);
                }
                v
            })
            .collect();
        Columns {
            values,
            cov,
            params: p,
        }
    }

    fn select(&self, base: &[usize]) -> DMatrix<f64> {
        self.values.select_columns(base)
    }

    /// T(t | base), its uncorrected p-value and the one-step value of t.
    fn conditional(&self, r: &DVector<f64>, base: &[usize], t: usize) -> (f64, f64, f64) {
        let xs = self.select(base);
        let maker = ResidualMaker::new(&xs);
        let mr = maker.apply(r);
        let g = maker.apply(&self.values.column(t).into_owned());
        let gg = g.dot(&g);
        if gg <= 1e-12 * self.values.column(t).norm_squared().max(1e-300) {
            return (0.0, 1.0, 0.0);
        }
        let b = maker.coefficients(r).unwrap_or_else(|| DVector::zeros(0));
        let noise: f64 = (0..r.len())
            .map(|i| {
                let Some(v) = self.cov.get(i) else {
                    return 0.0;
                };
                let own = mr[i] * mr[i] * v[(t, t)];
                let (with, along) = base.iter().enumerate().fold((0.0, 0.0), |acc, (a, &ca)| {
                    let with = acc.0 + v[(t, ca)] * b[a];
                    let along: f64 = base
                        .iter()
                        .enumerate()
                        .map(|(c, &cc)| b[a] * v[(ca, cc)] * b[c])
                        .sum();
                    (with, acc.1 + along)
                });
                own - 2.0 * mr[i] * g[i] * with + g[i] * g[i] * along
            })
            .sum();
        let gr = g.dot(r);
        let statistic = gr * gr / (gg + noise.max(0.0));
        (statistic, chi2_sf(statistic, 1.0), gr / gg)
    }

    fn misfit(&self, r: &DVector<f64>, base: &[usize], residual_dof: &[f64]) -> Misfit {
        let xs = self.select(base);
        let maker = ResidualMaker::new(&xs);
        let e = maker.apply(r);
        let chi2: f64 = (0..r.len())
            .map(|i| {
                let nu = residual_dof.get(i).copied().unwrap_or(f64::INFINITY);
                if nu.is_infinite() {
                    return e[i] * e[i];
                }
                let h = maker.apply(&DVector::from_fn(r.len(), |k, _| f64::from(k == i)))[i];
                if h <= 1e-12 {
                    return e[i] * e[i];
                }
                h * normal_score(e[i] / h.sqrt(), nu).powi(2)
            })
            .sum();
        let dof = r.len().saturating_sub(maker.rank());
        let b = maker.coefficients(r).unwrap_or_else(|| DVector::zeros(0));
        // E|M Ê b|^2 = sum_i b' C_i b times the share of each row M keeps, (m - q) / m.
        let leak: f64 = (0..r.len())
            .map(|i| {
                self.cov.get(i).map_or(0.0, |v| {
                    let vs = v.select_rows(base).select_columns(base);
                    b.dot(&(vs * &b))
                })
            })
            .sum::<f64>()
            * dof as f64
            / r.len().max(1) as f64;
        let p_value = if dof == 0 {
            1.0
        } else {
            chi2_sf(chi2, dof as f64)
        };
        Misfit {
            chi2,
            noise: leak,
            dof,
            p_value,
        }
    }

    /// Least-squares values of `base` and their linear standard errors (unit noise).
    fn estimates(&self, r: &DVector<f64>, base: &[usize]) -> Vec<(f64, f64)> {
        let xs = self.select(base);
        let b = ResidualMaker::new(&xs)
            .coefficients(r)
            .unwrap_or_else(|| DVector::zeros(0));
        let inv = (xs.transpose() * &xs).pseudo_inverse(1e-12).ok();
        (0..base.len())
            .map(|a| {
                let se = inv.as_ref().map_or(f64::NAN, |m| m[(a, a)].max(0.0).sqrt());
                (b[a], se)
            })
            .collect()
    }
}

fn chi2_sf(x: f64, dof: f64) -> f64 {
    ChiSquared::new(dof).expect("positive dof").sf(x)
}

/// The verdict on the residuals `residual` (standardised, each row's standard error with
/// `residual_dof` degrees of freedom; empty: all exact) given the free parameters'
/// Jacobian `jacobian`, its noise and the candidates, as [`super::score_tests`] takes them;
/// `scores` is its output (only identifiable candidates take part).
pub fn verdict(
    residual: &[f64],
    residual_dof: &[f64],
    jacobian: &DMatrix<f64>,
    noise: &JacobianNoise,
    candidates: &[Candidate],
    scores: &[Score],
    alpha: f64,
) -> Verdict {
    let cols = Columns::new(jacobian, noise, candidates);
    let r = DVector::from_column_slice(residual);
    let p = cols.params;
    let identifiable = |k: usize| {
        scores
            .iter()
            .any(|s| s.name == candidates[k].name && s.identifiable)
    };
    let mut left: Vec<usize> = (0..candidates.len()).filter(|&k| identifiable(k)).collect();
    let mut base: Vec<usize> = (0..p).collect();
    let mut added: Vec<(usize, f64, f64)> = vec![];
    let mut ambiguous: Vec<String> = vec![];
    // The first of an ambiguous set: the misfit is judged with it in.
    let mut first_of_ambiguous = None;

    let encompassing = encompassing_tests(&cols, &r, &left, candidates, alpha);

    while !left.is_empty() {
        let tests: Vec<(f64, f64)> = left
            .iter()
            .map(|&k| {
                let (t, pr, _) = cols.conditional(&r, &base, p + k);
                (t, pr)
            })
            .collect();
        let corrected = holm_adjust(&tests.iter().map(|t| t.1).collect::<Vec<_>>());
        let best = (0..left.len())
            .max_by(|&a, &b| tests[a].0.total_cmp(&tests[b].0))
            .expect("non-empty");
        if corrected[best] >= alpha {
            break;
        }
        let k = left[best];
        let rivals: Vec<usize> = left
            .iter()
            .copied()
            .filter(|&b| b != k)
            .filter(|&b| {
                let mut s = base.clone();
                s.push(p + b);
                cols.conditional(&r, &s, p + k).1 >= alpha
            })
            .collect();
        if !rivals.is_empty() {
            ambiguous.push(candidates[k].name.clone());
            ambiguous.extend(rivals.iter().map(|&b| candidates[b].name.clone()));
            first_of_ambiguous = Some(p + k);
            break;
        }
        added.push((k, tests[best].0, corrected[best]));
        base.push(p + k);
        left.remove(best);
    }

    let estimates = cols.estimates(&r, &base);
    let effects: Vec<Named> = added
        .iter()
        .enumerate()
        .map(|(n, &(k, statistic, p_value))| Named {
            name: candidates[k].name.clone(),
            strength: estimates[p + n].0,
            standard_error: estimates[p + n].1,
            statistic,
            p_value,
        })
        .collect();
    let with_best: Vec<usize> = base.iter().copied().chain(first_of_ambiguous).collect();
    let misfit = cols.misfit(&r, &with_best, residual_dof);
    Verdict {
        verdict: kind(&misfit, &ambiguous, &effects, alpha),
        effects,
        ambiguous,
        encompassing,
        misfit,
        alpha,
    }
}

/// Among the candidates `left` significant on their own (given the free parameters alone),
/// each tested given each other one.
fn encompassing_tests(
    cols: &Columns,
    r: &DVector<f64>,
    left: &[usize],
    candidates: &[Candidate],
    alpha: f64,
) -> Vec<Encompassing> {
    let p = cols.params;
    let base: Vec<usize> = (0..p).collect();
    let alone: Vec<(usize, f64)> = left
        .iter()
        .map(|&k| (k, cols.conditional(r, &base, p + k).1))
        .collect();
    let contenders: Vec<usize> = alone
        .iter()
        .filter(|(_, pr)| *pr < alpha)
        .map(|(k, _)| *k)
        .collect();
    let mut encompassing = vec![];
    for &a in &contenders {
        for &b in &contenders {
            if a != b {
                let mut s = base.clone();
                s.push(p + b);
                let (statistic, p_value, _) = cols.conditional(r, &s, p + a);
                encompassing.push(Encompassing {
                    needed: candidates[a].name.clone(),
                    given: candidates[b].name.clone(),
                    statistic,
                    p_value,
                });
            }
        }
    }
    encompassing
}

/// The verdict's kind. A significant misfit comes first: when the best single candidate (of
/// an ambiguous set, the first) leaves one, what is left is none of them, whatever they
/// cannot be told apart on.
fn kind(misfit: &Misfit, ambiguous: &[String], effects: &[Named], alpha: f64) -> Kind {
    if misfit.p_value < alpha {
        Kind::NoneOfTheCandidates
    } else if !ambiguous.is_empty() {
        Kind::Ambiguous
    } else if effects.is_empty() {
        Kind::NoEffect
    } else {
        Kind::Effect
    }
}

#[cfg(test)]
mod tests;
