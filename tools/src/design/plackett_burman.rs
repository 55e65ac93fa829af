//! Plackett-Burman two-level screening designs.

use super::DesignError;

/// The cyclic generators of Plackett & Burman (1946) for N = 8, 12, 16, 20, 24, written as
/// the signs of the first column (N - 1 entries each). Kept as text so each line can be
/// read against the paper's table.
const GENERATORS: [(usize, &str); 5] = [
    (8, "+++-+--"),
    (12, "++-+++---+-"),
    (16, "++++-+-++--+---"),
    (20, "++--++++-+-+----++-"),
    (24, "+++++-+-++--++--+-+----"),
];

/// The Plackett-Burman design of `runs` runs on the first `factors` columns.
///
/// Reference: R. L. Plackett and J. P. Burman (1946), "The design of optimum multifactorial
/// experiments", *Biometrika* 33(4):305-325.
///
/// `runs` is one of 8, 12, 16, 20, 24 and `factors` is 2 to `runs - 1`. The construction is
/// the paper's cyclic one: the generator g (length N-1) is the first column, and each next
/// column is the previous one shifted down cyclically by one, so for rows i = 0..N-2,
/// x\[i\]\[j\] = g\[(i - j) mod (N-1)\]; the last row is all -1. The full N-1 columns are
/// balanced (each column has N/2 runs at +1) and pairwise orthogonal, so every main effect
/// is estimated with the same variance as in a full factorial. Standard order is the row
/// order just described. Unused columns are the dummy factors an analyst may keep to
/// estimate error; they are left out here, not returned.
///
/// # Errors
/// `runs` not in {8, 12, 16, 20, 24}, or `factors` outside 2..=runs-1.
pub fn plackett_burman(runs: usize, factors: usize) -> Result<Vec<Vec<f64>>, DesignError> {
    let generator = GENERATORS
        .iter()
        .find(|&&(n, _)| n == runs)
        .map(|&(_, g)| g)
        .ok_or(DesignError::PlackettBurmanRuns { runs })?;
    if !(2..runs).contains(&factors) {
        return Err(DesignError::PlackettBurmanFactors { runs, factors });
    }
    let g: Vec<f64> = generator
        .chars()
        .map(|c| if c == '+' { 1.0 } else { -1.0 })
        .collect();
    let m = runs - 1;
    let mut rows: Vec<Vec<f64>> = (0..m)
        // (i - j) mod m, kept non-negative by adding m before subtracting j (j < m).
        .map(|i| (0..factors).map(|j| g[(i + m - j) % m]).collect())
        .collect();
    rows.push(vec![-1.0; factors]);
    Ok(rows)
}

/// The smallest Plackett-Burman run count (8, 12, 16, 20 or 24) that takes `factors`
/// factors, i.e. the least N with `factors <= N - 1`.
///
/// Reference: Plackett & Burman (1946), as for [`plackett_burman`].
///
/// # Errors
/// `factors` outside 2..=23.
pub fn plackett_burman_size(factors: usize) -> Result<usize, DesignError> {
    if factors < 2 {
        return Err(DesignError::PlackettBurmanSize { factors });
    }
    GENERATORS
        .iter()
        .map(|&(n, _)| n)
        .find(|&n| factors < n)
        .ok_or(DesignError::PlackettBurmanSize { factors })
}

#[cfg(test)]
mod tests {
    use super::super::test_util::assert_balanced_and_orthogonal;
    use super::*;

    #[test]
    fn every_size_is_balanced_and_orthogonal_on_all_columns() {
        for n in [8, 12, 16, 20, 24] {
            let d = plackett_burman(n, n - 1).unwrap();
            assert_eq!(d.len(), n);
            assert!(d.iter().all(|r| r.len() == n - 1));
            assert!(d.iter().flatten().all(|&x| x == 1.0 || x == -1.0));
            assert_balanced_and_orthogonal(&d);
        }
    }

    #[test]
    fn twelve_runs_seven_factors_is_the_published_design() {
        // The 12 runs of a published 7-factor screening study, as a set.
        let published: [[i8; 7]; 12] = [
            [1, -1, 1, -1, -1, -1, 1],
            [1, -1, 1, 1, -1, 1, -1],
            [-1, 1, 1, 1, -1, 1, 1],
            [-1, 1, 1, -1, 1, -1, -1],
            [1, 1, 1, -1, 1, 1, -1],
            [-1, -1, -1, 1, 1, 1, -1],
            [-1, -1, 1, 1, 1, -1, 1],
            [1, -1, -1, -1, 1, 1, 1],
            [1, 1, -1, 1, -1, -1, -1],
            [-1, 1, -1, -1, -1, 1, 1],
            [1, 1, -1, 1, 1, -1, 1],
            [-1, -1, -1, -1, -1, -1, -1],
        ];
        let mut expected: Vec<Vec<f64>> = published
            .iter()
            .map(|r| r.iter().map(|&x| f64::from(x)).collect())
            .collect();
        let mut got = plackett_burman(12, 7).unwrap();
        let key = |a: &Vec<f64>, b: &Vec<f64>| a.partial_cmp(b).unwrap();
        expected.sort_by(key);
        got.sort_by(key);
        assert_eq!(got, expected);
    }

    #[test]
    fn first_column_is_the_generator_and_columns_shift_down() {
        let d = plackett_burman(8, 7).unwrap();
        let first: Vec<f64> = d[..7].iter().map(|r| r[0]).collect();
        assert_eq!(first, vec![1.0, 1.0, 1.0, -1.0, 1.0, -1.0, -1.0]);
        // Column 1 is column 0 shifted down by one: its top entry is column 0's last.
        let second: Vec<f64> = d[..7].iter().map(|r| r[1]).collect();
        assert_eq!(second, vec![-1.0, 1.0, 1.0, 1.0, -1.0, 1.0, -1.0]);
        assert_eq!(d[7], vec![-1.0; 7]);
    }

    #[test]
    fn fewer_factors_take_the_first_columns() {
        let all = plackett_burman(20, 19).unwrap();
        let some = plackett_burman(20, 5).unwrap();
        for (a, s) in all.iter().zip(&some) {
            assert_eq!(&a[..5], &s[..]);
        }
    }

    #[test]
    fn size_is_the_smallest_that_fits() {
        let cases = [
            (2, 8),
            (7, 8),
            (8, 12),
            (11, 12),
            (12, 16),
            (15, 16),
            (19, 20),
            (23, 24),
        ];
        for (factors, n) in cases {
            assert_eq!(plackett_burman_size(factors), Ok(n), "{factors} factors");
        }
    }

    #[test]
    fn errors_name_the_allowed_range() {
        let msg = |e: DesignError| e.to_string();
        assert_eq!(
            msg(plackett_burman(12, 13).unwrap_err()),
            "a 12-run Plackett-Burman design takes 2 to 11 factors; this sweep has 13"
        );
        assert_eq!(
            msg(plackett_burman(8, 1).unwrap_err()),
            "an 8-run Plackett-Burman design takes 2 to 7 factors; this sweep has 1"
        );
        assert_eq!(
            msg(plackett_burman(10, 3).unwrap_err()),
            "a Plackett-Burman design has 8, 12, 16, 20 or 24 runs; this sweep asks for 10"
        );
        assert_eq!(
            msg(plackett_burman_size(24).unwrap_err()),
            "a Plackett-Burman design takes 2 to 23 factors; this sweep has 24"
        );
        assert!(plackett_burman_size(1).is_err());
    }
}
