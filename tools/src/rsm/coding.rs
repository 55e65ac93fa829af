//! Coded units: z = (x - centre) / half_range, so that a factor's low and high levels are
//! -1 and +1 (Design-Expert's and R `rsm`'s convention). Fits are done in coded units; the
//! equation in real units follows by substitution.

use serde::Serialize;

/// Each factor's low and high levels in real units.
#[derive(Debug, Clone, Serialize)]
pub struct Coding {
    pub low: Vec<f64>,
    pub high: Vec<f64>,
}

impl Coding {
    pub fn centre(&self, i: usize) -> f64 {
        0.5 * (self.low[i] + self.high[i])
    }

    pub fn half(&self, i: usize) -> f64 {
        0.5 * (self.high[i] - self.low[i])
    }

    /// Real settings -> coded.
    pub fn code(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(i, v)| (v - self.centre(i)) / self.half(i))
            .collect()
    }

    /// Coded settings -> real.
    pub fn real(&self, z: &[f64]) -> Vec<f64> {
        z.iter()
            .enumerate()
            .map(|(i, v)| self.centre(i) + v * self.half(i))
            .collect()
    }
}
