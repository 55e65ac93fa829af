//! `capillary`: pendular liquid bridge (moisture), acting across a gap.
//!
//! Willett et al. (2000) closed form for equal spheres, with R* for unequal ones:
//!   F = 2 pi R* gamma_lv cos(theta) / (1 + 1.05 s + 2.5 s^2),  s = S sqrt(R*/V)
//! (N, attractive), S the gap (m, 0 while touching), V the bridge volume (m^3), gamma_lv the
//! liquid surface tension (N/m), theta the contact angle. The bridge forms when the particles
//! touch and ruptures at the gap S_c = (1 + theta/2) V^(1/3) (theta in radians; Lian et al. 1993).
//!
//! Reference: Willett, Adams, Johnson, Seville (2000) Langmuir 16:9396; Lian, Thornton, Adams
//! (1993) J. Colloid Interface Sci. 161:138. This file is the worked example of
//! `kernel/ADDING_A_LAW.md`.
//!
//! ```
//! use tilth_kernel::contact::laws::capillary::bridge_force;
//! // Touching spheres: the full 2 pi R* gamma cos(theta).
//! let f = bridge_force(5e-4, 0.072, 0.0, 1e-12, 0.0);
//! assert!((f - 2.0 * std::f64::consts::PI * 5e-4 * 0.072).abs() < 1e-15);
//! ```

use crate::contact::{BuiltLaw, Contact, ExtraLaw, LawEntry, LawInput, Slot};
use crate::param::{Bound, ParamSpec};
use std::f64::consts::PI;

pub const BRIDGE_VOLUME: ParamSpec = ParamSpec {
    key: "bridge_volume",
    unit: "m^3",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "liquid bridge volume V",
};
pub const SURFACE_TENSION: ParamSpec = ParamSpec {
    key: "surface_tension",
    unit: "N/m",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: Some(0.072),
    doc: "liquid surface tension gamma_lv (water at 25 C: 0.072)",
};
pub const CONTACT_ANGLE: ParamSpec = ParamSpec {
    key: "contact_angle",
    unit: "deg",
    min: Bound::Closed(0.0),
    max: Bound::Open(90.0),
    default: Some(0.0),
    doc: "liquid-solid contact angle theta",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "capillary",
    slot: Slot::Extra,
    summary: "pendular liquid bridge (Willett 2000), ruptures at (1 + theta/2) V^(1/3)",
    params: &[BRIDGE_VOLUME, SURFACE_TENSION, CONTACT_ANGLE],
    history: &[],
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Extra(Capillary {
        volume: input.params.get(&BRIDGE_VOLUME),
        gamma: input.params.get(&SURFACE_TENSION),
        theta: input.params.get(&CONTACT_ANGLE).to_radians(),
    }.into())
}

/// Attractive bridge force (N, >= 0) for R* (m), gamma_lv (N/m), theta (rad), V (m^3), gap S (m).
pub fn bridge_force(r_eff: f64, gamma: f64, theta: f64, volume: f64, gap: f64) -> f64 {
    let s = gap.max(0.0) * (r_eff / volume).sqrt();
    2.0 * PI * r_eff * gamma * theta.cos() / (1.0 + 1.05 * s + 2.5 * s * s)
}

pub struct Capillary {
    volume: f64,
    gamma: f64,
    theta: f64,
}

impl ExtraLaw for Capillary {
    fn force(&self, c: &Contact, _h: &mut [f64]) -> f64 {
        -bridge_force(c.r_eff, self.gamma, self.theta, self.volume, -c.overlap)
    }

    fn reach(&self, _r_eff: f64) -> f64 {
        (1.0 + 0.5 * self.theta) * self.volume.cbrt()
    }
}
