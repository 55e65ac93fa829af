//! Owen-scrambled Sobol' points.

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};

use super::DesignError;

/// The most runs [`sobol`] gives: the `sobol_burley` generator indexes 2^16 points.
pub const SOBOL_MAX_RUNS: usize = 1 << 16;

/// The most factors [`sobol`] takes: the `sobol_burley` generator has 256 dimensions
/// (direction numbers of Joe & Kuo).
pub const SOBOL_MAX_FACTORS: usize = sobol_burley::NUM_DIMENSIONS as usize;

/// `runs` Owen-scrambled Sobol' points on `factors` factors in [-1, 1), from `seed`.
///
/// References: I. M. Sobol' (1967), "On the distribution of points in a cube and the
/// approximate evaluation of integrals", *USSR Computational Mathematics and Mathematical
/// Physics* 7(4):86-112; A. B. Owen (1995), "Randomly permuted (t,m,s)-nets and
/// (t,s)-sequences", *Monte Carlo and Quasi-Monte Carlo Methods*, Lecture Notes in
/// Statistics 106:299-317; B. Burley (2020), "Practical hash-based Owen scrambling",
/// *Journal of Computer Graphics Techniques* 9(4):1-20 (the `sobol_burley` crate); S. Joe
/// and F. Y. Kuo (2008), "Constructing Sobol sequences with better two-dimensional
/// projections", *SIAM J. Sci. Comput.* 30(5):2635-2654, for the direction numbers.
///
/// Row i is point i of the sequence, factor j its dimension j, mapped from [0, 1) to
/// [-1, 1) by x = 2u - 1. The scrambling is a nested uniform (Owen) scramble, which keeps
/// the net structure: for `runs` a power of two 2^m, every dimension puts exactly one point
/// in each of the 2^m equal strata of [-1, 1), and low-dimensional projections are
/// stratified as well. Prefer a power of two for that reason. The generator works in `f32`
/// (24-bit resolution), far finer than any factor setting a sweep needs.
///
/// Determinism: the generator takes a 32-bit seed, drawn as the first `next_u32` of
/// `ChaCha8Rng::seed_from_u64(seed)`, so neighbouring seeds give unrelated scrambles and
/// the same seed gives the same points everywhere. Two of the 2^64 seeds can share a 32-bit
/// seed (and so the same points); that is a 2^-32 chance for any given pair.
///
/// # Errors
/// `runs` outside 1..=[`SOBOL_MAX_RUNS`] or `factors` outside 1..=[`SOBOL_MAX_FACTORS`].
pub fn sobol(runs: usize, factors: usize, seed: u64) -> Result<Vec<Vec<f64>>, DesignError> {
    if !(1..=SOBOL_MAX_RUNS).contains(&runs) {
        return Err(DesignError::SobolRuns {
            max: SOBOL_MAX_RUNS,
            runs,
        });
    }
    if !(1..=SOBOL_MAX_FACTORS).contains(&factors) {
        return Err(DesignError::SobolFactors {
            max: SOBOL_MAX_FACTORS,
            factors,
        });
    }
    let seed32 = ChaCha8Rng::seed_from_u64(seed).next_u32();
    // The range checks above make both casts lossless.
    Ok((0..runs as u32)
        .map(|i| {
            (0..factors as u32)
                .map(|d| 2.0 * f64::from(sobol_burley::sample(i, d, seed32)) - 1.0)
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn stratum(x: f64, n: usize) -> usize {
        ((x + 1.0) / 2.0 * n as f64).floor() as usize
    }

    #[test]
    fn points_are_in_range() {
        let d = sobol(1000, 10, 3).unwrap();
        assert_eq!(d.len(), 1000);
        assert!(d.iter().all(|r| r.len() == 10));
        assert!(d.iter().flatten().all(|x| (-1.0..1.0).contains(x)));
    }

    #[test]
    fn deterministic_in_the_seed() {
        let bits =
            |d: Vec<Vec<f64>>| -> Vec<u64> { d.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(
            bits(sobol(64, 4, 11).unwrap()),
            bits(sobol(64, 4, 11).unwrap())
        );
        assert_ne!(
            bits(sobol(64, 4, 11).unwrap()),
            bits(sobol(64, 4, 12).unwrap())
        );
    }

    #[test]
    fn sixty_four_points_fill_sixty_four_strata_in_every_dimension() {
        // Each one-dimensional projection of the first 2^m Sobol' points is a (0,m,1)-net
        // in base 2, and Owen scrambling preserves that: one point per stratum of width
        // 1/2^m. Checked for several seeds and dimensions, including the last one.
        for seed in [0, 1, 99] {
            let d = sobol(64, SOBOL_MAX_FACTORS, seed).unwrap();
            for j in [0, 1, 2, 5, 17, SOBOL_MAX_FACTORS - 1] {
                let mut strata: Vec<usize> = d.iter().map(|r| stratum(r[j], 64)).collect();
                strata.sort_unstable();
                assert_eq!(
                    strata,
                    (0..64).collect::<Vec<_>>(),
                    "seed {seed}, dimension {j}"
                );
            }
        }
    }

    #[test]
    fn first_two_dimensions_form_a_two_dimensional_net() {
        // The first two Sobol' dimensions form a (0,m,2)-net: 64 points put one point in
        // each cell of an 8 x 8 grid (and of a 4 x 16 grid) over the square.
        let d = sobol(64, 2, 5).unwrap();
        for (nx, ny) in [(8, 8), (4, 16), (16, 4), (2, 32)] {
            let mut cells: Vec<usize> = d
                .iter()
                .map(|r| stratum(r[0], nx) * ny + stratum(r[1], ny))
                .collect();
            cells.sort_unstable();
            assert_eq!(cells, (0..64).collect::<Vec<_>>(), "{nx} x {ny} grid");
        }
    }

    #[test]
    fn errors_name_the_allowed_range() {
        assert_eq!(
            sobol(0, 2, 0).unwrap_err().to_string(),
            "a Sobol design takes 1 to 65536 runs; this sweep has 0"
        );
        assert_eq!(
            sobol(70_000, 2, 0).unwrap_err().to_string(),
            "a Sobol design takes 1 to 65536 runs; this sweep has 70000"
        );
        assert_eq!(
            sobol(8, 257, 0).unwrap_err().to_string(),
            "a Sobol design takes 1 to 256 factors; this sweep has 257"
        );
        assert!(sobol(SOBOL_MAX_RUNS, 1, 0).is_ok());
    }
}
