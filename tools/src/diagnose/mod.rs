//! Which missing physical effect explains a model's residuals: a score (Lagrange-multiplier)
//! test per candidate, after removing what the model's own free parameters can absorb.
//!
//! Everything is standardised by each measurement's noise: residuals r_i = (measured_i -
//! simulated_i) / sigma_i, the model's Jacobian X (m x p, d simulated_i / d beta_j / sigma_i)
//! and each candidate's sensitivity j_k (d simulated_i / d theta_k / sigma_i, per unit of its
//! strength theta_k, where theta_k = 0 is the model as it is). With M = I - X X^+ the
//! residual maker of the free parameters (recalibrating them removes X's span):
//!
//! - g_k = M j_k, the part of the candidate's signature that the free parameters cannot
//!   mimic;
//! - score statistic S_k = (g_k . r)^2 / (g_k . g_k + n_k), chi^2 with 1 degree of freedom
//!   when the candidate is absent; n_k is the variance that the finite differences' own
//!   noise adds to g_k . r (below);
//! - p-value corrected for K candidates by Holm's step-down method;
//! - strength theta_k = (g_k . r) / (g_k . g_k), the one-step estimate;
//! - predicted drop of the sum of squared standardised residuals: S_k (from |M r|^2 to
//!   |M r|^2 - S_k);
//! - identifiable when |g_k| / |j_k| >= [`MIN_DISTINCT`] (the free parameters cannot
//!   reproduce at least that fraction of its signature) and |g_k| > 0; otherwise the
//!   candidate is reported as absorbed, never as a discovery.
//!
//! The finite differences are noisy (runs of chaotic grains), and their noise enters g_k . r
//! twice. With the estimates ĵ_k = j_k + d_k and X̂ = X + E, residuals r = X b + eps when the
//! candidate is absent (b: what recalibrating the free parameters would shift), and M̂ the
//! residual maker of X̂ (M̂ X̂ = 0, so M̂ X b = -M̂ E b exactly):
//!
//!   ĵ_k' M̂ r = ĝ_k' eps + d_k' M̂ r - ĝ_k' E b.
//!
//! The first term has variance ĝ_k . ĝ_k. With each row's estimates independent of the
//! residuals' runs (other seeds) and of other rows (other runs), the other two add
//!
//!   n_k = sum_i [ (M r)_i^2 v_ki - 2 (M r)_i g_ki (c_ki . b) + g_ki^2 (b' C_i b) ],
//!
//! v_ki the variance of ĵ_ki, C_i (p x p) the covariance of row i of X̂, c_ki that of ĵ_ki
//! with it (both are differences against the same runs), each estimated from the per-seed
//! slopes, and b = X̂^+ r. The first term alone is the candidate's own noise. The others are
//! the free parameters' noise: it matters when their recalibration is large and their steps
//! are short, and a statistic without it is too large then: an absorbable misfit leaks
//! through a noisy X̂ into every candidate (`tilth fit` takes the same noise off J'J,
//! `runner/src/study/fit/jacobian_noise.rs`).
//!
//! Reference: Rao (1948), score tests; Engle (1984), "Wald, likelihood ratio, and Lagrange
//! multiplier tests in econometrics", Handbook of Econometrics II, ch. 13; Holm (1979),
//! Scand. J. Statist. 6:65.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

pub mod discriminate;
pub mod nonnested;
pub mod verdict;

/// Below this fraction of its signature left after the free parameters, a candidate is
/// confounded with them.
pub const MIN_DISTINCT: f64 = 0.1;

/// Two identifiable candidates whose signatures, after what the free parameters absorb,
/// point this close to the same way (|cos| of the angle between g_a and g_b) are reported
/// as alike: the data cannot rank one above the other with confidence, however
/// significant each is. At 0.8 the part of one that the other cannot mimic is 0.6 of it.
pub const ALIKE_COSINE: f64 = 0.8;

/// One candidate's standardised sensitivity.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    pub name: String,
    /// d simulated_i / d theta / sigma_i, one per measurement row.
    pub sensitivity: Vec<f64>,
    /// Variance of each sensitivity estimate (standardised likewise; empty or zeros when
    /// exact). Finite differences of noisy simulations are noisy: this noise enters the
    /// score's variance, so that it is not mistaken for an effect.
    pub sensitivity_var: Vec<f64>,
}

