//! Central composite designs: a 2^k factorial plus 2k axial points.

use super::{DesignError, full_factorial};

/// The axial distance of a central composite design, in coded units.
///
/// Reference: Box & Wilson (1951) for the design; Box & Hunter (1957), "Multi-factor
/// experimental designs for exploring response surfaces", *Annals of Mathematical
/// Statistics* 28(1):195-241, for rotatability; Montgomery, *Design and Analysis of
/// Experiments*, ch. 11.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Alpha {
    /// alpha = (2^k)^(1/4), the fourth root of the number of factorial points: the
    /// prediction variance then depends only on the distance from the centre.
    Rotatable,
    /// alpha = 1: the axial points sit on the faces of the cube, so every factor takes only
    /// the levels -1, 0, 1 (for factors whose range cannot be exceeded).
    FaceCentred,
    /// A given alpha, finite and above 0.
    Value(f64),
}

impl Alpha {
    /// The axial distance for a design on `factors` factors.
    pub fn value(self, factors: usize) -> f64 {
        match self {
            // (2^k)^(1/4) = 2^(k/4), computed in the second form so no 2^k is formed.
            Alpha::Rotatable => 2f64.powf(factors as f64 / 4.0),
            Alpha::FaceCentred => 1.0,
            Alpha::Value(a) => a,
        }
    }
}

/// The central composite design on `factors` factors (2 to 8), without centre points.
///
/// Reference: G. E. P. Box and K. B. Wilson (1951), "On the experimental attainment of
/// optimum conditions", *Journal of the Royal Statistical Society B* 13(1):1-45; Montgomery,
/// *Design and Analysis of Experiments*, ch. 11.
///
/// Standard order: first the 2^k full factorial at ±1 in Yates order (first factor
/// fastest, see [`full_factorial`]), then the 2k axial points factor by factor:
/// (-alpha, 0, ..., 0), (+alpha, 0, ..., 0), (0, -alpha, 0, ...), (0, +alpha, 0, ...), ...
/// Runs: 2^k + 2k. alpha comes from [`Alpha::value`]. The caller appends centre points
/// (see [`super::with_centre_points`]).
///
/// # Errors
/// `factors` outside 2..=8, or an [`Alpha::Value`] that is not finite and above 0.
pub fn central_composite(factors: usize, alpha: Alpha) -> Result<Vec<Vec<f64>>, DesignError> {
    if !(2..=8).contains(&factors) {
        return Err(DesignError::CentralCompositeFactors { factors });
    }
    let a = alpha.value(factors);
    if !(a.is_finite() && a > 0.0) {
        return Err(DesignError::CentralCompositeAlpha { alpha: a });
    }
    let mut rows = full_factorial(&vec![2; factors])?;
    for j in 0..factors {
        for sign in [-1.0, 1.0] {
            let mut row = vec![0.0; factors];
            row[j] = sign * a;
            rows.push(row);
        }
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_count_is_two_to_the_k_plus_two_k() {
        for k in 2..=8 {
            let d = central_composite(k, Alpha::Rotatable).unwrap();
            assert_eq!(d.len(), (1 << k) + 2 * k, "{k} factors");
        }
    }

    #[test]
    fn rotatable_alpha_is_the_fourth_root_of_the_factorial_runs() {
        // Textbook values: 1.414 (k=2), 1.682 (k=3), 2 (k=4), 2.378 (k=5).
        let expected = [
            (2, 2f64.sqrt()),
            (3, 8f64.sqrt().sqrt()),
            (4, 2.0),
            (5, 32f64.sqrt().sqrt()),
            (8, 4.0),
        ];
        for (k, a) in expected {
            assert!((Alpha::Rotatable.value(k) - a).abs() < 1e-12, "{k} factors");
        }
        assert!((Alpha::Rotatable.value(3) - 1.681_792_830_507_429).abs() < 1e-12);
        // The axial points of a rotatable 3-factor design sit at ±1.6818 on each axis.
        let d = central_composite(3, Alpha::Rotatable).unwrap();
        let a = 8f64.sqrt().sqrt();
        assert!((d[8][0] + a).abs() < 1e-12 && (d[9][0] - a).abs() < 1e-12);
    }

    #[test]
    fn face_centred_two_factors_written_out() {
        let expected = vec![
            vec![-1.0, -1.0],
            vec![1.0, -1.0],
            vec![-1.0, 1.0],
            vec![1.0, 1.0],
            vec![-1.0, 0.0],
            vec![1.0, 0.0],
            vec![0.0, -1.0],
            vec![0.0, 1.0],
        ];
        assert_eq!(central_composite(2, Alpha::FaceCentred).unwrap(), expected);
        assert_eq!(Alpha::FaceCentred.value(5), 1.0);
    }

    #[test]
    fn given_alpha_is_used_as_is() {
        let d = central_composite(4, Alpha::Value(1.5)).unwrap();
        assert_eq!(d[16], vec![-1.5, 0.0, 0.0, 0.0]);
        assert_eq!(d[23], vec![0.0, 0.0, 0.0, 1.5]);
    }

    #[test]
    fn errors_name_the_allowed_range() {
        for k in [1, 9] {
            assert_eq!(
                central_composite(k, Alpha::Rotatable)
                    .unwrap_err()
                    .to_string(),
                format!("a central composite design takes 2 to 8 factors; this sweep has {k}")
            );
        }
        assert_eq!(
            central_composite(3, Alpha::Value(-1.0))
                .unwrap_err()
                .to_string(),
            "a central composite design's axial distance alpha must be a finite number above 0; \
             this sweep has -1"
        );
        assert!(central_composite(3, Alpha::Value(f64::NAN)).is_err());
    }
}
