//! Full factorial designs with any number of levels per factor.

use super::DesignError;

/// The largest full factorial [`full_factorial`] builds: 2^20 = 1,048,576 runs.
///
/// A full factorial's size is implicit in its levels and grows as a product, so a slip such
/// as 3 levels on 20 factors (3.5e9 runs) would otherwise end in an out-of-memory abort.
/// Every run of a DEM sweep costs minutes, so a design near this cap is already a mistake.
pub const MAX_FACTORIAL_RUNS: usize = 1 << 20;

/// The full factorial design on `levels[j]` levels of factor `j`, in Yates standard order.
///
/// Reference: F. Yates (1937), *The Design and Analysis of Factorial Experiments*, Imperial
/// Bureau of Soil Science, Technical Communication 35; Montgomery, *Design and Analysis of
/// Experiments*, ch. 5-6 and 9.
///
/// Factor `j`'s levels are evenly spaced on [-1, 1]: 2 levels give -1, 1; 3 give -1, 0, 1;
/// 5 give -1, -0.5, 0, 0.5, 1. Standard order: the first factor changes fastest, then the
/// second, and so on (the "Std" order of Design-Expert), so a 2^3 design runs
/// (-,-,-), (+,-,-), (-,+,-), (+,+,-), (-,-,+), (+,-,+), (-,+,+), (+,+,+).
/// The run count is the product of the levels.
///
/// # Errors
/// No factor, a factor with fewer than 2 levels, or more than [`MAX_FACTORIAL_RUNS`] runs.
pub fn full_factorial(levels: &[usize]) -> Result<Vec<Vec<f64>>, DesignError> {
    if levels.is_empty() {
        return Err(DesignError::FactorialNoFactors);
    }
    if let Some((j, &l)) = levels.iter().enumerate().find(|&(_, &l)| l < 2) {
        return Err(DesignError::FactorialTooFewLevels {
            factor: j + 1,
            levels: l,
        });
    }
    let runs = levels.iter().fold(1usize, |acc, &l| acc.saturating_mul(l));
    if runs > MAX_FACTORIAL_RUNS {
        return Err(DesignError::FactorialTooManyRuns {
            max: MAX_FACTORIAL_RUNS,
            runs,
        });
    }
    Ok((0..runs)
        .map(|run| {
            // Read the run index as a mixed-radix number whose lowest digit is factor 0:
            // that is what makes the first factor change fastest.
            let mut rest = run;
            levels
                .iter()
                .map(|&l| {
                    let digit = rest % l;
                    rest /= l;
                    coded_level(digit, l)
                })
                .collect()
        })
        .collect())
}

/// Level `digit` (0-based) of `levels` evenly spaced levels on [-1, 1].
///
/// Written as (2d - (L-1)) / (L-1) rather than -1 + 2d/(L-1) so that the middle level of an
/// odd count is exactly 0 and the levels are exactly symmetric about it.
pub(super) fn coded_level(digit: usize, levels: usize) -> f64 {
    let span = (levels - 1) as f64;
    (2.0 * digit as f64 - span) / span
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_cubed_is_in_yates_order() {
        let expected = vec![
            vec![-1.0, -1.0, -1.0],
            vec![1.0, -1.0, -1.0],
            vec![-1.0, 1.0, -1.0],
            vec![1.0, 1.0, -1.0],
            vec![-1.0, -1.0, 1.0],
            vec![1.0, -1.0, 1.0],
            vec![-1.0, 1.0, 1.0],
            vec![1.0, 1.0, 1.0],
        ];
        assert_eq!(full_factorial(&[2, 2, 2]).unwrap(), expected);
    }

    #[test]
    fn mixed_levels_count_spacing_and_order() {
        let d = full_factorial(&[3, 2, 5]).unwrap();
        assert_eq!(d.len(), 3 * 2 * 5);
        // First factor fastest: rows 0..3 step factor 0 through -1, 0, 1 at the others' lows.
        assert_eq!(d[0], vec![-1.0, -1.0, -1.0]);
        assert_eq!(d[1], vec![0.0, -1.0, -1.0]);
        assert_eq!(d[2], vec![1.0, -1.0, -1.0]);
        assert_eq!(d[3], vec![-1.0, 1.0, -1.0]);
        // Factor 2 (5 levels) moves every 3 * 2 = 6 runs.
        let third: Vec<f64> = d.iter().step_by(6).map(|r| r[2]).collect();
        assert_eq!(third, vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
        // Every combination appears once.
        let mut keys: Vec<String> = d.iter().map(|r| format!("{r:?}")).collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), 30);
    }

    #[test]
    fn one_factor_is_allowed() {
        assert_eq!(
            full_factorial(&[4]).unwrap(),
            vec![vec![-1.0], vec![-1.0 / 3.0], vec![1.0 / 3.0], vec![1.0]]
        );
    }

    #[test]
    fn errors_name_the_allowed_range() {
        let e = full_factorial(&[]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a full factorial design takes at least 1 factor; this sweep has 0"
        );
        let e = full_factorial(&[2, 1, 3]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "each factor of a full factorial design takes 2 or more levels; factor 2 has 1"
        );
        let e = full_factorial(&[2; 21]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a full factorial design takes at most 1048576 runs; these levels make 2097152"
        );
    }
}
