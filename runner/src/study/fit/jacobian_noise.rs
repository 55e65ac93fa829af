//! The standard errors of `tilth fit`, with the finite-difference Jacobian's own noise taken
//! off the information matrix.
//!
//! With residuals standardised by each row's standard error, the estimate's covariance is
//! (J'J)^-1 for the *exact* Jacobian J. The fit only has a finite-difference estimate
//! Ĵ = J + E: each entry is a mean over the R seeds of per-seed slopes
//! g_ijs = (y_i(θ + h_j e_j, s) - y_i(θ, s)) / h_j, scaled by 1 / se_i. The grains' chaos
//! decorrelates the two runs of one seed after a small change, so E is not small: on the
//! discovery proof's draws the per-seed slopes scatter by more than their mean
//! (docs/discovery-proof.md, "`fit`'s standard errors"). Since
//! E[Ĵ'Ĵ] = J'J + N, with
//!
//!   N_jk = Σ_i Cov_s(g_ijs, g_iks) / (R se_i^2)
//!
//! (rows are independent draws: each condition has its own seeds; two parameters' slopes on
//! one row share the centre runs, hence the off-diagonal terms), the naive (Ĵ'Ĵ)^-1 is too
//! small. Ĵ'Ĵ - N, with N from the per-seed slopes' sample covariances, is an unbiased
//! estimate of J'J: the errors-in-variables correction of the normal equations (Fuller,
//! Measurement Error Models, 1987, sec. 2.2; here each entry's error variance is measured,
//! not assumed). Where Ĵ'Ĵ - N is not positive definite, the runs cannot tell how the
//! readings move with the parameters, and no standard error is reported.

use nalgebra::DMatrix;

/// N (P x P): the noise Ĵ'Ĵ carries. `centre[i]` holds row i's per-seed values at the
/// setting, `moved[j][i]` those with parameter j moved by `steps[j]`, seeds in the same
/// order; `se[i]` is the row's standard error. Rows with fewer than two seeds add nothing.
pub fn jacobian_noise(
    centre: &[Vec<f64>],
    moved: &[Vec<Vec<f64>>],
    steps: &[f64],
    se: &[f64],
) -> DMatrix<f64> {
    let p = moved.len();
    let mut n = DMatrix::zeros(p, p);
    for (i, c) in centre.iter().enumerate() {
        let r = c.len();
        if r < 2 || moved.iter().any(|m| m[i].len() != r) {
            continue;
        }
        let slopes: Vec<Vec<f64>> = (0..p)
            .map(|j| (0..r).map(|s| (moved[j][i][s] - c[s]) / steps[j]).collect())
            .collect();
        let means: Vec<f64> = slopes
            .iter()
            .map(|g| g.iter().sum::<f64>() / r as f64)
            .collect();
        let scale = 1.0 / ((r * (r - 1)) as f64 * se[i] * se[i]);
        for j in 0..p {
            for k in 0..p {
                let cov: f64 = (0..r)
                    .map(|s| (slopes[j][s] - means[j]) * (slopes[k][s] - means[k]))
                    .sum();
                n[(j, k)] += cov * scale;
            }
        }
    }
    n
}

