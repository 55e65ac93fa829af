//! `capillary_moisture`: pendular liquid bridges whose volume comes from the moisture content.
//!
//! The force is the `capillary` law's (Willett et al. 2000, rupture at the Lian et al. 1993
//! gap S_c = (1 + theta/2) V^(1/3)); only the bridge volume V differs. Each grain's water,
//! `moisture` (kg water per kg dry solid, the soil-science dry basis) times its mass, is
//! spread over `bridges_per_grain` bridges, of which the share `bridge_share` is held in
//! bridges between grains (the rest in the grains' own pores and films: a simulated grain
//! of a soil is an aggregate, not a sand crystal). A bridge takes its share from both
//! grains, so for grains of mass m_i and m_j (kg):
//!
//!   V = bridge_share * moisture * (m_i + m_j) / (rho_w * bridges_per_grain)   (m^3)
//!
//! with rho_w the liquid's density (kg/m^3). A wall holds no water of its own: on a wall only
//! the grain's share counts. No water, no bridge (V = 0 gives no force). The volume scales
//! with the grains' volume, so V / R^3, and with it the force-gap curve in units of R, is the
//! same at any grain size (coarse graining keeps the bridges' shape).
//!
//! Reference: Willett, Adams, Johnson, Seville (2000) Langmuir 16:9396; Lian, Thornton, Adams
//! (1993) J. Colloid Interface Sci. 161:138; the equal split of a grain's water over its
//! contacts as in Shi and McCarthy (2008) Powder Technol. 184:64.
//!
//! ```
//! use tilth_kernel::contact::laws::capillary_moisture::bridge_volume;
//! // 6 % moisture, 1 % of it in bridges, two grains of 5.78 mg, 6 bridges each: ~1.2e-12 m^3.
//! let v = bridge_volume(0.06, 0.01, 6.0, 1000.0, 5.78e-6, 5.78e-6);
//! assert!((v - 0.01 * 0.06 * 2.0 * 5.78e-6 / 6000.0).abs() < 1e-25);
//! ```

use super::capillary::{CONTACT_ANGLE, SURFACE_TENSION, bridge_force};
use crate::contact::{BuiltLaw, Contact, ExtraLaw, LawEntry, LawInput, Slot};
use crate::param::{Bound, ParamSpec};
use std::f64::consts::PI;

pub const MOISTURE: ParamSpec = ParamSpec {
    key: "moisture",
    unit: "kg/kg",
    min: Bound::Closed(0.0),
    max: Bound::Closed(1.0),
    default: None,
    doc: "moisture content, kg of water per kg of dry solid (12 % is 0.12)",
};
pub const BRIDGE_SHARE: ParamSpec = ParamSpec {
    key: "bridge_share",
    unit: "1",
    min: Bound::Open(0.0),
    max: Bound::Closed(1.0),
    default: None,
    doc: "share of the water held in bridges between grains",
};
pub const BRIDGES_PER_GRAIN: ParamSpec = ParamSpec {
    key: "bridges_per_grain",
    unit: "1",
    min: Bound::Closed(1.0),
    max: Bound::Closed(20.0),
    default: Some(6.0),
    doc: "bridges a grain's water is split over (its coordination number; 4-6 in loose soil)",
};
pub const LIQUID_DENSITY: ParamSpec = ParamSpec {
    key: "liquid_density",
    unit: "kg/m^3",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: Some(1000.0),
    doc: "density of the liquid rho_w (water: 1000)",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "capillary_moisture",
    slot: Slot::Extra,
    summary: "liquid bridge (Willett 2000) with its volume from the moisture content",
    params: &[
        MOISTURE,
        BRIDGE_SHARE,
        BRIDGES_PER_GRAIN,
        LIQUID_DENSITY,
        SURFACE_TENSION,
        CONTACT_ANGLE,
    ],
    history: &[],
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Extra(CapillaryMoisture {
        moisture: input.params.get(&MOISTURE),
        share: input.params.get(&BRIDGE_SHARE),
        bridges: input.params.get(&BRIDGES_PER_GRAIN),
        rho_w: input.params.get(&LIQUID_DENSITY),
        gamma: input.params.get(&SURFACE_TENSION),
        theta: input.params.get(&CONTACT_ANGLE).to_radians(),
        rho_max: input.material_i.density.max(input.material_j.density),
    }.into())
}

/// Bridge volume (m^3) between bodies of mass `m_i`, `m_j` (kg; a wall's is infinite and
/// adds no water), from the moisture (kg/kg), the share of water in bridges, the bridges
/// per grain and the liquid's density (kg/m^3).
pub fn bridge_volume(
    moisture: f64,
    share: f64,
    bridges_per_grain: f64,
    rho_w: f64,
    m_i: f64,
    m_j: f64,
) -> f64 {
    let grain = |m: f64| if m.is_finite() { m } else { 0.0 };
    share * moisture * (grain(m_i) + grain(m_j)) / (rho_w * bridges_per_grain)
}

pub struct CapillaryMoisture {
    moisture: f64,
    share: f64,
    bridges: f64,
    rho_w: f64,
    gamma: f64,
    theta: f64,
    /// The denser of the pair's two materials, kg/m^3: bounds a grain's mass by its radius.
    rho_max: f64,
}

impl CapillaryMoisture {
    fn volume(&self, m_i: f64, m_j: f64) -> f64 {
        bridge_volume(self.moisture, self.share, self.bridges, self.rho_w, m_i, m_j)
    }

    fn rupture_gap(&self, volume: f64) -> f64 {
        (1.0 + 0.5 * self.theta) * volume.cbrt()
    }
}

impl ExtraLaw for CapillaryMoisture {
    fn force(&self, c: &Contact, _h: &mut [f64]) -> f64 {
        let v = self.volume(c.mass_i, c.mass_j);
        if v <= 0.0 {
            return 0.0;
        }
        -bridge_force(c.r_eff, self.gamma, self.theta, v, -c.overlap)
    }

    /// A bound for any two grains of radius up to `r_max`: both at the densest material.
    fn reach(&self, r_max: f64) -> f64 {
        let m = self.rho_max * 4.0 / 3.0 * PI * r_max.powi(3);
        self.rupture_gap(self.volume(m, m))
    }

    fn reach_between(&self, c: &Contact) -> f64 {
        self.rupture_gap(self.volume(c.mass_i, c.mass_j))
    }
}
