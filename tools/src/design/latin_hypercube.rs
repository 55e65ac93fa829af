//! Latin hypercube sampling.

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};

use super::DesignError;

/// A Latin hypercube of `runs` points on `factors` factors in [-1, 1), from `seed`.
///
/// Reference: M. D. McKay, R. J. Beckman and W. J. Conover (1979), "A comparison of three
/// methods for selecting values of input variables in the analysis of output from a
/// computer code", *Technometrics* 21(2):239-245.
///
/// Each factor's range [-1, 1] is cut into `runs` equal strata; each stratum holds exactly
/// one point, placed uniformly at random inside it, and the strata are matched to runs by
/// an independent random permutation per factor. Row order carries no meaning.
///
/// Determinism: all randomness comes from `ChaCha8Rng::seed_from_u64(seed)`, whose output
/// stream is fixed by its specification, and is turned into integers and floats by the
/// code in this file rather than by `rand`'s distributions, whose algorithms may change
/// between releases. So the same seed gives the same bits on every platform, as long as
/// `rand_chacha` (0.9 here) keeps its seeding, which only a major release may change.
/// Draw order: factor by factor, first a Fisher-Yates shuffle of the strata (from the last
/// position down), then one uniform offset per run.
///
/// # Errors
/// `runs` or `factors` is 0.
pub fn latin_hypercube(
    runs: usize,
    factors: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>, DesignError> {
    if runs == 0 || factors == 0 {
        return Err(DesignError::LatinHypercubeSize { runs, factors });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rows = vec![vec![0.0; factors]; runs];
    let width = 2.0 / runs as f64;
    let mut strata: Vec<usize> = (0..runs).collect();
    for j in 0..factors {
        // A Fisher-Yates shuffle gives a uniform permutation whatever order it starts
        // from, so reshuffling the previous factor's permutation is still independent.
        for i in (1..runs).rev() {
            strata.swap(i, below(&mut rng, i as u64 + 1) as usize);
        }
        for (row, &s) in rows.iter_mut().zip(&strata) {
            let lo = -1.0 + s as f64 * width;
            let hi = -1.0 + (s + 1) as f64 * width;
            let x = lo + unit(&mut rng) * (hi - lo);
            // Rounding can land an offset close to 1 on `hi`, which belongs to the next
            // stratum; fall back to the stratum's lower edge so each stratum keeps one point.
            row[j] = if x < hi { x } else { lo };
        }
    }
    Ok(rows)
}

/// A uniform float in [0, 1) from the top 53 bits of one draw (every value is a multiple of
/// 2^-53, so 1 is never reached).
fn unit(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A uniform integer in [0, n), n >= 1, by Lemire's multiply-and-reject method (D. Lemire
/// (2019), "Fast random integer generation in an interval", *ACM TOMACS* 29(1):3), which is
/// exactly uniform, unlike a plain modulo.
fn below(rng: &mut ChaCha8Rng, n: u64) -> u64 {
    let threshold = n.wrapping_neg() % n;
    loop {
        let m = u128::from(rng.next_u64()) * u128::from(n);
        if (m as u64) >= threshold {
            return (m >> 64) as u64;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stratum (0-based) of `x` in [-1, 1) cut into `n` strata.
    fn stratum(x: f64, n: usize) -> usize {
        ((x + 1.0) / 2.0 * n as f64).floor() as usize
    }

    #[test]
    fn one_point_per_stratum_per_factor() {
        for (runs, factors) in [(1, 1), (2, 3), (10, 4), (37, 7), (500, 2)] {
            let d = latin_hypercube(runs, factors, 42).unwrap();
            assert_eq!(d.len(), runs);
            for j in 0..factors {
                let mut seen = vec![false; runs];
                for r in &d {
                    assert!((-1.0..1.0).contains(&r[j]));
                    let s = stratum(r[j], runs);
                    assert!(
                        !seen[s],
                        "{runs} runs: factor {j} has two points in stratum {s}"
                    );
                    seen[s] = true;
                }
                assert!(seen.iter().all(|&b| b));
            }
        }
    }

    #[test]
    fn same_seed_same_bits_other_seed_other_points() {
        let a = latin_hypercube(20, 5, 7).unwrap();
        let b = latin_hypercube(20, 5, 7).unwrap();
        let bits =
            |d: &[Vec<f64>]| -> Vec<u64> { d.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(bits(&a), bits(&b));
        let c = latin_hypercube(20, 5, 8).unwrap();
        assert_ne!(bits(&a), bits(&c));
    }

    #[test]
    fn factors_get_independent_permutations() {
        // With one shared permutation every column would order the runs the same way.
        let d = latin_hypercube(50, 3, 1).unwrap();
        let order = |j: usize| -> Vec<usize> { d.iter().map(|r| stratum(r[j], 50)).collect() };
        assert_ne!(order(0), order(1));
        assert_ne!(order(1), order(2));
    }

    #[test]
    fn bounded_integers_are_in_range_and_cover_it() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let mut hits = [0usize; 7];
        for _ in 0..7000 {
            hits[below(&mut rng, 7) as usize] += 1;
        }
        // Each of 7 values expects 1000 hits (sd about 30); 800 is over six sd away.
        assert!(hits.iter().all(|&h| h > 800), "{hits:?}");
    }

    #[test]
    fn errors_name_the_allowed_range() {
        assert_eq!(
            latin_hypercube(0, 3, 1).unwrap_err().to_string(),
            "a Latin hypercube takes at least 1 run and 1 factor; this sweep has 0 runs and 3 factors"
        );
        assert!(latin_hypercube(4, 0, 1).is_err());
    }
}