/// The estimate's covariance, (Ĵ'Ĵ - noise)^-1 `scale`; None when Ĵ'Ĵ - noise is not
/// positive definite (with a zero `noise`: the naive (Ĵ'Ĵ)^-1, None when singular).
pub fn covariance(jac: &DMatrix<f64>, noise: &DMatrix<f64>, scale: f64) -> Option<DMatrix<f64>> {
    let info = jac.transpose() * jac - noise;
    Some(info.cholesky()?.inverse() * scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// A linear model: rows i = 0..16, readings y_i(θ) = a_i + b_i θ_0 + c_i θ_1, each run's
    /// value that plus its own chaos (sd `sigma`, independent between the centre and the
    /// moved runs of one seed, the chaotic extreme), moved by `STEPS`. Returns the exact J'J
    /// (standardised by se_i = sigma / sqrt(R)) and, for each of `draws` draws, Ĵ'Ĵ and
    /// Ĵ'Ĵ - N.
    fn draws(r: usize, draws: usize) -> (DMatrix<f64>, Vec<Draw>) {
        let rows = 16;
        let sigma = 2.0;
        let b: Vec<f64> = (0..rows).map(|i| 10.0 + 3.0 * i as f64).collect();
        let c: Vec<f64> = (0..rows).map(|i| 40.0 - 2.0 * i as f64).collect();
        let se = vec![sigma / (r as f64).sqrt(); rows];
        let exact = DMatrix::from_fn(rows, 2, |i, j| [b[i], c[i]][j] / se[i]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let chaos = Normal::new(0.0, sigma).unwrap();
        let mut out = vec![];
        for _ in 0..draws {
            let mut run = |shift: f64| -> Vec<f64> {
                (0..r).map(|_| shift + chaos.sample(&mut rng)).collect()
            };
            let centre: Vec<Vec<f64>> = (0..rows).map(|_| run(0.0)).collect();
            let moved: Vec<Vec<Vec<f64>>> = (0..2)
                .map(|j| (0..rows).map(|i| run([b[i], c[i]][j] * STEPS[j])).collect())
                .collect();
            let jac = DMatrix::from_fn(rows, 2, |i, j| {
                let mean = |v: &[f64]| v.iter().sum::<f64>() / r as f64;
                (mean(&moved[j][i]) - mean(&centre[i])) / STEPS[j] / se[i]
            });
            let jtj = jac.transpose() * &jac;
            let noise = jacobian_noise(&centre, &moved, &STEPS, &se);
            out.push((jtj.clone(), jtj - noise));
        }
        (exact.transpose() * exact, out)
    }

    const STEPS: [f64; 2] = [0.05, 0.02];

    /// One draw's Ĵ'Ĵ and Ĵ'Ĵ - N.
    type Draw = (DMatrix<f64>, DMatrix<f64>);

    /// The mean over draws of entry (j, k) and its Monte Carlo standard error.
    fn mean_and_error(v: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
        let n = v.clone().count() as f64;
        let m = v.clone().sum::<f64>() / n;
        let var = v.map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m, (var / n).sqrt())
    }

    /// Over many draws Ĵ'Ĵ - N averages to the exact J'J, entry by entry, within 4 Monte
    /// Carlo standard errors; Ĵ'Ĵ alone exceeds it on the diagonal by the formula's
    /// Σ_i 2 sigma^2 / (R h_j^2 se_i^2) = 2 rows / h_j^2 (a slope's variance from two
    /// independent runs), far beyond that error.
    #[test]
    fn the_corrected_information_is_unbiased_and_the_naive_one_is_inflated_as_predicted() {
        for r in [3, 4] {
            let (exact, draws) = draws(r, 4000);
            for j in 0..2 {
                for k in 0..2 {
                    let (c, err) = mean_and_error(draws.iter().map(|d| d.1[(j, k)]));
                    let e = exact[(j, k)];
                    assert!(
                        (c - e).abs() < 4.0 * err,
                        "R {r}: ({j},{k}) corrected {c} ± {err}, exact {e}"
                    );
                }
                let (naive, err) = mean_and_error(draws.iter().map(|d| d.0[(j, j)]));
                let inflation = 2.0 * 16.0 / (STEPS[j] * STEPS[j]);
                let got = naive - exact[(j, j)];
                assert!(
                    (got - inflation).abs() < 4.0 * err && inflation > 20.0 * err,
                    "R {r}: parameter {j} inflated by {got} ± {err}, the formula says {inflation}"
                );
            }
        }
    }

    /// With a Jacobian that is all noise, the corrected information is not positive definite
    /// in most draws and no standard error is given; the naive one always gives one.
    #[test]
    fn a_jacobian_of_pure_noise_gives_no_standard_error() {
        let rows = 16;
        let r = 4;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let chaos = Normal::new(0.0, 1.0).unwrap();
        let se = vec![0.5; rows];
        let mut undetermined = 0;
        for _ in 0..200 {
            let mut run = || -> Vec<f64> { (0..r).map(|_| chaos.sample(&mut rng)).collect() };
            let centre: Vec<Vec<f64>> = (0..rows).map(|_| run()).collect();
            let moved = vec![(0..rows).map(|_| run()).collect::<Vec<_>>()];
            let jac = DMatrix::from_fn(rows, 1, |i, _| {
                let mean = |v: &[f64]| v.iter().sum::<f64>() / r as f64;
                (mean(&moved[0][i]) - mean(&centre[i])) / 0.1 / se[i]
            });
            let noise = jacobian_noise(&centre, &moved, &[0.1], &se);
            assert!(covariance(&jac, &DMatrix::zeros(1, 1), 1.0).is_some());
            undetermined += covariance(&jac, &noise, 1.0).is_none() as usize;
        }
        // Ĵ'Ĵ - N is a difference of two estimates of the same sum; it falls at or below 0
        // about half the time.
        assert!(undetermined > 60, "{undetermined} of 200 undetermined");
    }
}
