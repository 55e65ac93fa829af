//! Residuals standardised by *estimated* variances, and a chi^2 test that allows for it.
//!
//! A row's standardised residual is z = r / sqrt(s^2/R + u^2), s the scatter of R
//! simulation runs (estimated, R - 1 degrees of freedom) and u the measurement's stated
//! uncertainty (exact, or itself estimated with the degrees of freedom the file states).
//! With R = 4 the variance estimate has 3 degrees of freedom, so z is not N(0, 1) but close
//! to Student's t with the Welch-Satterthwaite degrees of freedom
//!
//!   nu = (s^2/R + u^2)^2 / ((s^2/R)^2 / (R - 1) + u^4 / nu_u)
//!
//! (Welch 1947, Biometrika 34:28; GUM, JCGM 100:2008, eq. G.2b), whose square has mean
//! nu / (nu - 2): 3 at nu = 3. Summed over rows, chi^2 = sum z^2 against chi^2(m) then rejects
//! a right model far more often than its level says. Each z is therefore mapped to the
//! normal score with the same tail probability, q = Phi^-1(F_nu(z)), and sum q^2 is what is
//! compared with chi^2.

use statrs::distribution::{ContinuousCDF, Normal, StudentsT};

/// Degrees of freedom above which t is taken as normal (the score differs by < 1e-6 at
/// |z| <= 6).
const NORMAL_DOF: f64 = 1e7;

/// Welch-Satterthwaite degrees of freedom of a sum of variances, each `(variance, dof)`
/// (an infinite or non-positive dof: exact). Infinite when every part with a variance is
/// exact.
pub fn welch_dof(parts: &[(f64, f64)]) -> f64 {
    let total: f64 = parts.iter().map(|p| p.0).sum();
    let denominator: f64 = parts
        .iter()
        .filter(|(v, d)| *v > 0.0 && *d > 0.0 && d.is_finite())
        .map(|(v, d)| v * v / d)
        .sum();
    if denominator > 0.0 {
        total * total / denominator
    } else {
        f64::INFINITY
    }
}

/// Degrees of freedom of s^2/R + u^2: `scatter` s from `replicates` runs (R - 1 degrees of
/// freedom), `uncertainty` u with `uncertainty_dof` (None: exact).
pub fn residual_dof(
    scatter: Option<f64>,
    replicates: usize,
    uncertainty: Option<f64>,
    uncertainty_dof: Option<f64>,
) -> f64 {
    let runs = replicates.max(1);
    welch_dof(&[
        (
            scatter.map_or(0.0, |s| s * s / runs as f64),
            (runs - 1) as f64,
        ),
        (
            uncertainty.map_or(0.0, |u| u * u),
            uncertainty_dof.unwrap_or(f64::INFINITY),
        ),
    ])
}

/// The standard normal score with the tail probability of `t` under Student's t with `dof`
/// degrees of freedom: Phi^-1(F_dof(t)). `t` itself when `dof` is infinite.
pub fn normal_score(t: f64, dof: f64) -> f64 {
    if !(dof < NORMAL_DOF) || !t.is_finite() || t == 0.0 {
        return t;
    }
    let student = StudentsT::new(0.0, 1.0, dof).expect("positive dof");
    let normal = Normal::standard();
    // From the tail, so that a large |t| keeps its precision.
    let tail = student.sf(t.abs());
    let q = if tail > 0.0 {
        -normal.inverse_cdf(tail)
    } else {
        // Below the smallest f64: as far out as a normal score reaches.
        38.0
    };
    q.copysign(t)
}

