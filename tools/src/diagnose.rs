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
//! - score statistic S_k = (g_k . r)^2 / (g_k . g_k + sum_i (M r)_i^2 v_ki), chi^2 with 1
//!   degree of freedom when the candidate is absent (r = M eps, eps ~ N(0, I)); v_ki is the
//!   variance of the estimated sensitivity j_ki (finite differences of noisy runs, which must
//!   be independent of r: other seeds than the runs that give the residuals);
//! - p-value corrected for K candidates by Holm's step-down method;
//! - strength theta_k = (g_k . r) / (g_k . g_k), the one-step estimate;
//! - predicted drop of the sum of squared standardised residuals: S_k (from |M r|^2 to
//!   |M r|^2 - S_k);
//! - identifiable when |g_k| / |j_k| >= [`MIN_DISTINCT`] (the free parameters cannot
//!   reproduce at least that fraction of its signature) and |g_k| > 0; otherwise the
//!   candidate is reported as absorbed, never as a discovery.
//!
//! Reference: Rao (1948), score tests; Engle (1984), "Wald, likelihood ratio, and Lagrange
//! multiplier tests in econometrics", Handbook of Econometrics II, ch. 13; Holm (1979),
//! Scand. J. Statist. 6:65.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ChiSquared, ContinuousCDF};

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
    /// S = (g . r)^2 / (g . g), chi^2(1) when the candidate is absent; 0 when not identifiable.
    pub statistic: f64,
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
    candidates: &[Candidate],
) -> Vec<Score> {
    let m = residual.len();
    let r = DVector::from_column_slice(residual);
    let maker = ResidualMaker::new(jacobian);
    let mr = maker.apply(&r);
    let mut scores: Vec<Score> = candidates
        .iter()
        .map(|c| {
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
            let (statistic, strength) = if identifiable {
                let gr = g.dot(&r);
                let noise: f64 = (0..m)
                    .map(|i| mr[i] * mr[i] * c.sensitivity_var.get(i).copied().unwrap_or(0.0))
                    .sum();
                (gr * gr / (gg + noise), gr / gg)
            } else {
                (0.0, 0.0)
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
struct ResidualMaker<'a> {
    x: &'a DMatrix<f64>,
    svd: Option<nalgebra::SVD<f64, nalgebra::Dyn, nalgebra::Dyn>>,
    tolerance: f64,
}

impl<'a> ResidualMaker<'a> {
    fn new(x: &'a DMatrix<f64>) -> Self {
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

    fn apply(&self, v: &DVector<f64>) -> DVector<f64> {
        match &self.svd {
            None => v.clone(),
            Some(svd) => {
                let b = svd.solve(v, self.tolerance).expect("both factors computed");
                v - self.x * b
            }
        }
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
    let maker = ResidualMaker::new(jacobian);
    match &maker.svd {
        None => vec![0.0; jacobian.ncols()],
        Some(svd) => svd
            .solve(&DVector::from_column_slice(residual), maker.tolerance)
            .expect("both factors computed")
            .iter()
            .copied()
            .collect(),
    }
}

/// Whether a free parameter's measured effect, column `x` of the Jacobian with estimate
/// variances `var`, stands above the noise of its own estimate (|x|^2 > sum var: the rule
/// that makes a candidate [`Unidentified::Unmeasured`]).
pub fn measurable(x: &[f64], var: &[f64]) -> bool {
    let xx: f64 = x.iter().map(|v| v * v).sum();
    xx > 0.0 && xx > var.iter().sum::<f64>()
}

/// Holm's step-down correction of `p_raw` into `p_value` (monotone, capped at 1).
fn holm(scores: &mut [Score]) {
    let k = scores.len();
    let mut order: Vec<usize> = (0..k).collect();
    order.sort_by(|&a, &b| scores[a].p_raw.total_cmp(&scores[b].p_raw));
    let mut running: f64 = 0.0;
    for (rank, &i) in order.iter().enumerate() {
        let adj = ((k - rank) as f64 * scores[i].p_raw).min(1.0);
        running = running.max(adj);
        scores[i].p_value = running;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    fn normal(rng: &mut ChaCha8Rng, n: usize) -> Vec<f64> {
        (0..n).map(|_| StandardNormal.sample(rng)).collect()
    }

    #[test]
    fn recalibration_recovers_the_shift_that_made_the_residuals() {
        let (x, _) = problem(11);
        let b = [0.7, -2.5];
        let r: Vec<f64> = (0..x.nrows())
            .map(|i| x[(i, 0)] * b[0] + x[(i, 1)] * b[1])
            .collect();
        let got = recalibration(&r, &x);
        for (g, want) in got.iter().zip(b) {
            assert!((g - want).abs() < 1e-9, "{got:?} against {b:?}");
        }
        // And what it leaves is what `absorbed` reports: nothing.
        assert!(absorbed(&r, &x).iter().all(|v| v.abs() < 1e-9));
    }

    #[test]
    fn a_parameter_is_measurable_only_above_its_estimate_noise() {
        assert!(measurable(&[3.0, 4.0], &[1.0, 1.0]));
        assert!(!measurable(&[1.0, 1.0], &[1.5, 1.5]));
        assert!(!measurable(&[0.0, 0.0], &[]));
    }

    /// m rows, 2 free parameters, 3 candidates with random signatures; the third is made a
    /// mix of the free parameters' columns plus 1 % of its own.
    fn problem(seed: u64) -> (DMatrix<f64>, Vec<Candidate>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let m = 24;
        let x = DMatrix::from_column_slice(m, 2, &normal(&mut rng, 2 * m));
        let mut cands: Vec<Candidate> = ["a", "b"]
            .iter()
            .map(|n| Candidate {
                name: n.to_string(),
                sensitivity: normal(&mut rng, m),
                sensitivity_var: vec![],
            })
            .collect();
        let own = normal(&mut rng, m);
        let absorbed: Vec<f64> = (0..m)
            .map(|i| 0.7 * x[(i, 0)] - 1.3 * x[(i, 1)] + 0.01 * own[i])
            .collect();
        cands.push(Candidate {
            name: "absorbed".into(),
            sensitivity: absorbed,
            sensitivity_var: vec![],
        });
        (x, cands)
    }

    #[test]
    fn the_hidden_effect_ranks_first_with_its_strength() {
        let (x, cands) = problem(7);
        let mut rng = ChaCha8Rng::seed_from_u64(70);
        // Truth = model + 0.8 of candidate b + noise; the model's parameters are off by
        // (0.3, -0.2), which recalibration absorbs.
        let noise = normal(&mut rng, 24);
        let r: Vec<f64> = (0..24)
            .map(|i| {
                0.3 * x[(i, 0)] - 0.2 * x[(i, 1)] + 0.8 * cands[1].sensitivity[i] + noise[i] * 0.2
            })
            .collect();
        let s = score_tests(&r, &x, &cands);
        assert_eq!(s[0].name, "b");
        assert!(s[0].p_value < 0.01, "{:?}", s[0]);
        assert!((s[0].strength - 0.8).abs() < 0.15, "{:?}", s[0]);
        assert!(s.iter().find(|c| c.name == "a").unwrap().p_value > 0.01);
    }

    /// A strong signal's p-value is the chi^2(1) tail, erfc(sqrt(S / 2)), down to the
    /// smallest numbers: not 0 (1 - cdf rounds everything below about 1e-16 to 0).
    #[test]
    fn a_strong_signals_p_value_is_not_rounded_to_zero() {
        let (x, cands) = problem(7);
        let r: Vec<f64> = cands[1].sensitivity.iter().map(|v| 3.0 * v).collect();
        let s = score_tests(&r, &x, &cands);
        let b = s.iter().find(|c| c.name == "b").unwrap();
        let tail = statrs::function::erf::erfc((b.statistic / 2.0).sqrt());
        assert!(b.statistic > 75.0 && tail < 1e-17, "{b:?}");
        assert!(
            (b.p_raw / tail - 1.0).abs() < 1e-6,
            "{} against {tail}",
            b.p_raw
        );
    }

    /// A candidate that is another's signature plus a little of its own is reported alike
    /// to it (both ways, with the cosine), an unrelated one is not.
    #[test]
    fn candidates_with_alike_signatures_are_named() {
        let (x, mut cands) = problem(5);
        let mut rng = ChaCha8Rng::seed_from_u64(50);
        let own = normal(&mut rng, 24);
        let twin: Vec<f64> = (0..24)
            .map(|i| 1.5 * cands[1].sensitivity[i] + 0.2 * own[i])
            .collect();
        cands.push(Candidate {
            name: "twin".into(),
            sensitivity: twin,
            sensitivity_var: vec![],
        });
        let r: Vec<f64> = (0..24).map(|i| cands[1].sensitivity[i]).collect();
        let s = score_tests(&r, &x, &cands);
        let get = |n: &str| s.iter().find(|c| c.name == n).unwrap();
        let b = get("b");
        assert_eq!(b.alike.len(), 1, "{:?}", b.alike);
        assert_eq!(b.alike[0].0, "twin");
        assert!(b.alike[0].1 > ALIKE_COSINE && b.alike[0].1 < 1.0);
        assert_eq!(get("twin").alike[0].0, "b");
        assert!(get("a").alike.is_empty(), "{:?}", get("a").alike);
    }

    #[test]
    fn with_no_hidden_effect_nothing_is_flagged_in_19_of_20_seeds() {
        let (x, cands) = problem(11);
        let mut flagged = 0;
        for seed in 0..20 {
            let mut rng = ChaCha8Rng::seed_from_u64(1000 + seed);
            let noise = normal(&mut rng, 24);
            let r: Vec<f64> = (0..24).map(|i| 0.5 * x[(i, 0)] + noise[i]).collect();
            let s = score_tests(&r, &x, &cands);
            if s.iter().any(|c| c.p_value < 0.01) {
                flagged += 1;
            }
        }
        assert!(flagged <= 1, "flagged in {flagged} of 20 seeds");
    }

    #[test]
    fn an_effect_the_free_parameters_absorb_is_not_identifiable() {
        let (x, cands) = problem(3);
        // The truth carries the absorbable effect strongly.
        let r: Vec<f64> = cands[2].sensitivity.iter().map(|v| 2.0 * v).collect();
        let s = score_tests(&r, &x, &cands);
        let a = s.iter().find(|c| c.name == "absorbed").unwrap();
        assert!(!a.identifiable, "{a:?}");
        assert_eq!(a.unidentified, Some(Unidentified::Absorbed));
        assert!(a.distinct_fraction < MIN_DISTINCT);
        assert_eq!(a.p_value, 1.0);
        // Nothing else is a discovery either: the free parameters explain the residuals.
        assert!(s.iter().all(|c| c.p_value > 0.01), "{s:?}");
    }

    /// A sensitivity known only to within twice its size says little: the same residual
    /// gives a much smaller statistic.
    #[test]
    fn a_noisy_sensitivity_weakens_the_test() {
        let (x, mut cands) = problem(7);
        let r: Vec<f64> = cands[1].sensitivity.iter().map(|v| 0.8 * v).collect();
        let exact = score_tests(&r, &x, &cands);
        cands[1].sensitivity_var = vec![4.0; 24];
        let noisy = score_tests(&r, &x, &cands);
        let s = |v: &[Score]| v.iter().find(|c| c.name == "b").unwrap().statistic;
        assert!(
            s(&noisy) < 0.5 * s(&exact),
            "{} vs {}",
            s(&noisy),
            s(&exact)
        );
    }

    /// A candidate whose estimated signature is all noise is unmeasured, not a finding.
    #[test]
    fn a_signature_within_its_noise_is_unmeasured() {
        let (x, mut cands) = problem(5);
        cands[0].sensitivity_var = vec![4.0; 24];
        let r: Vec<f64> = cands[0].sensitivity.iter().map(|v| 3.0 * v).collect();
        let s = score_tests(&r, &x, &cands);
        let a = s.iter().find(|c| c.name == "a").unwrap();
        assert_eq!(a.unidentified, Some(Unidentified::Unmeasured), "{a:?}");
        assert_eq!(a.p_value, 1.0);
    }

    #[test]
    fn holm_matches_a_hand_calculation() {
        let mut s: Vec<Score> = [0.01, 0.04, 0.03]
            .iter()
            .map(|&p| Score {
                name: String::new(),
                statistic: 0.0,
                p_raw: p,
                p_value: p,
                strength: 0.0,
                predicted_chi2_drop: 0.0,
                distinct_fraction: 1.0,
                identifiable: true,
                unidentified: None,
                fitted_change: vec![],
                alike: vec![],
                signature: vec![],
            })
            .collect();
        holm(&mut s);
        // Sorted 0.01, 0.03, 0.04: 3 x 0.01 = 0.03, 2 x 0.03 = 0.06, max(0.06, 1 x 0.04).
        let p: Vec<f64> = s.iter().map(|c| c.p_value).collect();
        assert!(
            (p[0] - 0.03).abs() < 1e-15
                && (p[1] - 0.06).abs() < 1e-15
                && (p[2] - 0.06).abs() < 1e-15,
            "{p:?}"
        );
    }
}
