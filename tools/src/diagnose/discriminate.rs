//! How well a set of measurements would tell rival candidates apart: the T-optimal criterion
//! of model discrimination (Atkinson and Fedorov 1975, Biometrika 62:57; after Box and Hill
//! 1967, Technometrics 9:57), in the linearised, standardised form `diagnose` works in.
//!
//! When candidate a is the truth at strength theta_a and the rival b is fitted in its place
//! (with the free parameters), what the rival cannot reproduce is
//!
//!   lambda(a -> b) = |M_[X, j_b] theta_a j_a|^2,
//!
//! the noncentrality of the encompassing test T(a | X, b) of [`super::verdict`] on those
//! rows: the test rejects b in favour of a with power P(|Z + sqrt(lambda)| > z_{1-alpha/2}).
//! A design separates the rivals when the smallest lambda over every ordered pair is large
//! (T-optimality is the max-min of it). Columns are sensitivities per unit of each
//! parameter, every row standardised by its standard error.
//!
//! The sensitivities are finite differences of noisy runs, so part of lambda is their noise:
//! E|M theta_a d_a|^2 = theta_a^2 sum_i v_ai (m - q) / m for the estimate's noise d_a with
//! variances v_a. It is reported, and taken off before the power.

use super::ResidualMaker;
use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, Normal};

/// The standardised columns of a set of rows: the free parameters', and each rival's with
/// the variances of its estimate.
#[derive(Debug, Clone)]
pub struct Rows {
    /// m x p.
    pub free: DMatrix<f64>,
    /// m x K: each rival's sensitivity per unit strength.
    pub rivals: DMatrix<f64>,
    /// m x K: the variance of each entry of `rivals`.
    pub rival_var: DMatrix<f64>,
}

impl Rows {
    /// These rows and `more` below them.
    pub fn stack(&self, more: &Rows) -> Rows {
        let cat = |a: &DMatrix<f64>, b: &DMatrix<f64>| {
            let mut out = DMatrix::zeros(a.nrows() + b.nrows(), a.ncols());
            out.rows_mut(0, a.nrows()).copy_from(a);
            out.rows_mut(a.nrows(), b.nrows()).copy_from(b);
            out
        };
        Rows {
            free: cat(&self.free, &more.free),
            rivals: cat(&self.rivals, &more.rivals),
            rival_var: cat(&self.rival_var, &more.rival_var),
        }
    }
}

/// The separation of one ordered pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Separation {
    pub truth: String,
    pub rival: String,
    /// lambda(truth -> rival), finite-difference noise included.
    pub noncentrality: f64,
    /// The part of it the finite differences' noise is expected to bring.
    pub noise: f64,
    /// Power of the encompassing test at `alpha` to reject the rival when the truth holds,
    /// from the noncentrality less the noise.
    pub power: f64,
}

/// Every ordered pair's separation on `rows`, each rival at its strength in `strengths`.
pub fn separations(
    rows: &Rows,
    names: &[String],
    strengths: &[f64],
    alpha: f64,
) -> Vec<Separation> {
    let (m, k) = (rows.rivals.nrows(), rows.rivals.ncols());
    assert_eq!(names.len(), k, "one name per rival");
    assert_eq!(strengths.len(), k, "one strength per rival");
    let z = Normal::new(0.0, 1.0)
        .expect("standard normal")
        .inverse_cdf(1.0 - alpha / 2.0);
    let mut out = vec![];
    for b in 0..k {
        let mut xs = DMatrix::zeros(m, rows.free.ncols() + 1);
        xs.columns_mut(0, rows.free.ncols()).copy_from(&rows.free);
        xs.set_column(rows.free.ncols(), &rows.rivals.column(b));
        let maker = ResidualMaker::new(&xs);
        let kept = m.saturating_sub(maker.rank()) as f64 / m.max(1) as f64;
        for a in (0..k).filter(|&a| a != b) {
            let signal: DVector<f64> = rows.rivals.column(a) * strengths[a];
            let noncentrality = maker.apply(&signal).norm_squared();
            let noise = strengths[a].powi(2) * rows.rival_var.column(a).sum() * kept;
            out.push(Separation {
                truth: names[a].clone(),
                rival: names[b].clone(),
                noncentrality,
                noise,
                power: power(noncentrality - noise, z),
            });
        }
    }
    out
}

