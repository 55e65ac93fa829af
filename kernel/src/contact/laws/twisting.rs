//! `twisting`: resistance to relative spin about the contact normal (an extra law: torques
//! only), an elastic-plastic spring-dashpot as LAMMPS's `twisting marshall`.
//!
//! With a the contact radius (m) from the normal law and G* the effective shear modulus:
//! - twisting stiffness k_tw = 0.5 k_t a^2 = 4 G* a^3 (N m/rad), k_t = 8 G* a the Mindlin
//!   tangential stiffness;
//! - the spring's twist angle phi (history, rad) grows by omega_tw dt, omega_tw =
//!   (omega_i - omega_j) . n, and the spring torque on i is M = -k_tw phi n;
//! - it is capped at M_max = (2/3) mu_tw a L (N m), L the Coulomb load (N): the torque of
//!   uniform traction mu_tw L / (pi a^2) over the contact disc. Fully mobilised, the spring
//!   slips (phi = -M_max sign / k_tw) and no dashpot acts;
//! - below the cap a dashpot adds -eta_tw 2 sqrt(I_tw k_tw) omega_tw n, I_tw =
//!   1/(1/I_i + 1/I_j) (kg m^2), eta_tw the fraction of critical damping.
//!
//! j gets the opposite torque. `twisting_friction` = 0 switches it off (the cap is zero).
//!
//! Reference: Marshall (2009) J. Comput. Phys. 228:1541; LAMMPS `pair_style granular`,
//! `twisting marshall` (twisting stiffness 0.5 k_t a^2, friction (2/3) a mu).

use crate::contact::{BuiltLaw, Contact, ExtraLaw, LawEntry, LawInput, NormalForce, Slot};
use crate::param::{Bound, ParamSpec};
use glam::DVec3;

pub const TWISTING_FRICTION: ParamSpec = ParamSpec {
    key: "twisting_friction",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "twisting friction coefficient mu_tw (cap (2/3) mu_tw a L; 0 = off)",
};

pub const TWISTING_DAMPING: ParamSpec = ParamSpec {
    key: "twisting_damping",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Unbounded,
    default: Some(0.3),
    doc: "twisting viscous damping as a fraction of critical",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "twisting",
    slot: Slot::Extra,
    summary: "twisting resistance: elastic-plastic spring-dashpot about the normal (Marshall 2009)",
    params: &[TWISTING_FRICTION, TWISTING_DAMPING],
    history: &["twist_angle"],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Extra(Twisting {
        g_eff: input.g_eff,
        mu_tw: input.params.get(&TWISTING_FRICTION),
        eta_tw: input.params.get(&TWISTING_DAMPING),
    }.into())
}

/// k_tw = 4 G* a^3, N m/rad.
pub fn twisting_stiffness(g_eff: f64, contact_radius: f64) -> f64 {
    4.0 * g_eff * contact_radius.powi(3)
}

/// M_max = (2/3) mu_tw a L, N m.
pub fn twisting_cap(mu_tw: f64, contact_radius: f64, load: f64) -> f64 {
    2.0 / 3.0 * mu_tw * contact_radius * load
}

pub struct Twisting {
    g_eff: f64,
    mu_tw: f64,
    eta_tw: f64,
}

impl ExtraLaw for Twisting {
    fn force(&self, _c: &Contact, _h: &mut [f64]) -> f64 {
        0.0
    }

    fn torques(
        &self,
        c: &Contact,
        normal: &NormalForce,
        load: f64,
        h: &mut [f64],
    ) -> (DVec3, DVec3) {
        let a = normal.contact_radius;
        let k = twisting_stiffness(self.g_eff, a);
        if k <= 0.0 || self.mu_tw == 0.0 {
            h[0] = 0.0;
            return (DVec3::ZERO, DVec3::ZERO);
        }
        let n = c.normal;
        let w = (c.omega_i - c.omega_j).dot(n);
        let phi = h[0] + w * c.dt;
        let cap = twisting_cap(self.mu_tw, a, load);
        let spring = -k * phi;
        let m = if spring.abs() > cap {
            let m = cap * spring.signum();
            h[0] = -m / k;
            m
        } else {
            h[0] = phi;
            let inv = |i: f64| if i.is_finite() { 1.0 / i } else { 0.0 };
            let i_tw = 1.0 / (inv(c.inertia_i) + inv(c.inertia_j));
            spring - self.eta_tw * 2.0 * (i_tw * k).sqrt() * w
        };
        (m * n, -m * n)
    }
}
