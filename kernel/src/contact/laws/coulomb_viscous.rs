//! `coulomb_viscous`: history-free friction, a dashpot capped by Coulomb.
//!
//! F_t = -min(eta_t |v_t|, mu_s L) v_t/|v_t|  (N), eta_t from the damping slot for the Mindlin
//! stiffness S_t = 8 G* a, L the Coulomb load. Cheap, but it has no static friction: a contact
//! at rest carries no tangential load. With adhesion, contacts persist at rest and cohesive
//! clusters would creep, so the builder refuses it next to a cohesive law.
//!
//! Reference: Haff & Werner (1986) Powder Technol. 48:239; LIGGGHTS `tangential no_history`.

use crate::contact::{BuiltLaw, Contact, LawEntry, LawInput, NormalForce, Slot, TangentialLaw};
use crate::contact::laws::mindlin::{FRICTION, tangential_stiffness};
use glam::DVec3;

pub const ENTRY: LawEntry = LawEntry {
    name: "coulomb_viscous",
    slot: Slot::Tangential,
    summary: "history-free viscous friction capped by Coulomb (no static friction)",
    params: &[FRICTION],
    history: &[],
    cohesive: false,
    allows_cohesion: false,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Tangential(CoulombViscous { g_eff: input.g_eff, mu: input.params.get(&FRICTION) }.into())
}

pub struct CoulombViscous {
    g_eff: f64,
    mu: f64,
}

impl TangentialLaw for CoulombViscous {
    fn stiffness(&self, _c: &Contact, normal: &NormalForce) -> f64 {
        tangential_stiffness(self.g_eff, normal.contact_radius)
    }

    fn force(&self, c: &Contact, coulomb_load: f64, _s_t: f64, eta_t: f64, _h: &mut [f64]) -> DVec3 {
        let speed = c.v_t.length();
        if speed == 0.0 {
            return DVec3::ZERO;
        }
        -(eta_t * speed).min(self.mu * coulomb_load) * c.v_t / speed
    }
}