/// New readings simulated with each rival's fitted model (`diagnose`'s refit): per rival,
/// per reading, the values of the replicates (the same seeds for every rival), and per
/// reading the variance a measurement of it carries, lab^2 / specimens.
pub struct Fitted<'a> {
    pub names: &'a [String],
    /// [rival][reading][replicate].
    pub values: &'a [Vec<Vec<f64>>],
    pub lab_var: &'a [f64],
}

/// Every ordered pair's separation on new readings when the rivals are fitted models: with
/// a the truth, a measurement y_i of reading i compared with rival b's prediction has mean
/// mu_a,i - mu_b,i and variance sigma_i^2 = lab_i^2 / specimens + s_b,i^2 / R (b's
/// prediction from R runs), so the test along the predicted difference has noncentrality
///
///   lambda(a -> b) = sum_i (mu_a,i - mu_b,i)^2 / sigma_i^2.
///
/// mu_a - mu_b is estimated by the mean per-seed difference d_i (common seeds), whose own
/// variance var(d_i) / R is reported as noise and taken off before the power. Unlike
/// [`separations`], b is not refitted to the new readings: the free parameters could take
/// up part of the difference, so this is an upper bound of what the measurement adds.
pub fn fitted_separations(f: &Fitted, alpha: f64) -> Vec<Separation> {
    let k = f.names.len();
    assert_eq!(f.values.len(), k, "one set of values per rival");
    let z = Normal::new(0.0, 1.0)
        .expect("standard normal")
        .inverse_cdf(1.0 - alpha / 2.0);
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    let var = |x: &[f64]| {
        let m = mean(x);
        x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() as f64 - 1.0)
    };
    let mut out = vec![];
    for b in 0..k {
        for a in (0..k).filter(|&a| a != b) {
            let (mut noncentrality, mut noise) = (0.0, 0.0);
            for (i, lab_var) in f.lab_var.iter().enumerate() {
                let (ya, yb) = (&f.values[a][i], &f.values[b][i]);
                let r = ya.len().min(yb.len());
                if r < 2 {
                    continue;
                }
                let d: Vec<f64> = ya.iter().zip(yb).map(|(x, y)| x - y).collect();
                let sigma2 = lab_var + var(&yb[..r]) / r as f64;
                if !(sigma2 > 0.0) {
                    continue;
                }
                noncentrality += mean(&d).powi(2) / sigma2;
                noise += var(&d) / r as f64 / sigma2;
            }
            out.push(Separation {
                truth: f.names[a].clone(),
                rival: f.names[b].clone(),
                noncentrality,
                noise,
                power: power(noncentrality - noise, z),
            });
        }
    }
    out
}

/// The rivals' weights on the data so far, the posterior probabilities of Box and Hill
/// (1967): with equal priors and each rival one strength beyond the free parameters (so no
/// rival pays more for its parameters than another),
///
///   P_k = exp(-chi2_k / 2) / sum_j exp(-chi2_j / 2),
///
/// chi2_k the misfit of rival k fitted. A rival whose misfit is unknown (its fit failed)
/// weighs as much as the best: no rival loses weight for want of a fit. All unknown: equal.
pub fn weights(chi2: &[Option<f64>]) -> Vec<f64> {
    let best = chi2.iter().flatten().copied().fold(f64::INFINITY, f64::min);
    if !best.is_finite() {
        return vec![1.0 / chi2.len() as f64; chi2.len()];
    }
    let raw: Vec<f64> = (chi2.iter())
        .map(|c| (-(c.unwrap_or(best) - best) / 2.0).exp())
        .collect();
    let total: f64 = raw.iter().sum();
    raw.iter().map(|w| w / total).collect()
}

