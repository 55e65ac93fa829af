//! `bond`: the bonded particle model (Potyondy & Cundall 2004 parallel bond; EDEM
//! "Bonding V1"). A cemented disc between two particles that carries force and moment in
//! every direction, on top of the contact laws, until it breaks.
//!
//! Geometry: bond disc radius R_B = `bond_radius_ratio` * min(r_i, r_j) (EDEM's "bonded disk
//! radius" as a fraction of the smaller particle), area A = pi R_B^2, polar moment
//! J = pi R_B^4 / 2 (the bending moment of area is J/2).
//!
//! Bonds form (see `Simulation::form_bonds`) between pairs whose centres are closer than the
//! sum of their contact radii, `bond_contact_ratio` * (r_i + r_j). A new bond carries no
//! load; each step its loads grow by
//!
//!   dF_n = S_n A v_n dt            (v_n > 0 approaching, so F_n > 0 in compression)
//!   dF_t = -S_t A v_t dt           (v_t the tangential velocity of i's contact point
//!                                   relative to j's; F_t the force on i)
//!   dM_n = -S_t J w_n dt           (w = omega_i - omega_j, w_n = n.w; twisting moment on i)
//!   dM_t = -S_n (J/2) w_t dt       (w_t = w - n w_n; bending moment on i)
//!
//! with S_n, S_t the normal and shear stiffness per unit area (N/m^3). F_t and M_t are
//! first rotated into the current tangent plane (length kept), as the incremental Mindlin
//! spring is. Force on i: -F_n n + F_t; torque on i: M_n n + M_t + (arm_i n) x F_t; on j:
//! -(M_n n + M_t) + (arm_j n) x F_t. In the brief's terms dF_n = -v_n S_n A dt with v_n the
//! separation speed and F_n positive in compression: the same thing.
//!
//! The bond breaks in the step where (tension positive)
//!   sigma = -F_n / A + 2 |M_t| R_B / J > critical_normal_stress,  or
//!   tau   = |F_t| / A + |M_n| R_B / J  > critical_shear_stress,
//! and never re-forms. No bond damping.
//!
//! Reach: a bond forms at a gap below (c - 1)(r_i + r_j) <= (c - 1) 2 r_max, so the
//! neighbour list must reach that far for `form_bonds` to see the pair:
//!   reach = (c - 1) 2 r_max.
//! Once formed, an intact bond keeps its pair in the list however far it stretches (the
//! simulation's rebuild keeps bonded pairs), so the list does not have to reach the
//! stretch at break, sigma_c / S_n, which can exceed a particle diameter and would fill the
//! lists of every pair with partners that never touch.
//!
//! Stability: the bond springs S_n A and S_t A must be resolved by the time step, which the
//! Rayleigh-time check does not cover: `Simulation::form_bonds` warns when dt exceeds
//! `timestep::BOND_WARN_FRACTION` of sqrt(m / (max(S_n, S_t) A)) for the lightest bonded
//! particle (each particle carries several bonds in parallel, with their bending and
//! twisting springs, so the usable fraction is well below the single spring's 2).
//!
//! Reference: Potyondy & Cundall (2004) Int. J. Rock Mech. Min. Sci. 41:1329-1364; EDEM
//! Bonding V1 (Altair EDEM Creator documentation).

use crate::contact::geometry::rotate_into_plane;
use crate::contact::{BondLaw, BondLoads, BuiltLaw, Contact, ContactOut, LawEntry, LawInput, Slot};
use crate::param::{Bound, ParamSpec};
use glam::DVec3;
use std::f64::consts::PI;

