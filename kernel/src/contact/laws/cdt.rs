//! `cdt`: constant directional torque rolling resistance (type A; EDEM "standard rolling friction").
//!
//! tau_i = -mu_r L d_i omega_i/|omega_i|  (N m), with L the Coulomb load (N) and d_i the distance
//! from i's centre to the contact point (m); the same for j with its own spin. EDEM uses each
//! particle's own angular velocity (LIGGGHTS `cdt` uses the relative one and R*; see docs/physics.md).
//! No torque on a particle that does not spin. It chatters at rest: the torque does not vanish
//! as omega -> 0, so a pile may never settle; prefer `epsd` for heaps.
//!
//! Reference: Zhou et al. (1999) Physica A 269:536; Ai et al. (2011) Powder Technol. 206:269 (model A);
//! EDEM 2020 documentation.
//!
//! ```
//! use tilth_kernel::contact::laws::cdt::cdt_torque;
//! use glam::DVec3;
//! let t = cdt_torque(0.15, 2.0, 1e-3, DVec3::new(0.0, 3.0, 0.0));
//! assert!((t - DVec3::new(0.0, -0.15 * 2.0 * 1e-3, 0.0)).length() < 1e-18);
//! ```

use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes,
    RollingLaw, Slot, V,
};
use crate::param::{Bound, ParamSpec};
use glam::DVec3;

pub const ROLLING_FRICTION: ParamSpec = ParamSpec {
    key: "rolling_friction",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "rolling friction coefficient mu_r",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "cdt",
    slot: Slot::Rolling,
    summary: "constant directional torque rolling friction (EDEM standard, type A)",
    params: &[ROLLING_FRICTION],
    history: &[],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Rolling(Cdt { mu_r: input.params.get(&ROLLING_FRICTION) }.into())
}

/// -mu_r L d omega/|omega|, N m.
pub fn cdt_torque(mu_r: f64, load: f64, arm: f64, omega: DVec3) -> DVec3 {
    let w = omega.length();
    if w == 0.0 { DVec3::ZERO } else { -mu_r * load * arm / w * omega }
}

/// [`cdt_torque`] lane by lane.
#[inline(always)]
fn cdt_torque_lanes(mu_r: f64, load: F, arm: F, omega: V) -> V {
    let w = omega.length();
    V::select(w.eq(F::ZERO), V::ZERO, (-mu_r * load * arm / w) * omega)
}

pub struct Cdt {
    mu_r: f64,
}

impl RollingLaw for Cdt {
    #[inline]
    fn torques(&self, c: &Contact, _normal: &NormalForce, load: f64, _h: &mut [f64]) -> (DVec3, DVec3) {
        let ti = cdt_torque(self.mu_r, load, c.arm_i, c.omega_i);
        let tj = if c.arm_j.is_finite() { cdt_torque(self.mu_r, load, c.arm_j, c.omega_j) } else { DVec3::ZERO };
        (ti, tj)
    }

    #[inline(always)]
    fn torques_lanes(&self, c: &ContactLanes, _normal: &NormalForceLanes, load: F, _h: &mut [F]) -> (V, V) {
        let ti = cdt_torque_lanes(self.mu_r, load, c.arm_i, c.omega_i);
        let tj = cdt_torque_lanes(self.mu_r, load, c.arm_j, c.omega_j);
        (ti, V::select(c.arm_j.is_finite(), tj, V::ZERO))
    }
}
