//! The funnel's mass flow rate, as a flowmeter funnel (ASTM B213's Hall flowmeter, ISO 4490)
//! measures it: how fast the soil leaves the outlet.
//!
//! The fraction of the poured particles below the outlet plane is sampled as the run goes;
//! the times at which it crosses 20 % and 80 % are interpolated linearly between samples, and
//!
//!   W = 0.6 M / (t80 - t20)   [g/s]
//!
//! with M the poured mass. The middle 60 % leaves out the start (the first grains fall
//! freely, before the funnel flows as a bulk) and the end (the last grains trickle off the
//! walls); in between the flow is steady, which is what Beverloo's law describes
//! (W = C rho_b sqrt(g) (D - k d)^(5/2); Beverloo, Leniger & van de Velde 1961). Cohesion and
//! wall friction slow it; rolling resistance between grains much less: that is why it is
//! measured beside the heap angle.

/// The two fractions between which the rate is measured.
const FROM: f64 = 0.2;
const TO: f64 = 0.8;

/// Samples of (time, fraction of the particles below the outlet).
#[derive(Debug, Clone, Default)]
pub struct Discharge {
    samples: Vec<(f64, f64)>,
}

impl Discharge {
    /// Records the fraction `passed` (0..1) at `time`, s.
    pub fn sample(&mut self, time: f64, passed: f64) {
        self.samples.push((time, passed));
    }

    /// Whether the sampling can stop: the last sample is past 80 %.
    pub fn done(&self) -> bool {
        self.samples.last().is_some_and(|&(_, f)| f >= TO)
    }

    /// When the fraction first reached `level`, interpolated between samples.
    fn crossing(&self, level: f64) -> Option<f64> {
        let k = self.samples.iter().position(|&(_, f)| f >= level)?;
        if k == 0 {
            return Some(self.samples[0].0);
        }
        let ((t0, f0), (t1, f1)) = (self.samples[k - 1], self.samples[k]);
        Some(t0 + (t1 - t0) * (level - f0) / (f1 - f0))
    }

    /// W = 0.6 M / (t80 - t20), g/s, for `mass_g` poured; None until 80 % has passed.
    pub fn rate_g_per_s(&self, mass_g: f64) -> Option<f64> {
        let (a, b) = (self.crossing(FROM)?, self.crossing(TO)?);
        (b > a).then(|| (TO - FROM) * mass_g / (b - a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_steady_flow_gives_its_rate() {
        // 10 % of 40 g per 10 ms: 400 g/s, sampled every 3 ms (crossings between samples).
        let mut d = Discharge::default();
        for k in 0..60 {
            let t = 0.003 * k as f64;
            d.sample(t, (10.0 * (t - 0.01)).clamp(0.0, 1.0));
        }
        let w = d.rate_g_per_s(40.0).unwrap();
        assert!((w - 400.0).abs() < 1e-9, "{w}");
        assert!(d.done());
    }

    #[test]
    fn no_rate_before_eighty_percent() {
        let mut d = Discharge::default();
        d.sample(0.0, 0.0);
        d.sample(0.1, 0.5);
        assert_eq!(d.rate_g_per_s(40.0), None);
        assert!(!d.done());
    }
}