pub const NORMAL_STIFFNESS: ParamSpec = ParamSpec {
    key: "normal_stiffness_per_area",
    unit: "N/m^3",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "bond normal stiffness per unit area S_n",
};
pub const SHEAR_STIFFNESS: ParamSpec = ParamSpec {
    key: "shear_stiffness_per_area",
    unit: "N/m^3",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "bond shear stiffness per unit area S_t",
};
pub const CRITICAL_NORMAL_STRESS: ParamSpec = ParamSpec {
    key: "critical_normal_stress",
    unit: "Pa",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "tensile strength: breaks when -F_n/A + 2|M_t| R_B/J exceeds it",
};
pub const CRITICAL_SHEAR_STRESS: ParamSpec = ParamSpec {
    key: "critical_shear_stress",
    unit: "Pa",
    min: Bound::Open(0.0),
    max: Bound::Unbounded,
    default: None,
    doc: "shear strength: breaks when |F_t|/A + |M_n| R_B/J exceeds it",
};
pub const BOND_RADIUS_RATIO: ParamSpec = ParamSpec {
    key: "bond_radius_ratio",
    unit: "-",
    min: Bound::Open(0.0),
    max: Bound::Closed(2.0),
    default: Some(1.0),
    doc: "bond disc radius R_B as a fraction of the smaller particle radius",
};
pub const BOND_CONTACT_RATIO: ParamSpec = ParamSpec {
    key: "bond_contact_ratio",
    unit: "-",
    min: Bound::Closed(1.0),
    max: Bound::Closed(2.0),
    default: Some(1.05),
    doc: "contact radius / radius: pairs closer than the contact radius sum bond",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "bond",
    slot: Slot::Bond,
    summary: "parallel bond (Potyondy-Cundall, EDEM Bonding V1): formed on request, breaks on critical normal or shear stress",
    params: &[
        NORMAL_STIFFNESS,
        SHEAR_STIFFNESS,
        CRITICAL_NORMAL_STRESS,
        CRITICAL_SHEAR_STRESS,
        BOND_RADIUS_RATIO,
        BOND_CONTACT_RATIO,
    ],
    history: &[
        "normal_force",
        "shear_force_x",
        "shear_force_y",
        "shear_force_z",
        "normal_moment",
        "shear_moment_x",
        "shear_moment_y",
        "shear_moment_z",
    ],
    // It pulls, but not through the normal force that friction and rolling laws cap on.
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Bond(Bond {
        s_n: input.params.get(&NORMAL_STIFFNESS),
        s_t: input.params.get(&SHEAR_STIFFNESS),
        sigma_c: input.params.get(&CRITICAL_NORMAL_STRESS),
        tau_c: input.params.get(&CRITICAL_SHEAR_STRESS),
        radius_ratio: input.params.get(&BOND_RADIUS_RATIO),
        contact_ratio: input.params.get(&BOND_CONTACT_RATIO),
    }.into())
}

pub struct Bond {
    s_n: f64,
    s_t: f64,
    sigma_c: f64,
    tau_c: f64,
    radius_ratio: f64,
    contact_ratio: f64,
}

impl BondLaw for Bond {
    fn contact_ratio(&self) -> f64 {
        self.contact_ratio
    }

    fn reach(&self, r_max: f64) -> f64 {
        (self.contact_ratio - 1.0) * 2.0 * r_max
    }

    #[inline]
    fn force(&self, c: &Contact, h: &mut [f64]) -> Option<ContactOut> {
        let n = c.normal;
        let r_b = self.radius_ratio * c.radius_i.min(c.radius_j);
        let area = PI * r_b * r_b;
        let polar = 0.5 * area * r_b * r_b;
        let dt = c.dt;

        let f_n = h[0] + self.s_n * area * c.v_n * dt;
        let f_t = rotate_into_plane(DVec3::new(h[1], h[2], h[3]), n) - self.s_t * area * dt * c.v_t;
        let w = c.omega_i - c.omega_j;
        let w_n = n.dot(w);
        let w_t = w - n * w_n;
        let m_n = h[4] - self.s_t * polar * w_n * dt;
        let m_t = rotate_into_plane(DVec3::new(h[5], h[6], h[7]), n)
            - (self.s_n * 0.5 * polar * dt) * w_t;

        let sigma = -f_n / area + 2.0 * m_t.length() * r_b / polar;
        let tau = f_t.length() / area + m_n.abs() * r_b / polar;
        if sigma > self.sigma_c || tau > self.tau_c {
            return None;
        }
        h[0] = f_n;
        h[1] = f_t.x;
        h[2] = f_t.y;
        h[3] = f_t.z;
        h[4] = m_n;
        h[5] = m_t.x;
        h[6] = m_t.y;
        h[7] = m_t.z;
        let moment = n * m_n + m_t;
        let mut torque_j = -moment;
        if c.arm_j.is_finite() {
            torque_j += (n * c.arm_j).cross(f_t);
        }
        Some(ContactOut {
            force: f_t - n * f_n,
            torque_i: moment + (n * c.arm_i).cross(f_t),
            torque_j,
        })
    }

    /// sqrt(m / (max(S_n, S_t) A)), A = pi R_B^2: the period of the bond's stiffest spring
    /// over 2 pi.
    fn time_scale(&self, mass: f64, r_i: f64, r_j: f64) -> f64 {
        let r_b = self.radius_ratio * r_i.min(r_j);
        (mass / (self.s_n.max(self.s_t) * PI * r_b * r_b)).sqrt()
    }

    fn loads(&self, h: &[f64]) -> BondLoads {
        BondLoads {
            normal_force: h[0],
            shear_force: DVec3::new(h[1], h[2], h[3]),
            normal_moment: h[4],
            shear_moment: DVec3::new(h[5], h[6], h[7]),
        }
    }
}
