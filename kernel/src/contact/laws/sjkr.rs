//! `sjkr`: LIGGGHTS's "simplified JKR" cohesion, an extra law.
//!
//! Touching particles (overlap delta > 0) attract with a force proportional to the area A
//! (m^2) of the circle where the two *undeformed* spheres intersect:
//!
//!   F = -k A  (N, negative = attractive),
//!
//! k the cohesion energy density (`cohesion_energy_density`, J/m^3; LIGGGHTS's
//! `cohesionEnergyDensity`), 0 switching it off. For two spheres of radii r_i, r_j whose
//! centres are d = r_i + r_j - delta apart (m):
//!
//!   A = -pi/4 (d - r_i - r_j)(d + r_i - r_j)(d - r_i + r_j)(d + r_i + r_j) / d^2,
//!
//! about 2 pi R* delta for small overlaps. Against a wall (flat, r_j infinite) tilth follows
//! LIGGGHTS's wall branch, A = pi (r_i^2 - d^2) with d = r_i - delta the distance from the
//! centre to the wall, i.e.
//!
//!   A = pi (2 r_i delta - delta^2),
//!
//! the limit of the sphere-sphere area as r_j grows (LIGGGHTS multiplies it by the mesh
//! element's `area_ratio`, which is 1 for primitive walls; tilth treats every wall as locally
//! flat). No force across a gap (delta <= 0) and no history: like LIGGGHTS's `sjkr` (and
//! unlike JKR or `capillary`) the attraction ends the moment the spheres separate.
//!
//! One difference from LIGGGHTS: there the cohesion force is added to the normal force
//! before the tangential model reads it, so the Coulomb cap is mu |F_n + F_coh|; in tilth
//! extra laws do not enter the Coulomb load, which stays |elastic + damping| of the normal
//! law (for `hertz`, the Hertz force plus its damping).
//!
//! Reference: LIGGGHTS-PUBLIC `src/cohesion_model_sjkr.h` and the `gran cohesion sjkr`
//! documentation (DCS Computing / JKU Linz); Johnson, Kendall, Roberts (1971) Proc. R. Soc.
//! Lond. A 324:301 for the full theory it simplifies.
//!
//! ```
//! use std::f64::consts::PI;
//! use tilth_kernel::contact::laws::sjkr::contact_area;
//! // Equal spheres r = 1 mm, overlap 10 um: the circle's radius squared is
//! // r^2 - (r - delta/2)^2 = r delta - delta^2/4.
//! let (r, delta) = (1e-3, 1e-5);
//! let a = contact_area(r, r, delta);
//! assert!((a - PI * (r * delta - delta * delta / 4.0)).abs() < 1e-12 * a);
//! // A flat wall: pi (2 r delta - delta^2).
//! let w = contact_area(r, f64::INFINITY, delta);
//! assert!((w - PI * (2.0 * r * delta - delta * delta)).abs() < 1e-12 * w);
//! // No area across a gap.
//! assert_eq!(contact_area(r, r, -1e-6), 0.0);
//! ```

use crate::contact::{
    BuiltLaw, Contact, ContactLanes, ExtraLaw, F, LawEntry, LawInput, NormalForceLanes, Slot, V,
};
use crate::param::{Bound, ParamSpec};
use std::f64::consts::PI;

pub const COHESION_ENERGY_DENSITY: ParamSpec = ParamSpec {
    key: "cohesion_energy_density",
    unit: "J/m^3",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "cohesion energy density k: attraction k A, A the intersection area of the spheres (0 = off)",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "sjkr",
    slot: Slot::Extra,
    summary: "simplified JKR (LIGGGHTS sjkr): attraction k A in contact, A the spheres' intersection area",
    params: &[COHESION_ENERGY_DENSITY],
    history: &[],
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Extra(Sjkr {
        k: input.params.get(&COHESION_ENERGY_DENSITY),
    }.into())
}

/// Area (m^2) of the circle where two undeformed spheres of radii `r_i`, `r_j` (m; `r_j`
/// infinite for a flat wall) overlapping by `overlap` (m) intersect; 0 when not overlapping.
pub fn contact_area(r_i: f64, r_j: f64, overlap: f64) -> f64 {
    if overlap <= 0.0 {
        return 0.0;
    }
    if r_j.is_finite() {
        let d = r_i + r_j - overlap;
        // The first factor, d - r_i - r_j, is -overlap: written so, it loses no digits to
        // cancellation.
        PI / 4.0 * overlap * (d + r_i - r_j) * (d - r_i + r_j) * (d + r_i + r_j) / (d * d)
    } else {
        PI * overlap * (2.0 * r_i - overlap)
    }
}

pub struct Sjkr {
    k: f64,
}

impl ExtraLaw for Sjkr {
    #[inline]
    fn force(&self, c: &Contact, _h: &mut [f64]) -> f64 {
        if c.overlap <= 0.0 || self.k == 0.0 {
            return 0.0;
        }
        -self.k * contact_area(c.radius_i, c.radius_j, c.overlap)
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, _h: &mut [F]) -> F {
        if self.k == 0.0 {
            return F::ZERO;
        }
        let (r_i, r_j, overlap) = (c.radius_i, c.radius_j, c.overlap);
        let d = r_i + r_j - overlap;
        let spheres =
            PI / 4.0 * overlap * (d + r_i - r_j) * (d - r_i + r_j) * (d + r_i + r_j) / (d * d);
        let wall = PI * overlap * (2.0 * r_i - overlap);
        let area = F::select(r_j.is_finite(), spheres, wall);
        F::select(overlap.le(F::ZERO), F::ZERO, -self.k * area)
    }

    /// No torques (as the scalar default), without running it lane by lane.
    #[inline(always)]
    fn torques_lanes(&self, _c: &ContactLanes, _n: &NormalForceLanes, _load: F, _h: &mut [F]) -> (V, V) {
        (V::ZERO, V::ZERO)
    }
}