/// The noise of the free parameters' estimated Jacobian X̂, row by row, standardised as X̂
/// is: `cov[i]` (p x p) the covariance of row i's slopes, `cross[i]` (K x p) that of each
/// candidate's estimated sensitivity (in the order given to [`score_tests`]) with them.
/// `among[i]` (K x K) the covariance of the candidates' estimates with each other (all are
/// differences against the same runs). Empty: X̂ is exact.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct JacobianNoise {
    pub cov: Vec<DMatrix<f64>>,
    pub cross: Vec<DMatrix<f64>>,
    pub among: Vec<DMatrix<f64>>,
}

impl JacobianNoise {
    /// From the per-seed slopes, seeds in the same order everywhere: `params[p][i]` holds
    /// row i's per-seed slopes of free parameter p (standardised), `candidates[k][i]` those
    /// of candidate k. Each covariance is that of the mean over the R seeds: the sample
    /// covariance over R. A row with fewer than two seeds in any of them adds nothing.
    pub fn from_seeds(params: &[Vec<Vec<f64>>], candidates: &[Vec<Vec<f64>>]) -> JacobianNoise {
        let (p, k) = (params.len(), candidates.len());
        let rows = params.iter().chain(candidates).next().map_or(0, Vec::len);
        let mut out = JacobianNoise::default();
        for i in 0..rows {
            let all = params.iter().chain(candidates);
            let seeds = all.clone().next().map_or(0, |v| v[i].len());
            let complete = seeds >= 2 && all.clone().all(|v| v[i].len() == seeds);
            let (mut cov, mut cross) = (DMatrix::zeros(p, p), DMatrix::zeros(k, p));
            let mut among = DMatrix::zeros(k, k);
            if complete {
                let mean = |v: &[f64]| v.iter().sum::<f64>() / seeds as f64;
                let sample_cov = |a: &[f64], b: &[f64]| {
                    let (ma, mb) = (mean(a), mean(b));
                    let sum: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
                    sum / ((seeds - 1) * seeds) as f64
                };
                for a in 0..p {
                    for b in 0..p {
                        cov[(a, b)] = sample_cov(&params[a][i], &params[b][i]);
                    }
                    for c in 0..k {
                        cross[(c, a)] = sample_cov(&candidates[c][i], &params[a][i]);
                    }
                }
                for c in 0..k {
                    for d in 0..k {
                        among[(c, d)] = sample_cov(&candidates[c][i], &candidates[d][i]);
                    }
                }
            }
            out.cov.push(cov);
            out.cross.push(cross);
            out.among.push(among);
        }
        out
    }
}

/// Why a candidate cannot be tested.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Unidentified {
    /// The free parameters reproduce all but [`MIN_DISTINCT`] of its signature.
    Absorbed,
    /// What is left of its signature is no larger than the noise of its estimate
    /// (sum of the sensitivity variances): more replicates, or a larger step.
    Unmeasured,
}

/// The test of one candidate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Score {
    pub name: String,
    /// S = (g . r)^2 / (g . g + n), chi^2(1) when the candidate is absent; 0 when not
    /// identifiable.
    pub statistic: f64,
    /// The share of the score's variance, g . g + n, that the free parameters' noise brings
    /// (the terms of C and c in the module's formula): what the statistic lost to it; 0
    /// when not identifiable or when X̂ is exact.
    pub free_parameter_noise_share: f64,
    /// Uncorrected p-value.
    pub p_raw: f64,
    /// Holm-corrected p-value over all candidates.
    pub p_value: f64,
    /// One-step estimate of the strength (in the candidate's own unit).
    pub strength: f64,
    /// Predicted drop of the sum of squared standardised residuals.
    pub predicted_chi2_drop: f64,
    /// |M j| / |j|: the fraction of the signature the free parameters cannot mimic.
    pub distinct_fraction: f64,
    pub identifiable: bool,
    /// Why not, when not identifiable.
    pub unidentified: Option<Unidentified>,
    /// g theta: what adding the candidate at its estimated strength changes in the
    /// standardised residuals left after recalibration (zero when not identifiable).
    #[serde(skip)]
    pub fitted_change: Vec<f64>,
    /// Other identifiable candidates with signatures alike (|cos| >= [`ALIKE_COSINE`] after
    /// the free parameters), with the cosine: the data cannot tell these apart.
    pub alike: Vec<(String, f64)>,
    /// g = M j, the signature the free parameters leave.
    #[serde(skip)]
    pub signature: Vec<f64>,
}