/// The Bayesian discrimination criterion in power form: with rival a the truth with
/// probability P_a ([`weights`]), the chance that the encompassing tests on the new data
/// reject every wrong rival, bounded above by the hardest of them,
///
///   E = sum_a P_a min_{b != a} power(a -> b).
///
/// Unlike the max-min of T-optimality, a pair of rivals the data already make unlikely
/// does not decide the choice (Box and Hill 1967; Hill, Hunter and Wichern 1968,
/// Technometrics 10:145, weigh the pairs so).
pub fn expected_power(pairs: &[Separation], names: &[String], weights: &[f64]) -> f64 {
    assert_eq!(names.len(), weights.len(), "one weight per rival");
    names
        .iter()
        .zip(weights)
        .map(|(a, w)| {
            let hardest = (pairs.iter())
                .filter(|p| &p.truth == a)
                .map(|p| p.power)
                .fold(1.0, f64::min);
            w * hardest
        })
        .sum()
}

/// P(|Z + sqrt(lambda)| > z), Z standard normal: a 1-df chi^2 test's power.
fn power(lambda: f64, z: f64) -> f64 {
    let n = Normal::new(0.0, 1.0).expect("standard normal");
    let shift = lambda.max(0.0).sqrt();
    n.sf(z - shift) + n.cdf(-z - shift)
}

