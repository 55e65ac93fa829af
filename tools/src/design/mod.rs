//! Experimental designs in coded units, for calibration sweeps.
//!
//! Every design is a `Vec<Vec<f64>>`: one row per run, one column per factor, in coded
//! units (-1..1 for two-level designs, ±alpha for the axial points of a central composite
//! design), in the standard order documented on each function. The caller maps coded units
//! to physical values and randomises the run order; keeping both out of here means a design
//! can be checked against its textbook table row by row.
//!
//! Centre points are not part of any design returned here, because how many to add is the
//! experimenter's choice (pure-error degrees of freedom against cost); append them with
//! [`with_centre_points`].
//!
//! One design per file:
//! - [`full_factorial`]: any number of levels per factor (Yates order).
//! - [`plackett_burman`]: two-level screening, Plackett & Burman (1946).
//! - [`box_behnken`]: three-level response surface, Box & Behnken (1960).
//! - [`central_composite`]: 2^k factorial plus axial points, Box & Wilson (1951).
//! - [`latin_hypercube`]: stratified random sampling, McKay, Beckman & Conover (1979).
//! - [`sobol`]: Owen-scrambled Sobol' points, Sobol' (1967), Owen (1995), Burley (2020).
//! - [`steepest_ascent`]: the path of steepest ascent, Box & Wilson (1951).

mod box_behnken;
mod central_composite;
mod error;
mod factorial;
mod latin_hypercube;
mod plackett_burman;
mod sobol;
mod steepest_ascent;

#[cfg(test)]
mod test_util;

pub use box_behnken::{box_behnken, box_behnken_default_centres};
pub use central_composite::{Alpha, central_composite};
pub use error::DesignError;
pub use factorial::{MAX_FACTORIAL_RUNS, full_factorial};
pub use latin_hypercube::latin_hypercube;
pub use plackett_burman::{plackett_burman, plackett_burman_size};
pub use sobol::{SOBOL_MAX_FACTORS, SOBOL_MAX_RUNS, sobol};
pub use steepest_ascent::steepest_ascent;

/// Appends `k` centre points (rows of zeros, as wide as the first row) to `rows`.
///
/// The designs in this module leave centre points to the caller; this is the one place
/// that adds them, so "how many" stays a visible decision at the call site. An empty
/// `rows` has no width to copy and is returned unchanged (no design here is empty).
pub fn with_centre_points(mut rows: Vec<Vec<f64>>, k: usize) -> Vec<Vec<f64>> {
    if let Some(width) = rows.first().map(Vec::len) {
        rows.extend(std::iter::repeat_n(vec![0.0; width], k));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_points_are_zero_rows_appended_at_the_end() {
        let rows = vec![vec![-1.0, 1.0], vec![1.0, -1.0]];
        let out = with_centre_points(rows.clone(), 3);
        assert_eq!(out.len(), 5);
        assert_eq!(&out[..2], &rows[..]);
        assert!(out[2..].iter().all(|r| r == &vec![0.0, 0.0]));
        assert!(with_centre_points(Vec::new(), 3).is_empty());
        assert_eq!(with_centre_points(rows.clone(), 0), rows);
    }
}
