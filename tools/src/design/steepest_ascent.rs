//! The path of steepest ascent from a first-order model.

use super::DesignError;

/// `steps` points on the path of steepest ascent from `origin` along `direction`, in coded
/// units.
///
/// References: G. E. P. Box and K. B. Wilson (1951), "On the experimental attainment of
/// optimum conditions", *Journal of the Royal Statistical Society B* 13(1):1-45;
/// D. C. Montgomery, *Design and Analysis of Experiments*, ch. 11 (the method of steepest
/// ascent).
///
/// `direction` is normally the first-order coefficients b_1..b_k of a model fitted in coded
/// units. The factor with the largest |b_i| moves by `step` coded units per point; every
/// other factor moves by step * b_i / |b_max|, sign kept, so the path follows the gradient.
/// Point p (p = 0..steps-1) is origin + p * step * b / |b_max|; point 0 is the origin. Each
/// point is computed from the origin, not from the previous point, so no rounding builds up
/// along the path. For the path of steepest descent pass the negated direction.
///
/// # Errors
/// `direction` and `origin` empty or of different lengths, a non-finite entry in either, an
/// all-zero `direction`, or a `step` that is not finite and above 0.
pub fn steepest_ascent(
    direction: &[f64],
    origin: &[f64],
    step: f64,
    steps: usize,
) -> Result<Vec<Vec<f64>>, DesignError> {
    if direction.is_empty() || direction.len() != origin.len() {
        return Err(DesignError::SteepestAscentLengths {
            direction: direction.len(),
            origin: origin.len(),
        });
    }
    for (what, values) in [("direction", direction), ("origin", origin)] {
        if let Some((i, &value)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(DesignError::SteepestAscentNotFinite {
                what,
                factor: i + 1,
                value,
            });
        }
    }
    if !(step.is_finite() && step > 0.0) {
        return Err(DesignError::SteepestAscentStep { step });
    }
    let largest = direction.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    if largest == 0.0 {
        return Err(DesignError::SteepestAscentZeroDirection);
    }
    Ok((0..steps)
        .map(|p| {
            let along = p as f64 * step / largest;
            origin
                .iter()
                .zip(direction)
                .map(|(o, d)| o + along * d)
                .collect()
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(got: &[Vec<f64>], want: &[Vec<f64>]) {
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(want) {
            assert_eq!(g.len(), w.len());
            for (a, b) in g.iter().zip(w) {
                assert!((a - b).abs() < 1e-12, "got {g:?}, want {w:?}");
            }
        }
    }

    #[test]
    fn montgomery_example() {
        // Montgomery's first-order model y = 40.44 + 0.775 x1 + 0.325 x2: x1 moves 1 coded
        // unit per step, x2 moves 0.325 / 0.775 = 13/31 = 0.41935... per step.
        let path = steepest_ascent(&[0.775, 0.325], &[0.0, 0.0], 1.0, 4).unwrap();
        let r = 13.0 / 31.0;
        assert_close(
            &path,
            &[
                vec![0.0, 0.0],
                vec![1.0, r],
                vec![2.0, 2.0 * r],
                vec![3.0, 3.0 * r],
            ],
        );
    }

    #[test]
    fn largest_magnitude_leads_and_signs_are_kept() {
        // Factor 2 has the largest |b| = 2 and a negative sign: it moves -0.5 per step;
        // factor 1 moves 0.5 * 1 / 2 = 0.25, factor 3 moves 0.5 * (-0.5) / 2 = -0.125.
        let path = steepest_ascent(&[1.0, -2.0, -0.5], &[0.2, 0.0, -0.4], 0.5, 3).unwrap();
        assert_close(
            &path,
            &[
                vec![0.2, 0.0, -0.4],
                vec![0.45, -0.5, -0.525],
                vec![0.7, -1.0, -0.65],
            ],
        );
    }

    #[test]
    fn descent_is_the_negated_direction() {
        let up = steepest_ascent(&[3.0, 1.0], &[0.0, 0.0], 1.0, 3).unwrap();
        let down = steepest_ascent(&[-3.0, -1.0], &[0.0, 0.0], 1.0, 3).unwrap();
        for (u, d) in up.iter().zip(&down) {
            assert_eq!(u.iter().map(|x| -x).collect::<Vec<_>>(), *d);
        }
        assert!(steepest_ascent(&[3.0], &[0.0], 1.0, 0).unwrap().is_empty());
    }

    #[test]
    fn errors_name_the_allowed_range() {
        assert_eq!(
            steepest_ascent(&[0.0, 0.0], &[0.0, 0.0], 1.0, 3)
                .unwrap_err()
                .to_string(),
            "a steepest-ascent direction needs at least 1 non-zero component; this sweep's is all zeros"
        );
        assert_eq!(
            steepest_ascent(&[1.0, 0.5, 0.2], &[0.0, 0.0], 1.0, 3)
                .unwrap_err()
                .to_string(),
            "a steepest-ascent path needs a direction and an origin with the same number of \
             factors (1 or more); this sweep has 3 and 2"
        );
        assert!(steepest_ascent(&[], &[], 1.0, 3).is_err());
        assert_eq!(
            steepest_ascent(&[1.0, f64::NAN], &[0.0, 0.0], 1.0, 3)
                .unwrap_err()
                .to_string(),
            "a steepest-ascent direction takes finite numbers only; this sweep's has NaN at factor 2"
        );
        assert_eq!(
            steepest_ascent(&[1.0], &[0.0], 0.0, 3)
                .unwrap_err()
                .to_string(),
            "a steepest-ascent step must be a finite number of coded units above 0; this sweep has 0"
        );
    }
}
