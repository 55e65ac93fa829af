//! `mindlin_incremental`: Mindlin tangential spring in incremental form, with the force
//! rescaled on unloading (LAMMPS `tangential mindlin_rescale/force`).
//!
//! The history holds the spring force F_s (N) and the contact radius a of the last step.
//! Each step F_s is rotated into the current tangent plane (length kept); if the contact
//! shrank (a < a_old), F_s is scaled by a / a_old (the loaded annulus is lost); then
//!   F_s += -S_t v_t dt,  S_t = 8 G* a,   F_t = F_s - eta_t v_t,
//! capped at |F_t| <= mu_s L, with F_s = F_cap + eta_t v_t when it slides.
//! Unlike the total form of `mindlin` (F = -S_t(a) delta_t), a stiffening contact does not
//! raise the force at a fixed displacement, so a contact whose area oscillates (cohesive
//! contacts in a resting heap) cannot pump energy into the tangential spring.
//!
//! Reference: Thornton, Cummins, Cleary (2011) Powder Technol. 210:189 (incremental
//! Mindlin-Deresiewicz simplifications); Di Renzo & Di Maio (2005); LAMMPS
//! `tangential mindlin_rescale/force`.

use crate::contact::laws::mindlin::{FRICTION, tangential_stiffness};
use crate::contact::{BuiltLaw, Contact, LawEntry, LawInput, NormalForce, Slot, TangentialLaw};
use crate::contact::geometry::rotate_into_plane;
use glam::DVec3;

pub const ENTRY: LawEntry = LawEntry {
    name: "mindlin_incremental",
    slot: Slot::Tangential,
    summary: "Mindlin tangential spring, incremental force with rescaling on unloading (energy-consistent)",
    params: &[FRICTION],
    history: &["spring_force_x", "spring_force_y", "spring_force_z", "contact_radius"],
    cohesive: false,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Tangential(MindlinIncremental { g_eff: input.g_eff, mu: input.params.get(&FRICTION) }.into())
}

pub struct MindlinIncremental {
    g_eff: f64,
    mu: f64,
}

impl TangentialLaw for MindlinIncremental {
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
        let a = s_t / (8.0 * self.g_eff);
        let mut fs = rotate_into_plane(DVec3::new(h[0], h[1], h[2]), n);
        if a < h[3] {
            fs *= a / h[3];
        }
        fs -= s_t * c.v_t * c.dt;
        let mut f = fs - eta_t * c.v_t;
        let cap = self.mu * coulomb_load;
        let f2 = f.length_squared();
        if f2 > cap * cap {
            f *= cap / f2.sqrt();
            fs = f + eta_t * c.v_t;
        }
        h[0] = fs.x;
        h[1] = fs.y;
        h[2] = fs.z;
        h[3] = a;
        f
    }
}
