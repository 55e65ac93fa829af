//! The tilting-plate test: the angle at which a soil sample slides on steel (the inclinometer
//! of Li et al. 2022, table 1; docs/experiments.md).
//!
//! The plate's angle theta (degrees, `/scalars/plate_angle`) rises steadily; the sample's
//! speed down the slope v (m/s, `/scalars/slide_speed`, the median of its grains') stays
//! near zero while friction holds it (it creeps) and runs away once it slides. The slide
//! angle is theta where v first reaches the threshold `slide_speed_m_per_s` of
//! `tilth.experiment`, interpolated linearly between the two samples either side; the static
//! friction coefficient an inclinometer reports is tan(theta). A record that ends before v
//! reaches the threshold has no slide angle.

use super::error::ReduceError;
use super::read::{Run, RunSource};
use serde::{Deserialize, Serialize};

/// `tilth.experiment` type of a tilting-plate run.
pub const TILT: &str = "tilt";

/// The measurement, independent of the file it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TiltAnalysis {
    /// The plate's angle when the sample's speed reached `slide_speed_m_per_s`, degrees;
    /// `None` if it never did in the record.
    pub slide_angle_deg: Option<f64>,
    /// tan(slide angle), -.
    pub static_friction: Option<f64>,
    /// The speed that counts as sliding, m/s.
    pub slide_speed_m_per_s: f64,
    /// The largest angle the plate reached in the record, degrees.
    pub max_angle_deg: f64,
    /// The curve: (plate angle degrees, speed down the slope m/s), every sample in time
    /// order.
    pub curve: Vec<(f64, f64)>,
}

/// A tilting-plate run's result (one flat JSON object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TiltResult {
    #[serde(flatten)]
    pub source: RunSource,
    #[serde(flatten)]
    pub analysis: TiltAnalysis,
}

/// Reduces a tilting-plate run (scalars only; read it with [`super::CloudChoice::None`]).
pub fn tilt(run: &Run) -> Result<TiltResult, ReduceError> {
    run.expect_experiment(TILT)?;
    let threshold = run.experiment_number("slide_speed_m_per_s")?;
    let curve = run
        .scalar("plate_angle")?
        .paired(run.scalar("slide_speed")?);
    Ok(TiltResult {
        source: run.source(),
        analysis: analyse_tilt(curve, threshold),
    })
}

/// The slide angle on `curve` ((plate angle degrees, speed m/s) in time order) for a speed
/// `threshold` m/s.
pub fn analyse_tilt(curve: Vec<(f64, f64)>, threshold: f64) -> TiltAnalysis {
    let crossing = curve.windows(2).find_map(|w| {
        let ((a0, s0), (a1, s1)) = (w[0], w[1]);
        (s0 < threshold && s1 >= threshold).then(|| a0 + (a1 - a0) * (threshold - s0) / (s1 - s0))
    });
    let at_start = curve.first().filter(|p| p.1 >= threshold).map(|p| p.0);
    let slide_angle_deg = at_start.or(crossing);
    TiltAnalysis {
        slide_angle_deg,
        static_friction: slide_angle_deg.map(|a| a.to_radians().tan()),
        slide_speed_m_per_s: threshold,
        max_angle_deg: curve.iter().map(|p| p.0).fold(0.0, f64::max),
        curve,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A block that holds until 37 degrees and then speeds up by 1 mm/s per 0.1 degree.
    fn curve() -> Vec<(f64, f64)> {
        (0..=500)
            .map(|k| {
                let a = 0.1 * k as f64;
                (a, 1e-3 * (a - 37.0).max(0.0))
            })
            .collect()
    }

    #[test]
    fn the_slide_angle_is_where_the_travel_reaches_the_threshold() {
        let a = analyse_tilt(curve(), 4e-4);
        let angle = a.slide_angle_deg.unwrap();
        assert!((angle - 37.4).abs() < 1e-9, "{angle}");
        let mu = a.static_friction.unwrap();
        assert!((mu - 37.4f64.to_radians().tan()).abs() < 1e-12);
        assert_eq!(a.max_angle_deg, 50.0);
    }

    #[test]
    fn a_record_that_ends_before_the_slide_has_no_angle() {
        let a = analyse_tilt(curve().into_iter().take(370).collect(), 4e-4);
        assert_eq!(a.slide_angle_deg, None);
        assert_eq!(a.static_friction, None);
    }
}
