//! Two fits that are not nested in each other, on the same rows with known noise: how
//! unlikely the worse one's gap is if it were the truth.
//!
//! Fits a and b each free the same parameters plus one of their own (a candidate's strength
//! or a held parameter), on n rows whose errors are the standard errors the residuals are
//! scaled by. Let G = chi^2_b - chi^2_a. If b is the truth, how large can G be by chance?
//! In the linearised model (tangent planes T_a, T_b at the common start, standardised rows,
//! y = mu_b + e with e ~ N(0, I)), let S = T_a + T_b, which has one dimension more than each;
//! then
//!
//!   chi^2_b = |P_S^perp e|^2 + |Q_b e|^2,   chi^2_a = |P_S^perp e|^2 + |Q_a (d + e)|^2,
//!
//! with Q_x the projection on S minus T_x (one dimension) and d the part of mu_b that a
//! cannot reach (it lies in S). So G <= |Q_b e|^2 ~ chi^2(1), whatever d: a rival that
//! mimics the truth closely makes G small, one that cannot makes it negative. A curved
//! model can put part of d outside S; completing the square bounds that part by one more
//! chi^2(1), so the bound taken is chi^2(2)'s tail,
//!
//!   P(G >= g | b true) <= exp(-g/2),
//!
//! the same number as Royall's universal bound on misleading evidence (a likelihood ratio
//! of k favours a false hypothesis with probability at most 1/k). This is a Cox-type test
//! of b against a (Cox 1961) in its least favourable form: it needs neither fit's Jacobian,
//! and unlike a row-by-row test (Vuong 1989) it uses the noise the rows state, so one
//! decisive measurement can exclude a rival when the gap there is beyond the noise.
//!
//! What it assumes, and the caller must see to: both fits at their minima (an unfinished
//! fit overstates its chi^2 and would be excluded for want of iterations: subtract what it
//! could still gain), and the rows' standard errors right (the best fit within the noise).
//!
//! References: Cox (1961) Proc. 4th Berkeley Symp. 1:105, "Tests of separate families of
//! hypotheses"; Royall (2000) JASA 95:760, "On the probability of observing misleading
//! statistical evidence"; Vuong (1989) Econometrica 57:307.

/// The bound on P(G >= gap) when the worse fit is the truth: exp(-gap/2), 1 for gap <= 0.
pub fn gap_p(gap: f64) -> f64 {
    if gap > 0.0 { (-gap / 2.0).exp() } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use statrs::distribution::{ChiSquared, ContinuousCDF};

    /// The residual sum of squares of y on the columns of x.
    fn rss(x: &DMatrix<f64>, y: &DVector<f64>) -> f64 {
        let beta = (x.transpose() * x)
            .cholesky()
            .expect("full rank")
            .solve(&(x.transpose() * y));
        (y - x * beta).norm_squared()
    }

    /// The free columns with one more.
    fn with(free: &DMatrix<f64>, extra: &DVector<f64>) -> DMatrix<f64> {
        let mut x = free.clone().insert_column(free.ncols(), 0.0);
        x.set_column(free.ncols(), extra);
        x
    }

    #[test]
    fn the_formula() {
        assert_eq!(gap_p(0.0), 1.0);
        assert_eq!(gap_p(-3.0), 1.0);
        assert!((gap_p(2.0 * 100f64.ln()) - 0.01).abs() < 1e-15);
    }

    /// Linear rivals on 16 rows with two free columns, the truth b at several strengths and
    /// a at several angles to it: the share of draws with G >= g stays under chi^2(1)'s tail
    /// (the linear bound, tighter than exp(-g/2)). Each check fails a correct program only
    /// if a binomial count lands 4.5 standard deviations above its mean, probability
    /// < 3.4e-6; 24 checks: < 1e-4, so the test passes with probability > 0.999.
    #[test]
    fn a_truth_is_excluded_no_more_often_than_the_bound_says() {
        const DRAWS: usize = 20_000;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut normal = |n: usize| -> DVector<f64> {
            DVector::from_fn(n, |_, _| StandardNormal.sample(&mut rng))
        };
        let n = 16;
        let free = DMatrix::from_columns(&[normal(n), normal(n)]);
        let b = normal(n);
        let other = normal(n);
        let chi1 = ChiSquared::new(1.0).unwrap();
        // a close to b (hard to tell apart), at 45 degrees, and unrelated; b weak to strong.
        for mix in [0.2, 1.0, 5.0] {
            let a = &b + &other * mix;
            for strength in [0.0, 1.0, 3.0, 6.0] {
                let (xa, xb) = (with(&free, &a), with(&free, &b));
                let mean = &free.column(0) * 0.5 + &b * (strength / b.norm());
                let gaps: Vec<f64> = (0..DRAWS)
                    .map(|_| {
                        let y = &mean + normal(n);
                        rss(&xb, &y) - rss(&xa, &y)
                    })
                    .collect();
                for g in [4.0, 9.0] {
                    let bound = chi1.sf(g);
                    assert!(bound < gap_p(g));
                    let share = gaps.iter().filter(|&&x| x >= g).count() as f64 / DRAWS as f64;
                    let sd = (bound * (1.0 - bound) / DRAWS as f64).sqrt();
                    assert!(
                        share <= bound + 4.5 * sd,
                        "mix {mix}, strength {strength}, g {g}: {share} > {bound}"
                    );
                }
            }
        }
    }
}
