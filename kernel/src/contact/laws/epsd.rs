//! `epsd`: elastic-plastic spring-dashpot rolling resistance (type C, Ai et al. 2011; LIGGGHTS `epsd`).
//!
//! Rolling stiffness k_r = 2.25 S_n mu_r^2 R*^2 (N m/rad). The spring torque M_r (history) is
//! rotated into the current tangent plane and incremented by -k_r omega_r dt, where
//! omega_r = (omega_i - omega_j) with its normal (twisting) part removed; it is capped at
//! M_max = mu_r R* L (L the Coulomb load). While below the cap a dashpot adds
//! -C_r omega_r with C_r = eta_r * 2 sqrt(I_r k_r), I_r = 1/(1/(I_i + m_i d_i^2) + 1/(I_j + m_j d_j^2))
//! and eta_r the fraction of critical damping (`rolling_damping`, Ai et al. suggest 0.3).
//! Torque M_r + M_d on i, the opposite on j. The heap comes to rest, unlike `cdt`.
//!
//! Reference: Ai, Chen, Rotter, Ooi (2011) Powder Technol. 206:269-282, model C.

use crate::contact::laws::cdt::ROLLING_FRICTION;
use crate::contact::contact_lanes::rotate_into_plane_lanes;
use crate::contact::{
    BuiltLaw, Contact, ContactLanes, F, LawEntry, LawInput, NormalForce, NormalForceLanes,
    RollingLaw, Slot, V,
};
use crate::param::{Bound, ParamSpec};
use crate::contact::geometry::rotate_into_plane;
use glam::DVec3;

pub const ROLLING_DAMPING: ParamSpec = ParamSpec {
    key: "rolling_damping",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: Some(0.3),
    doc: "rolling viscous damping as a fraction of critical (Ai et al. eta_r)",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "epsd",
    slot: Slot::Rolling,
    summary: "elastic-plastic spring-dashpot rolling resistance (type C)",
    params: &[ROLLING_FRICTION, ROLLING_DAMPING],
    history: &["rolling_torque_x", "rolling_torque_y", "rolling_torque_z"],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Rolling(Epsd {
        mu_r: input.params.get(&ROLLING_FRICTION),
        eta_r: input.params.get(&ROLLING_DAMPING),
    }.into())
}

pub struct Epsd {
    mu_r: f64,
    eta_r: f64,
}

impl RollingLaw for Epsd {
    #[inline]
    fn torques(&self, c: &Contact, normal: &NormalForce, load: f64, h: &mut [f64]) -> (DVec3, DVec3) {
        let n = c.normal;
        let k_r = 2.25 * normal.stiffness * (self.mu_r * c.r_eff).powi(2);
        if k_r <= 0.0 {
            h.fill(0.0);
            return (DVec3::ZERO, DVec3::ZERO);
        }
        let w = c.omega_i - c.omega_j;
        let w_r = w - n * n.dot(w);
        let mut m = rotate_into_plane(DVec3::new(h[0], h[1], h[2]), n);
        m -= k_r * w_r * c.dt;
        let m_max = self.mu_r * c.r_eff * load;
        let mut total = m;
        let m2 = m.length_squared();
        if m2 > m_max * m_max {
            // Fully mobilised: plastic rolling, no dashpot (Ai et al. f = 0).
            m *= m_max / m2.sqrt();
            total = m;
        } else {
            let inv = |i: f64, mass: f64, d: f64| if i.is_finite() { 1.0 / (i + mass * d * d) } else { 0.0 };
            let i_r = 1.0 / (inv(c.inertia_i, c.mass_i, c.arm_i) + inv(c.inertia_j, c.mass_j, c.arm_j));
            total -= self.eta_r * 2.0 * (i_r * k_r).sqrt() * w_r;
        }
        h[0] = m.x;
        h[1] = m.y;
        h[2] = m.z;
        (total, -total)
    }

    /// [`Epsd::torques`] in lanes, operation for operation: each branch becomes a select.
    #[inline(always)]
    fn torques_lanes(&self, c: &ContactLanes, normal: &NormalForceLanes, load: F, h: &mut [F]) -> (V, V) {
        let n = c.normal;
        // `powi(2)` is one multiplication, as here.
        let mu_r_eff = self.mu_r * c.r_eff;
        let k_r = 2.25 * normal.stiffness * (mu_r_eff * mu_r_eff);
        let w = c.omega_i - c.omega_j;
        let w_r = w - n * n.dot(w);
        let mut m = rotate_into_plane_lanes(V { x: h[0], y: h[1], z: h[2] }, n);
        m -= w_r * k_r * c.dt;
        let m_max = self.mu_r * c.r_eff * load;
        let m2 = m.length_squared();
        let capped = m2.gt(m_max * m_max);
        let inv = |i: F, mass: F, d: F| F::select(i.is_finite(), 1.0 / (i + mass * d * d), F::ZERO);
        let i_r = 1.0 / (inv(c.inertia_i, c.mass_i, c.arm_i) + inv(c.inertia_j, c.mass_j, c.arm_j));
        let dashpot = w_r * (self.eta_r * 2.0 * (i_r * k_r).sqrt());
        m = V::select(capped, m * (m_max / m2.sqrt()), m);
        let total = V::select(capped, m, m - dashpot);
        // No stiffness: no torque, and the spring is forgotten (a NaN goes on, as there).
        let live = !k_r.le(F::ZERO);
        let m = V::select(live, m, V::ZERO);
        let total = V::select(live, total, V::ZERO);
        h[0] = m.x;
        h[1] = m.y;
        h[2] = m.z;
        (total, -total)
    }
}
