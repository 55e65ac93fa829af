//! Box-Behnken three-level response-surface designs.

use super::DesignError;

/// The incomplete blocks of Box & Behnken (1960) for 6 factors (1-based, as in the paper):
/// a partially balanced design in which each factor is in 3 blocks.
const BLOCKS_6: [[usize; 3]; 6] = [
    [1, 2, 4],
    [2, 3, 5],
    [3, 4, 6],
    [1, 4, 5],
    [2, 5, 6],
    [1, 3, 6],
];

/// The incomplete blocks of Box & Behnken (1960) for 7 factors (1-based): the balanced
/// incomplete block design of the Fano plane, in which every pair of factors shares exactly
/// one block.
const BLOCKS_7: [[usize; 3]; 7] = [
    [4, 5, 6],
    [1, 6, 7],
    [2, 5, 7],
    [1, 2, 4],
    [3, 4, 7],
    [1, 3, 5],
    [2, 3, 6],
];

/// The Box-Behnken design on `factors` factors (3 to 7), without centre points.
///
/// Reference: G. E. P. Box and D. W. Behnken (1960), "Some new three level designs for the
/// study of quantitative variables", *Technometrics* 2(4):455-475.
///
/// Each design is an incomplete block design crossed with a two-level factorial: for every
/// block, the factors in the block run through a full 2^m factorial at ±1 (first factor of
/// the block fastest, as in Yates order) while the other factors sit at 0.
/// - 3, 4, 5 factors: the blocks are all pairs, in lexicographic order (AB, AC, ..., BC,
///   ...), each a 2^2 factorial in the order (-,-), (+,-), (-,+), (+,+). Runs: 12, 24, 40.
/// - 6 factors: blocks {1,2,4}, {2,3,5}, {3,4,6}, {1,4,5}, {2,5,6}, {1,3,6}, each a 2^3
///   factorial: 48 runs.
/// - 7 factors: blocks {4,5,6}, {1,6,7}, {2,5,7}, {1,2,4}, {3,4,7}, {1,3,5}, {2,3,6}, each a
///   2^3 factorial: 56 runs.
///
/// A Box-Behnken design needs centre points to estimate the pure quadratic terms; see
/// [`box_behnken_default_centres`] and [`super::with_centre_points`].
///
/// # Errors
/// `factors` outside 3..=7.
pub fn box_behnken(factors: usize) -> Result<Vec<Vec<f64>>, DesignError> {
    let blocks: Vec<Vec<usize>> = match factors {
        3..=5 => (0..factors)
            .flat_map(|a| (a + 1..factors).map(move |b| vec![a, b]))
            .collect(),
        6 => to_zero_based(&BLOCKS_6),
        7 => to_zero_based(&BLOCKS_7),
        _ => return Err(DesignError::BoxBehnkenFactors { factors }),
    };
    let mut rows = Vec::new();
    for block in &blocks {
        for run in 0..1usize << block.len() {
            let mut row = vec![0.0; factors];
            for (bit, &factor) in block.iter().enumerate() {
                // Bit `bit` of the run index is the sign of the block's `bit`-th factor, so
                // the block's first factor changes fastest (Yates order).
                row[factor] = if run >> bit & 1 == 1 { 1.0 } else { -1.0 };
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

fn to_zero_based(blocks: &[[usize; 3]]) -> Vec<Vec<usize>> {
    blocks
        .iter()
        .map(|b| b.iter().map(|&f| f - 1).collect())
        .collect()
}

/// The number of centre points Box & Behnken (1960) tabulate with the design on `factors`
/// factors: 3 for 3 and 4 factors, 6 for 5, 6 and 7 factors (15, 27, 46, 54 and 62 runs in
/// all). `None` outside 3..=7.
///
/// Reference: Box & Behnken (1960), as for [`box_behnken`]; the same counts are the
/// defaults of MATLAB's `bbdesign`.
///
/// Why the paper's counts: they are the citable ones. Design-Expert is commonly reported to
/// default to 5 centre points for 3 and 4 factors (17 and 29 runs); a sweep reproducing
/// such a study should pass its own count to [`super::with_centre_points`].
pub fn box_behnken_default_centres(factors: usize) -> Option<usize> {
    match factors {
        3 | 4 => Some(3),
        5..=7 => Some(6),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::assert_balanced_and_orthogonal;
    use super::*;

    #[test]
    fn three_factors_written_out() {
        let (m, p) = (-1.0, 1.0);
        let expected = vec![
            // AB
            vec![m, m, 0.0],
            vec![p, m, 0.0],
            vec![m, p, 0.0],
            vec![p, p, 0.0],
            // AC
            vec![m, 0.0, m],
            vec![p, 0.0, m],
            vec![m, 0.0, p],
            vec![p, 0.0, p],
            // BC
            vec![0.0, m, m],
            vec![0.0, p, m],
            vec![0.0, m, p],
            vec![0.0, p, p],
        ];
        assert_eq!(box_behnken(3).unwrap(), expected);
    }

    #[test]
    fn run_counts() {
        // Pairs: 4 * C(k, 2); blocks of three: 8 * number of blocks.
        for (k, runs) in [(3, 12), (4, 24), (5, 40), (6, 48), (7, 56)] {
            let d = box_behnken(k).unwrap();
            assert_eq!(d.len(), runs, "{k} factors");
            assert!(d.iter().all(|r| r.len() == k));
        }
    }

    #[test]
    fn balanced_orthogonal_and_equireplicated() {
        for k in 3..=7 {
            let d = box_behnken(k).unwrap();
            assert!(d.iter().flatten().all(|&x| [-1.0, 0.0, 1.0].contains(&x)));
            assert_balanced_and_orthogonal(&d);
            // Each factor is non-zero in the same number of runs: 8 for 3 factors (2 pairs
            // of 4), 12 for 4, 16 for 5, 24 for 6 and 7 (3 blocks of 8).
            let expected = [8, 12, 16, 24, 24][k - 3];
            for j in 0..k {
                let nonzero = d.iter().filter(|r| r[j] != 0.0).count();
                assert_eq!(nonzero, expected, "{k} factors, factor {j}");
            }
        }
    }

    #[test]
    fn every_pair_meets_at_all_four_corners() {
        for k in 3..=7 {
            let d = box_behnken(k).unwrap();
            for a in 0..k {
                for b in a + 1..k {
                    for (sa, sb) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                        assert!(
                            d.iter().any(|r| r[a] == sa && r[b] == sb),
                            "{k} factors: pair ({a}, {b}) never at ({sa}, {sb})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn blocks_of_six_and_seven_are_two_cubed_in_yates_order() {
        // First block of 7 factors is {4,5,6}: factor 4 fastest.
        let d = box_behnken(7).unwrap();
        let block: Vec<[f64; 3]> = d[..8].iter().map(|r| [r[3], r[4], r[5]]).collect();
        let m = -1.0;
        assert_eq!(
            block,
            vec![
                [m, m, m],
                [1.0, m, m],
                [m, 1.0, m],
                [1.0, 1.0, m],
                [m, m, 1.0],
                [1.0, m, 1.0],
                [m, 1.0, 1.0],
                [1.0, 1.0, 1.0],
            ]
        );
        assert!(
            d[..8]
                .iter()
                .all(|r| r[0] == 0.0 && r[1] == 0.0 && r[2] == 0.0 && r[6] == 0.0)
        );
        // Second block of 6 factors is {2,3,5}.
        let d = box_behnken(6).unwrap();
        assert_eq!(d[9], vec![0.0, 1.0, -1.0, 0.0, -1.0, 0.0]);
    }

    #[test]
    fn default_centres_follow_the_paper() {
        let counts: Vec<_> = (2..=8).map(box_behnken_default_centres).collect();
        assert_eq!(
            counts,
            vec![None, Some(3), Some(3), Some(6), Some(6), Some(6), None]
        );
    }

    #[test]
    fn errors_name_the_allowed_range() {
        for k in [0, 2, 8] {
            assert_eq!(
                box_behnken(k).unwrap_err().to_string(),
                format!("a Box-Behnken design takes 3 to 7 factors; this sweep has {k}")
            );
        }
    }
}
