//! `plastic_adhesion`: adhesion that grows with how hard a contact was pressed (EEPA-like,
//! history-dependent cohesion), an extra law.
//!
//! Cohesive soils and powders stick harder after consolidation: the pull-off force of a
//! contact grows with the largest load it carried (Luding 2008; Thakur et al. 2014, EEPA).
//! Here, with delta_max (m) the largest overlap the contact has reached (history) and the
//! Hertz force F_H(delta) = 4/3 E* sqrt(R*) delta^(3/2) (N):
//!
//!   F_adh = -lambda F_H(delta_max)   while the particles overlap (delta > 0),
//!
//! so a contact unloaded from delta_max pulls with lambda times the load it once carried,
//! until the overlap is gone (like LIGGGHTS's `sjkr`, it acts in contact only). lambda
//! (`plastic_adhesion`, dimensionless) = 0 switches it off. The history is cleared when the
//! contact ends.
//!
//! Reference: Luding (2008) Granular Matter 10:235 (adhesion growing with the maximum
//! overlap); Thakur, Morrissey, Sun, Chen, Ooi (2014) Granular Matter 16:383 (EEPA).

use crate::contact::{BuiltLaw, Contact, ExtraLaw, LawEntry, LawInput, Slot};
use crate::param::{Bound, ParamSpec};

pub const PLASTIC_ADHESION: ParamSpec = ParamSpec {
    key: "plastic_adhesion",
    unit: "-",
    min: Bound::Closed(0.0),
    max: Bound::Open(1.0),
    default: None,
    doc: "pull-off as a fraction lambda of the Hertz force at the largest overlap reached (0 = off)",
};

pub const ENTRY: LawEntry = LawEntry {
    name: "plastic_adhesion",
    slot: Slot::Extra,
    summary: "adhesion growing with the largest load a contact carried (EEPA-like)",
    params: &[PLASTIC_ADHESION],
    history: &["max_overlap"],
    cohesive: true,
    allows_cohesion: true,
    build,
};

fn build(input: &LawInput) -> BuiltLaw {
    BuiltLaw::Extra(PlasticAdhesion {
        e_eff: input.e_eff,
        lambda: input.params.get(&PLASTIC_ADHESION),
    }.into())
}

pub struct PlasticAdhesion {
    e_eff: f64,
    lambda: f64,
}

impl ExtraLaw for PlasticAdhesion {
    fn force(&self, c: &Contact, h: &mut [f64]) -> f64 {
        if c.overlap <= 0.0 || self.lambda == 0.0 {
            return 0.0;
        }
        h[0] = h[0].max(c.overlap);
        -self.lambda * 4.0 / 3.0 * self.e_eff * c.r_eff.sqrt() * h[0].powf(1.5)
    }
}
