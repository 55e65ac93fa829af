//! The loaded-packing step, checked on the contacts as they are.
//!
//! [`crate::timestep::loaded_packing_step`] sets a step before a run from the load a packing
//! will carry; a scene stepped at a fraction of the Rayleigh time has no such rule, and a
//! packing pressed hard enough loses its friction at that step without any other sign
//! (tests/tests/loaded_packing.rs). This module bounds the same mode from the contacts in
//! the pair list: for each touching pair, its stiffest mode
//!
//!   omega_c^2 = max(k_t (1/m_i + r_i^2/I_i + 1/m_j + r_j^2/I_j), k_n (1/m_i + 1/m_j))
//!
//! (the tangential spring with both grains sliding and rolling, or the normal spring), a
//! grain's bound the row sum omega_i^2 = sum over its contacts of omega_c^2, and the
//! packing's the mean over the grains that touch: omega^2 = mean_i omega_i^2, the measured
//! counterpart of Z omega_1^2 in the rule. The damping ratio of the mode,
//! zeta_c = eta_t / (2 sqrt(k_t m_c)) with m_c = 1 / (the inverse masses above), is averaged
//! over the contacts. Velocity Verlet is stable for omega dt < 2 (sqrt(1 + zeta^2) - zeta).
//! Wall contacts and bonds are left out: bonds have their own check, and a wall is one
//! contact of many for all but the grains that touch it.
//!
//! Reference: the row-sum bound as in O'Sullivan and Bray (2004), Eng. Comput. 21:278.

use crate::contact::geometry::Contact;
use crate::contact::model::ContactModel;
use crate::neighbor::PairList;
use crate::particles::Particles;
use crate::timestep::damped_verlet_limit;

/// The packing's stiffest contact mode, from its touching pairs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackingFrequency {
    /// sqrt(mean over touching grains of the row sum of omega_c^2), rad/s.
    pub omega: f64,
    /// Mean damping ratio of the contacts' rolling-sliding mode.
    pub zeta: f64,
    /// Grains with at least one touching neighbour.
    pub grains: usize,
    /// Touching particle pairs.
    pub contacts: usize,
}

impl PackingFrequency {
    /// The explicit scheme's limit omega dt for this damping, 2 (sqrt(1 + zeta^2) - zeta).
    pub fn stable_omega_dt(&self) -> f64 {
        damped_verlet_limit(self.zeta)
    }

    /// The longest stable step for this packing, s.
    pub fn stable_step(&self) -> f64 {
        self.stable_omega_dt() / self.omega
    }
}

/// Bounds the packing's stiffest mode from the pairs in `pairs` that overlap now
/// ([`ContactModel::stiffness`] skips the others). `None` when no pair touches.
pub fn packing_frequency(
    p: &Particles,
    model: &ContactModel,
    pairs: &PairList,
    dt: f64,
) -> Option<PackingFrequency> {
    let mut row = vec![0.0f64; p.len()];
    let (mut zeta_sum, mut contacts) = (0.0, 0usize);
    let stride = pairs.stride;
    for k in 0..pairs.len() {
        let (i, j) = (pairs.i[k] as usize, pairs.j[k] as usize);
        let d = p.position[j] - p.position[i];
        let dist = d.length();
        if dist == 0.0 {
            continue;
        }
        let c = Contact::between_particles(p, i, j, d, dist, dt);
        let h = &pairs.history[k * stride..(k + 1) * stride];
        let (a, b) = (p.material[i] as usize, p.material[j] as usize);
        let Some(s) = model.stiffness(a, b, &c, h) else {
            continue;
        };
        let translate = 1.0 / p.mass[i] + 1.0 / p.mass[j];
        let roll = p.radius[i].powi(2) / p.inertia[i] + p.radius[j].powi(2) / p.inertia[j];
        let inverse_mass = translate + roll;
        let omega2 = (s.tangential * inverse_mass).max(s.normal * translate);
        row[i] += omega2;
        row[j] += omega2;
        if s.tangential > 0.0 {
            zeta_sum += s.tangential_damping / (2.0 * (s.tangential / inverse_mass).sqrt());
        }
        contacts += 1;
    }
    let touching: Vec<f64> = row.into_iter().filter(|&w| w > 0.0).collect();
    if touching.is_empty() {
        return None;
    }
    let mean = touching.iter().sum::<f64>() / touching.len() as f64;
    Some(PackingFrequency {
        omega: mean.sqrt(),
        zeta: zeta_sum / contacts as f64,
        grains: touching.len(),
        contacts,
    })
}

/// The warning for a step `dt` (s) beyond the stable limit of the packing's contacts, or
/// `None` within it.
pub fn loaded_step_warning(dt: f64, f: &PackingFrequency) -> Option<String> {
    let omega_dt = f.omega * dt;
    (omega_dt > f.stable_omega_dt()).then(|| {
        format!(
            "the time step {dt:.3e} s is beyond what the packing's contacts stand under their present load: \
             omega dt = {omega_dt:.2} over {} touching grains, stable up to {:.2} (damping ratio {:.2}); \
             a pressed packing stepped this long loses its friction without blowing up. \
             Use at most {:.3e} s (timestep::loaded_packing_step gives the step before a run)",
            f.grains,
            f.stable_omega_dt(),
            f.zeta,
            f.stable_step()
        )
    })
}
