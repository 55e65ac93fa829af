//! `hertz`: Hertz elastic normal force between spheres.
//!
//! F_n = 4/3 E* sqrt(R*) delta_n^(3/2)  (N), normal stiffness S_n = dF_n/d(delta_n) = 2 E* sqrt(R* delta_n) (N/m),
//! contact radius a = sqrt(R* delta_n). E* and R* as in docs/physics.md; no force at delta_n <= 0.
//!
//! Reference: H. Hertz (1882); EDEM "Hertz-Mindlin (no slip)"; LIGGGHTS `hertz`; LAMMPS `hertz/material`.
//!
//! ```
//! use tilth_kernel::contact::laws::hertz::hertz_force;
//! // E* = 7.03125e6 Pa (soil on soil), R* = 0.5 mm, delta = 10 um:
//! let f = hertz_force(7.03125e6, 5e-4, 1e-5);
//! assert!((f - 4.0 / 3.0 * 7.03125e6 * (5e-4f64).sqrt() * (1e-5f64).powf(1.5)).abs() < 1e-12);
//! ```

use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes,
    NormalLaw, Slot,
};

pub const ENTRY: LawEntry = LawEntry {
    name: "hertz",
    slot: Slot::Normal,
    summary: "Hertz elastic normal force, F = 4/3 E* sqrt(R*) delta^1.5",
    params: &[],
    history: &[],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Normal(Hertz { e_eff: input.e_eff }.into())
}

/// F_n (N) for E* (Pa), R* (m), overlap delta (m).
pub fn hertz_force(e_eff: f64, r_eff: f64, delta: f64) -> f64 {
    if delta <= 0.0 { 0.0 } else { 4.0 / 3.0 * e_eff * (r_eff * delta).sqrt() * delta }
}

pub struct Hertz {
    e_eff: f64,
}

impl NormalLaw for Hertz {
    #[inline]
    fn force(&self, c: &Contact, _history: &mut [f64]) -> NormalForce {
        if c.overlap <= 0.0 {
            return NormalForce::default();
        }
        let a = (c.r_eff * c.overlap).sqrt();
        let stiffness = 2.0 * self.e_eff * a;
        let elastic = 2.0 / 3.0 * stiffness * c.overlap;
        NormalForce { elastic, stiffness, friction_load: elastic, contact_radius: a }
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, _history: &mut [F]) -> NormalForceLanes {
        let a = (c.r_eff * c.overlap).sqrt();
        let stiffness = 2.0 * self.e_eff * a;
        let elastic = 2.0 / 3.0 * stiffness * c.overlap;
        let off = c.overlap.le(F::ZERO);
        NormalForceLanes {
            elastic: F::select(off, F::ZERO, elastic),
            stiffness: F::select(off, F::ZERO, stiffness),
            friction_load: F::select(off, F::ZERO, elastic),
            contact_radius: F::select(off, F::ZERO, a),
        }
    }
}