/// The pair hardest to tell apart: the smallest noncentrality less noise.
pub fn worst(separations: &[Separation]) -> Option<&Separation> {
    separations
        .iter()
        .min_by(|x, y| (x.noncentrality - x.noise).total_cmp(&(y.noncentrality - y.noise)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn col(v: &[f64]) -> DMatrix<f64> {
        DMatrix::from_column_slice(v.len(), 1, v)
    }

    #[test]
    fn a_row_where_the_rivals_differ_separates_them() {
        // Two rows where a and b move the readings alike: nothing separates them.
        let names = vec!["a".to_string(), "b".to_string()];
        let old = Rows {
            free: DMatrix::zeros(2, 0),
            rivals: DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 2.0, 2.0]),
            rival_var: DMatrix::zeros(2, 2),
        };
        let s = separations(&old, &names, &[1.0, 1.0], 0.01);
        assert!(s.iter().all(|x| x.noncentrality < 1e-12), "{s:?}");
        // A third row where a moves the reading by 3 and b not at all: fitting b in a's
        // place leaves the part of a's (1, 2, 3) that b's (1, 2, 0) cannot reproduce,
        // |(1, 2, 3) - (1, 2, 0) 5/5|^2 = 9.
        let new = Rows {
            free: DMatrix::zeros(1, 0),
            rivals: DMatrix::from_row_slice(1, 2, &[3.0, 0.0]),
            rival_var: DMatrix::zeros(1, 2),
        };
        let s = separations(&old.stack(&new), &names, &[1.0, 1.0], 0.01);
        let ab = s.iter().find(|x| x.truth == "a").unwrap();
        assert!((ab.noncentrality - 9.0).abs() < 1e-9, "{ab:?}");
        // b as the truth: a fitted in its place, (1, 2, 0) less its projection on (1, 2, 3):
        // 5 - 25/14.
        let ba = s.iter().find(|x| x.truth == "b").unwrap();
        assert!(
            (ba.noncentrality - (5.0 - 25.0 / 14.0)).abs() < 1e-9,
            "{ba:?}"
        );
        assert_eq!(worst(&s).unwrap().truth, "b");
    }

    #[test]
    fn what_a_free_parameter_mimics_does_not_separate() {
        // a and b differ only along the free parameter's column: recalibrating it fits b
        // to a's data exactly.
        let names = vec!["a".to_string(), "b".to_string()];
        let x = col(&[1.0, -1.0, 0.5]);
        let b = [0.3, 0.2, 0.1];
        let a: Vec<f64> = b.iter().zip(x.iter()).map(|(b, x)| b + 2.0 * x).collect();
        let mut rivals = DMatrix::zeros(3, 2);
        rivals.set_column(0, &DVector::from_column_slice(&a));
        rivals.set_column(1, &DVector::from_column_slice(&b));
        let rows = Rows {
            free: x,
            rivals,
            rival_var: DMatrix::zeros(3, 2),
        };
        let s = separations(&rows, &names, &[1.0, 1.0], 0.01);
        let ab = s.iter().find(|x| x.truth == "a").unwrap();
        assert!(ab.noncentrality < 1e-12, "{ab:?}");
    }

    #[test]
    fn fitted_rivals_are_separated_by_their_predicted_difference() {
        // Reading 0: a predicts 2 more than b, seed by seed (no noise in the difference);
        // reading 1: identical. Lab variance 1, b's 4 runs 10..13 (sample variance 5/3):
        // sigma^2 = 1 + 5/12, lambda = 4 / sigma^2 both ways, no noise.
        let names = vec!["a".to_string(), "b".to_string()];
        let b0 = [10.0, 11.0, 12.0, 13.0];
        let b0_var = 5.0 / 3.0; // sample variance of 10..13
        let values = vec![
            vec![
                b0.iter().map(|v| v + 2.0).collect(),
                vec![1.0, 2.0, 3.0, 4.0],
            ],
            vec![b0.to_vec(), vec![1.0, 2.0, 3.0, 4.0]],
        ];
        let f = Fitted {
            names: &names,
            values: &values,
            lab_var: &[1.0, 1.0],
        };
        let s = fitted_separations(&f, 0.01);
        assert_eq!(s.len(), 2);
        let want = 4.0 / (1.0 + b0_var / 4.0);
        for p in &s {
            assert!((p.noncentrality - want).abs() < 1e-12, "{p:?}");
            assert_eq!(p.noise, 0.0);
            assert!((p.power - power(want, 2.5758293035489004)).abs() < 1e-9);
        }
    }

    #[test]
    fn weights_are_the_posterior_and_a_failed_fit_weighs_as_the_best() {
        // chi2 10 and 12: odds exp(1) : 1.
        let w = weights(&[Some(10.0), Some(12.0)]);
        assert!((w[0] / w[1] - 1f64.exp()).abs() < 1e-12, "{w:?}");
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let w = weights(&[Some(10.0), None, Some(30.0)]);
        assert!((w[0] - w[1]).abs() < 1e-12 && w[2] < 1e-4 * w[0], "{w:?}");
        assert_eq!(weights(&[None, None]), vec![0.5, 0.5]);
    }

    #[test]
    fn expected_power_weighs_each_truth_by_its_hardest_rival() {
        let sep = |truth: &str, rival: &str, power: f64| Separation {
            truth: truth.into(),
            rival: rival.into(),
            noncentrality: 0.0,
            noise: 0.0,
            power,
        };
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let pairs = vec![
            sep("a", "b", 0.9),
            sep("a", "c", 0.8),
            sep("b", "a", 0.5),
            sep("b", "c", 0.1),
            sep("c", "a", 0.7),
            sep("c", "b", 0.2),
        ];
        // 0.6 * 0.8 + 0.3 * 0.1 + 0.1 * 0.2.
        let e = expected_power(&pairs, &names, &[0.6, 0.3, 0.1]);
        assert!((e - 0.53).abs() < 1e-12, "{e}");
        // All weight on a: only a's pairs count.
        let e = expected_power(&pairs, &names, &[1.0, 0.0, 0.0]);
        assert!((e - 0.8).abs() < 1e-12, "{e}");
    }

    #[test]
    fn power_is_the_two_sided_normal_formula() {
        let z = 2.5758293035489; // alpha 0.01
        assert!((power(0.0, z) - 0.01).abs() < 1e-9);
        // sqrt(lambda) = z: half the mass beyond, plus a negligible far tail.
        let p = power(z * z, z);
        assert!((p - 0.5).abs() < 1e-6, "{p}");
    }
}
