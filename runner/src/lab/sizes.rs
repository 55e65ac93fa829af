//! The soil's size mix in a test: the test's particle diameter d, plus a fine fraction when
//! the model has one (`[particles]`: a mass fraction `fine_fraction` of grains of diameter
//! `fine_diameter_ratio` x d). Real soils are never one size; a sandy loam's fines fill the
//! pores between the coarse grains, which changes packing, flow and strength (a candidate
//! effect, `[candidates.fines]` in models/li2022.toml).

use super::model::{At, Model, evaluate_at};
use crate::config::SizeClass;
use anyhow::{Result, anyhow, bail};
use std::f64::consts::PI;

/// Fine diameter / the test's diameter when the model does not say.
pub const DEFAULT_FINE_RATIO: f64 = 0.5;

/// Size classes: (diameter in m, mass fraction), fractions summing to 1.
#[derive(Debug, Clone, PartialEq)]
pub struct SizeMix {
    pub classes: Vec<(f64, f64)>,
}

impl SizeMix {
    /// The model's mix at `at` around the test's diameter `d`.
    pub fn of(model: &Model, at: At, d: f64) -> Result<SizeMix> {
        let path = model.path.display();
        let Some(p) = &model.file.particles else {
            return Ok(SizeMix {
                classes: vec![(d, 1.0)],
            });
        };
        let fine = match &p.fine_fraction {
            None => 0.0,
            Some(form) => evaluate_at(form, at)
                .map_err(|e| anyhow!("{path}: particles.fine_fraction: {e}"))?,
        };
        if !(0.0..=0.5).contains(&fine) {
            bail!(
                "{path}: particles.fine_fraction = {fine} is out of range: allowed [0, 0.5] (a mass fraction)"
            );
        }
        let ratio = p.fine_diameter_ratio.unwrap_or(DEFAULT_FINE_RATIO);
        if !(0.3..1.0).contains(&ratio) {
            bail!(
                "{path}: particles.fine_diameter_ratio = {ratio} is out of range: allowed [0.3, 1)"
            );
        }
        let mut classes = vec![(d, 1.0 - fine)];
        if fine > 0.0 {
            classes.push((ratio * d, fine));
        }
        Ok(SizeMix { classes })
    }

    /// Particles per m^3 of solid: sum of w_i / V_i.
    pub fn per_solid_volume(&self) -> f64 {
        self.classes
            .iter()
            .map(|&(d, w)| w / (PI * d.powi(3) / 6.0))
            .sum()
    }

    /// The number of particles that make `solid_volume` m^3 of solid, on average.
    pub fn count(&self, solid_volume: f64) -> usize {
        (solid_volume * self.per_solid_volume()).round() as usize
    }

    /// The smallest diameter (it sets the time step), m.
    pub fn min_diameter(&self) -> f64 {
        self.classes
            .iter()
            .map(|c| c.0)
            .fold(f64::INFINITY, f64::min)
    }

    /// The factory's `sizes` list (mass fractions: use with `basis = "mass"`).
    pub fn size_classes(&self) -> Vec<SizeClass> {
        self.classes
            .iter()
            .map(|&(diameter, fraction)| SizeClass { diameter, fraction })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_follow_the_mass_fractions() {
        let mix = SizeMix {
            classes: vec![(0.004, 0.8), (0.002, 0.2)],
        };
        let v = |d: f64| PI * d.powi(3) / 6.0;
        // 1 cm^3 of solid: 0.8 cm^3 of 4 mm grains and 0.2 cm^3 of 2 mm grains.
        let expect = 0.8e-6 / v(0.004) + 0.2e-6 / v(0.002);
        assert!((mix.per_solid_volume() * 1e-6 - expect).abs() < 1e-9 * expect);
        assert_eq!(mix.count(1e-6), expect.round() as usize);
        assert_eq!(mix.min_diameter(), 0.002);
    }
}
