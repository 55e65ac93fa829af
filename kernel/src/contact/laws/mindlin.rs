//! `mindlin`: Mindlin no-slip tangential spring with history, dashpot and Coulomb cap.
//!
//! S_t = 8 G* a  (N/m; a = sqrt(R* delta_n) for Hertz), delta_t the accumulated tangential
//! displacement (m), rotated into the current tangent plane each step with its length kept,
//! then incremented by v_t dt. Force on i:
//!   F_t = -S_t delta_t - eta_t v_t,   eta_t from the damping slot for stiffness S_t,
//! capped at |F_t| <= mu_s L with L the Coulomb load (|repulsive normal force + normal damping|).
//! When it slides, delta_t is rescaled so that spring plus dashpot sit on the cap:
//!   delta_t = -(F_cap + eta_t v_t) / S_t  (as LAMMPS `tangential mindlin`).
//!
//! Reference: Mindlin (1949); Di Renzo & Di Maio (2004); EDEM "Hertz-Mindlin (no slip)";
//! LAMMPS `tangential mindlin`.
//!
//! ```
//! use tilth_kernel::contact::laws::mindlin::tangential_stiffness;
//! // G* = 1.5625e6 Pa, R* = 0.5 mm, delta = 10 um: S_t = 8 G* sqrt(R* delta)
//! assert!((tangential_stiffness(1.5625e6, (5e-4f64 * 1e-5).sqrt()) - 8.0 * 1.5625e6 * 7.0710678118654755e-5).abs() < 1e-6);
//! ```

use crate::contact::contact_lanes::rotate_into_plane_lanes;
use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes, Slot,
    TangentialLaw, V,
};
use crate::param::{Bound, ParamSpec};
use crate::contact::geometry::rotate_into_plane;
use glam::DVec3;

pub const FRICTION: ParamSpec = ParamSpec {
    key: "friction",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "static (sliding) friction coefficient mu_s",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "mindlin",
    slot: Slot::Tangential,
    summary: "Mindlin tangential spring-dashpot with history and Coulomb cap",
    params: &[FRICTION],
    history: &["shear_x", "shear_y", "shear_z"],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Tangential(Mindlin { g_eff: input.g_eff, mu: input.params.get(&FRICTION) }.into())
}

/// S_t = 8 G* a, N/m.
pub fn tangential_stiffness(g_eff: f64, contact_radius: f64) -> f64 {
    8.0 * g_eff * contact_radius
}

pub struct Mindlin {
    g_eff: f64,
    mu: f64,
}

impl TangentialLaw for Mindlin {
    #[inline]
    fn stiffness(&self, _c: &Contact, normal: &NormalForce) -> f64 {
        tangential_stiffness(self.g_eff, normal.contact_radius)
    }

    #[inline]
    fn force(&self, c: &Contact, coulomb_load: f64, s_t: f64, eta_t: f64, h: &mut [f64]) -> DVec3 {
        if s_t <= 0.0 {
            h.fill(0.0);
            return DVec3::ZERO;
        }
        let n = c.normal;
        let mut xi = rotate_into_plane(DVec3::new(h[0], h[1], h[2]), n);
        xi += c.v_t * c.dt;
        let mut f = -s_t * xi - eta_t * c.v_t;
        let cap = self.mu * coulomb_load;
        let f2 = f.length_squared();
        if f2 > cap * cap {
            f *= cap / f2.sqrt();
            xi = -(f + eta_t * c.v_t) / s_t;
        }
        h[0] = xi.x;
        h[1] = xi.y;
        h[2] = xi.z;
        f
    }

    #[inline(always)]
    fn stiffness_lanes(&self, _c: &ContactLanes, normal: &NormalForceLanes) -> F {
        8.0 * self.g_eff * normal.contact_radius
    }

    #[inline(always)]
    fn force_lanes(&self, c: &ContactLanes, coulomb_load: F, s_t: F, eta_t: F, h: &mut [F]) -> V {
        let n = c.normal;
        let stored = V { x: h[0], y: h[1], z: h[2] };
        let mut xi = rotate_into_plane_lanes(stored, n);
        xi += c.v_t * c.dt;
        let mut f = -s_t * xi - eta_t * c.v_t;
        let cap = self.mu * coulomb_load;
        let f2 = f.length_squared();
        let slide = f2.gt(cap * cap);
        let capped = f * (cap / f2.sqrt());
        f = V::select(slide, capped, f);
        xi = V::select(slide, -(capped + eta_t * c.v_t) / s_t, xi);
        let off = s_t.le(F::ZERO);
        xi = V::select(off, V::ZERO, xi);
        h[0] = xi.x;
        h[1] = xi.y;
        h[2] = xi.z;
        V::select(off, V::ZERO, f)
    }
}
