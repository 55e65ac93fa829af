//! Checks shared by the design tests: balance and orthogonality of design columns.

/// Sum of column `j` over all runs.
pub fn column_sum(d: &[Vec<f64>], j: usize) -> f64 {
    d.iter().map(|r| r[j]).sum()
}

/// Dot product of columns `a` and `b` over all runs.
pub fn column_dot(d: &[Vec<f64>], a: usize, b: usize) -> f64 {
    d.iter().map(|r| r[a] * r[b]).sum()
}

/// Asserts every column sums to 0 and every pair of columns has dot product 0.
///
/// The entries are small integers (or exact sums of them), so the sums are exact and an
/// exact comparison is the right test: any non-zero value is a wrong design.
pub fn assert_balanced_and_orthogonal(d: &[Vec<f64>]) {
    let k = d[0].len();
    for j in 0..k {
        assert_eq!(column_sum(d, j), 0.0, "column {j} is not balanced");
        for b in j + 1..k {
            assert_eq!(
                column_dot(d, j, b),
                0.0,
                "columns {j} and {b} are not orthogonal"
            );
        }
    }
}