/// The tests, best first (identifiable candidates by statistic, then the others).
pub fn score_tests(
    residual: &[f64],
    jacobian: &DMatrix<f64>,
    jacobian_noise: &JacobianNoise,
    candidates: &[Candidate],
) -> Vec<Score> {
    let m = residual.len();
    let r = DVector::from_column_slice(residual);
    let maker = ResidualMaker::new(jacobian);
    let mr = maker.apply(&r);
    let shift = maker.coefficients(&r);
    let mut scores: Vec<Score> = candidates
        .iter()
        .enumerate()
        .map(|(k, c)| {
            assert_eq!(
                c.sensitivity.len(),
                m,
                "{}: one sensitivity per row",
                c.name
            );
            let j = DVector::from_column_slice(&c.sensitivity);
            let g = maker.apply(&j);
            let (gg, jj) = (g.dot(&g), j.dot(&j));
            let distinct = if jj > 0.0 { (gg / jj).sqrt() } else { 0.0 };
            // Expected |M noise|^2 of the estimated sensitivity: (m - p)/m of its total.
            let p = jacobian.ncols().min(m) as f64;
            let noise_energy = c.sensitivity_var.iter().sum::<f64>() * (m as f64 - p) / m as f64;
            let reason = if jj > 0.0 && distinct < MIN_DISTINCT {
                Some(Unidentified::Absorbed)
            } else if gg <= noise_energy || gg == 0.0 {
                Some(Unidentified::Unmeasured)
            } else {
                None
            };
            let identifiable = reason.is_none();
            let (statistic, strength, free_parameter_noise_share) = if identifiable {
                let gr = g.dot(&r);
                let own: f64 = (0..m)
                    .map(|i| mr[i] * mr[i] * c.sensitivity_var.get(i).copied().unwrap_or(0.0))
                    .sum();
                let free: f64 = match &shift {
                    Some(b) => (0..m)
                        .map(|i| {
                            let along = |cov: &DMatrix<f64>| b.dot(&(cov * b));
                            let with = |cross: &DMatrix<f64>| cross.row(k).transpose().dot(b);
                            g[i] * g[i] * jacobian_noise.cov.get(i).map_or(0.0, along)
                                - 2.0 * mr[i] * g[i] * jacobian_noise.cross.get(i).map_or(0.0, with)
                        })
                        .sum(),
                    None => 0.0,
                };
                // Estimated from the same seeds, the whole of n is a sum of quadratic forms
                // of sample covariances, so not negative; the guard is for inputs that were
                // not estimated together.
                let noise = (own + free).max(0.0);
                (gr * gr / (gg + noise), gr / gg, free / (gg + noise))
            } else {
                (0.0, 0.0, 0.0)
            };
            // The upper tail itself, not 1 - cdf: that rounds every p below about 1e-16 to 0.
            let p_raw = if identifiable {
                ChiSquared::new(1.0).expect("1 df").sf(statistic)
            } else {
                1.0
            };
            Score {
                name: c.name.clone(),
                statistic,
                free_parameter_noise_share,
                p_raw,
                p_value: p_raw,
                strength,
                predicted_chi2_drop: statistic,
                distinct_fraction: distinct,
                identifiable,
                unidentified: reason,
                fitted_change: (&g * strength).iter().copied().collect(),
                alike: vec![],
                signature: g.iter().copied().collect(),
            }
        })
        .collect();
    holm(&mut scores);
    let n = scores.len();
    for a in 0..n {
        for b in 0..n {
            if a == b || !scores[a].identifiable || !scores[b].identifiable {
                continue;
            }
            let (ga, gb) = (&scores[a].signature, &scores[b].signature);
            let dot: f64 = ga.iter().zip(gb).map(|(x, y)| x * y).sum();
            let na: f64 = ga.iter().map(|x| x * x).sum::<f64>().sqrt();
            let nb: f64 = gb.iter().map(|x| x * x).sum::<f64>().sqrt();
            let cos = dot / (na * nb);
            if cos.abs() >= ALIKE_COSINE {
                let name = scores[b].name.clone();
                scores[a].alike.push((name, cos));
            }
        }
    }
    scores.sort_by(|a, b| {
        b.identifiable
            .cmp(&a.identifiable)
            .then(b.statistic.total_cmp(&a.statistic))
    });
    scores
}