/// sum q_i^2 over standardised residuals `z` with degrees of freedom `dof` (empty: every
/// row exact, sum z^2).
pub fn normal_chi2(z: &[f64], dof: &[f64]) -> f64 {
    z.iter()
        .enumerate()
        .map(|(i, &zi)| normal_score(zi, dof.get(i).copied().unwrap_or(f64::INFINITY)).powi(2))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{ChiSquared as ChiSq, Distribution, StandardNormal};
    use statrs::distribution::ChiSquared;

    #[test]
    fn welch_dof_is_the_formula_and_exact_parts_add_none() {
        // s = 2 from 4 runs: s^2/R = 1 on 3 dof; u = 1 exact: nu = (1 + 1)^2 / (1/3) = 12.
        assert!((residual_dof(Some(2.0), 4, Some(1.0), None) - 12.0).abs() < 1e-12);
        // Only the runs' part: nu = R - 1.
        assert!((residual_dof(Some(2.0), 4, None, None) - 3.0).abs() < 1e-12);
        // u on 5 dof as well: (1 + 1)^2 / (1/3 + 1/5) = 7.5.
        assert!((residual_dof(Some(2.0), 4, Some(1.0), Some(5.0)) - 7.5).abs() < 1e-12);
        assert!(residual_dof(None, 4, Some(1.0), None).is_infinite());
        assert!(residual_dof(Some(0.0), 4, Some(1.0), None).is_infinite());
        assert!(residual_dof(Some(1.0), 1, Some(1.0), None).is_infinite());
    }

    #[test]
    fn the_normal_score_keeps_the_tail_probability() {
        // Student's t with 1 dof is Cauchy: F(t) = 1/2 + atan(t)/pi.
        let normal = Normal::standard();
        for t in [-30.0, -2.0, -0.3, 0.7, 4.0, 100.0] {
            let want = normal.inverse_cdf(0.5 + f64::atan(t) / std::f64::consts::PI);
            let got = normal_score(t, 1.0);
            assert!(
                (got - want).abs() < 1e-6 * want.abs().max(1.0),
                "{t}: {got} vs {want}"
            );
        }
        // Exact rows are unchanged; a large dof is nearly so; heavy tails are pulled in.
        assert_eq!(normal_score(2.5, f64::INFINITY), 2.5);
        assert!((normal_score(2.5, 1e5) - 2.5).abs() < 1e-4);
        assert!(normal_score(3.0, 3.0) < 2.0);
        assert_eq!(normal_score(0.0, 3.0), 0.0);
    }

    /// z from R = 4 runs whose scatter sets the standard error (the worst case, nu = 3):
    /// sum z^2 over 20 rows against chi^2(20) at the 1 % point, and sum q^2.
    #[test]
    fn the_scores_hold_the_level_that_raw_z_squared_breaks() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (rows, draws, runs) = (20, 2000, 4usize);
        let crit = ChiSquared::new(rows as f64).unwrap().inverse_cdf(0.99);
        let chi3 = ChiSq::new((runs - 1) as f64).unwrap();
        let (mut raw, mut scored) = (0, 0);
        for _ in 0..draws {
            let z: Vec<f64> = (0..rows)
                .map(|_| {
                    let n: f64 = StandardNormal.sample(&mut rng);
                    let s2 = chi3.sample(&mut rng) / (runs - 1) as f64;
                    n / s2.sqrt()
                })
                .collect();
            let dof = vec![residual_dof(Some(1.0), runs, None, None); rows];
            raw += usize::from(z.iter().map(|v| v * v).sum::<f64>() > crit);
            scored += usize::from(normal_chi2(&z, &dof) > crit);
        }
        // The scores are exactly N(0, 1) here, so the rejections are Bin(2000, 0.01):
        // P(Bin(2000, 0.01) > 38) = 9.9e-5.
        assert!(scored <= 38, "scored: {scored} of {draws} rejected");
        // Raw: a sum of 20 F(1, 3) variates (mean 60) beyond 37.6, at a rate of 0.565 (2e5
        // draws, scipy): the failure this module exists for. P(Bin(2000, 0.565) < 1000) =
        // 3e-9.
        assert!(raw >= 1000, "raw: only {raw} of {draws} rejected");
    }
}