/// M v = v - X X^+ v: what is left of v after least squares on the columns of X (through
/// the SVD, rank-revealing: a ridge of free parameters is fine). X is decomposed once.
pub(crate) struct ResidualMaker<'a> {
    x: &'a DMatrix<f64>,
    svd: Option<nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>>,
    tolerance: f64,
}

impl<'a> ResidualMaker<'a> {
    pub(crate) fn new(x: &'a DMatrix<f64>) -> Self {
        let svd = (x.ncols() > 0 && x.nrows() > 0).then(|| x.clone().svd(true, true));
        let smax = svd.as_ref().map_or(0.0, |s| {
            s.singular_values.iter().copied().fold(0.0, f64::max)
        });
        ResidualMaker {
            x,
            svd,
            tolerance: 1e-10 * smax.max(1e-300),
        }
    }

    pub(crate) fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        match self.coefficients(v) {
            None => v.clone(),
            Some(b) => v - self.x * b,
        }
    }

    /// The number of singular values above the tolerance: the columns' independent count.
    pub(crate) fn rank(&self) -> usize {
        self.svd.as_ref().map_or(0, |s| {
            s.singular_values
                .iter()
                .filter(|&&v| v > self.tolerance)
                .count()
        })
    }

    /// X^+ v (minimum norm where X's columns are confounded); None without columns.
    pub(crate) fn coefficients(&self, v: &DVector<f64>) -> Option<DVector<f64>> {
        let svd = self.svd.as_ref()?;
        Some(svd.solve(v, self.tolerance).expect("both factors computed"))
    }
}

/// The standardised residuals left after recalibrating the free parameters (linearised):
/// M r.
pub fn absorbed(residual: &[f64], jacobian: &DMatrix<f64>) -> Vec<f64> {
    ResidualMaker::new(jacobian)
        .apply(&DVector::from_column_slice(residual))
        .iter()
        .copied()
        .collect()
}

/// The recalibration that [`absorbed`] assumes: the least-squares change of each free
/// parameter, b = X^+ r (minimum norm where the parameters are confounded), in each
/// parameter's own unit (X's columns are per unit of the parameter). It is linear: a shift
/// far outside the range the sensitivities were measured over is an extrapolation, and the
/// residuals it predicts are not to be trusted.
pub fn recalibration(residual: &[f64], jacobian: &DMatrix<f64>) -> Vec<f64> {
    match ResidualMaker::new(jacobian).coefficients(&DVector::from_column_slice(residual)) {
        None => vec![0.0; jacobian.ncols()],
        Some(b) => b.iter().copied().collect(),
    }
}

/// Whether a free parameter's measured effect, column `x` of the Jacobian with estimate
/// variances `var`, stands above the noise of its own estimate (|x|^2 > sum var: the rule
/// that makes a candidate [`Unidentified::Unmeasured`]).
pub fn measurable(x: &[f64], var: &[f64]) -> bool {
    let xx: f64 = x.iter().map(|v| v * v).sum();
    xx > 0.0 && xx > var.iter().sum::<f64>()
}

/// The share of a measured column's |x|^2 that is its estimate's noise, sum var / |x|^2
/// (1 when |x| = 0). E|x|^2 = |x_true|^2 + sum var, so a least-squares shift along x is
/// shrunk towards zero by about this share (errors in variables: Fuller, Measurement Error
/// Models, 1987, sec. 1.1), and the part of the misfit it leaves is what a candidate alike
/// to the parameter would be credited with.
pub fn noise_share(x: &[f64], var: &[f64]) -> f64 {
    let xx: f64 = x.iter().map(|v| v * v).sum();
    if xx > 0.0 {
        (var.iter().sum::<f64>() / xx).min(1.0)
    } else {
        1.0
    }
}

/// Holm's step-down correction of `p_raw` into `p_value` (monotone, capped at 1).
fn holm(scores: &mut [Score]) {
    let raw: Vec<f64> = scores.iter().map(|s| s.p_raw).collect();
    for (s, p) in scores.iter_mut().zip(holm_adjust(&raw)) {
        s.p_value = p;
    }
}

/// Holm's step-down correction of raw p-values, in their order (monotone, capped at 1).
pub fn holm_adjust(raw: &[f64]) -> Vec<f64> {
    let k = raw.len();
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&a, &b| raw[a].total_cmp(&raw[b]));
    let mut out = vec![1.0; k];
    let mut running: f64 = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        running = running.max(((k - rank) as f64 * raw[i]).min(1.0));
        out[i] = running;
    }
    out
}

#[cfg(test)]
mod tests;
