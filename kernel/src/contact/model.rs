//! The contact model: which law fills each slot, the coefficients of every material pair,
//! and the per-contact history layout. Built (and checked) once; evaluated every step.

use super::{
    AnyBond, AnyDamping, AnyExtra, AnyNormal, AnyRolling, AnyTangential, BondLaw, BondLoads,
    Contact, DampingLaw, ExtraLaw, NormalLaw, RollingLaw, TangentialLaw,
};
use crate::error::{KernelError, Result};
use crate::material::Material;
use glam::DVec3;
use std::collections::BTreeMap;
use std::ops::Range;

mod build;
mod lanes;
pub use lanes::{ContactOutLanes, LaneLaws, TypedLaws, TypedModel};

/// Which law fills each slot (names from the registry). `damping`, `tangential` and
/// `rolling` may be left empty (no damping, frictionless, no rolling resistance).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelSpec {
    pub normal: String,
    pub damping: Option<String>,
    pub tangential: Option<String>,
    pub rolling: Option<String>,
    /// Extra laws, in order; a bond law (slot `bond`, at most one) is named here too
    /// (`extra = ["bond"]`) and goes to its own slot.
    pub extra: Vec<String>,
}

/// Coefficients of one material pair (order does not matter).
#[derive(Debug, Clone, PartialEq)]
pub struct PairSpec {
    pub materials: (String, String),
    pub params: BTreeMap<String, f64>,
}

/// Forces and torques of one contact.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactOut {
    /// Force on i (j gets the opposite), N.
    pub force: DVec3,
    /// Torque on i and on j, N m.
    pub torque_i: DVec3,
    pub torque_j: DVec3,
}

/// The laws of one material pair, each held by value in its slot's enum (no `dyn`: see
/// `contact/dispatch.rs`).
struct PairLaws {
    normal: AnyNormal,
    damping: Option<AnyDamping>,
    tangential: Option<AnyTangential>,
    rolling: Option<AnyRolling>,
    extras: Vec<AnyExtra>,
    bond: Option<AnyBond>,
}

/// Where each law's history lives inside a contact's history row. Slot 0 is the
/// "contact established" flag that gives cohesive laws their hysteresis. With a bond law,
/// the row ends with the bond block: status, breaking time, then the law's history; it
/// outlives the contact (ending a contact clears only `..contact_len`).
#[derive(Debug, Clone, Default)]
struct HistoryLayout {
    normal: Range<usize>,
    tangential: Range<usize>,
    rolling: Range<usize>,
    extras: Vec<Range<usize>>,
    /// Start of the bond block.
    bond: Option<usize>,
    /// Values of the contact laws (the flag included): `0..contact_len`.
    contact_len: usize,
    stride: usize,
}

/// Index 0 of every history row: 1.0 while a contact is established.
pub const ACTIVE: usize = 0;

/// Values of the bond status (first value of the bond block).
const BOND_NONE: f64 = 0.0;
const BOND_INTACT: f64 = 1.0;
const BOND_BROKEN: f64 = 2.0;
/// Bond block values before the law's own: status and breaking time.
const BOND_HEAD: usize = 2;

/// The bond status of a pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BondStatus {
    /// Never bonded (or no bond law).
    None,
    Intact,
    /// Broken at this time (s); never re-forms.
    Broken(f64),
}

/// A contact's stiffnesses at its current overlap (see [`ContactModel::stiffness`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactStiffness {
    /// dF_n / d(delta_n), N/m.
    pub normal: f64,
    /// The tangential spring, N/m.
    pub tangential: f64,
    /// The tangential dashpot, N s/m.
    pub tangential_damping: f64,
}

pub struct ContactModel {
    materials: Vec<Material>,
    /// `pairs[a * n + b]`, symmetric; `None` where no coefficients were given.
    pairs: Vec<Option<PairLaws>>,
    layout: HistoryLayout,
    law_names: Vec<&'static str>,
    has_reach: bool,
}

impl ContactModel {
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    pub fn material_index(&self, name: &str) -> Option<usize> {
        self.materials.iter().position(|m| m.name == name)
    }

    /// Names of the laws in use, in slot order.
    pub fn law_names(&self) -> &[&'static str] {
        &self.law_names
    }

    /// Number of f64 values per contact history row.
    pub fn history_stride(&self) -> usize {
        self.layout.stride
    }

    /// Whether coefficients exist for materials a and b.
    pub fn has_pair(&self, a: usize, b: usize) -> bool {
        self.pairs
            .get(a * self.materials.len() + b)
            .is_some_and(|p| p.is_some())
    }

    /// Checks that every pair among `needed` has coefficients.
    pub fn require_pairs(&self, needed: &[(usize, usize)]) -> Result<()> {
        for &(a, b) in needed {
            if !self.has_pair(a, b) {
                return Err(KernelError::Invalid(format!(
                    "no contact coefficients for the material pair ({}, {}); add a [[pairs]] entry with materials = [\"{}\", \"{}\"]",
                    self.materials[a].name,
                    self.materials[b].name,
                    self.materials[a].name,
                    self.materials[b].name
                )));
            }
        }
        Ok(())
    }

    /// The largest distance beyond touching (m) at which any established contact or intact
    /// bond between materials a and b, of particles of radius up to `r_max`, still acts.
    /// `r_max` bounds every contact radius R* (the contact laws get it as such) and half of
    /// every radius sum r_i + r_j (what the bond law needs).
    pub fn reach(&self, a: usize, b: usize, r_max: f64) -> f64 {
        match &self.pairs[a * self.materials.len() + b] {
            Some(l) => {
                let mut r: f64 = 0.0;
                if self.has_reach || !l.extras.is_empty() {
                    r = l.normal.reach(r_max);
                    for x in &l.extras {
                        r = r.max(x.reach(r_max));
                    }
                }
                if let Some(bond) = &l.bond {
                    r = r.max(bond.reach(r_max));
                }
                r
            }
            None => 0.0,
        }
    }

    /// Largest reach over all pairs, for particles of radius up to `r_max`.
    pub fn max_reach(&self, r_max: f64) -> f64 {
        let n = self.materials.len();
        let mut r: f64 = 0.0;
        for a in 0..n {
            for b in 0..n {
                if self.has_pair(a, b) {
                    r = r.max(self.reach(a, b, r_max));
                }
            }
        }
        r
    }

    /// Whether the model has a bond law.
    pub fn has_bond(&self) -> bool {
        self.layout.bond.is_some()
    }

    /// Whether a pair's history row holds an intact bond (cheap: the pair loop asks it).
    #[inline(always)]
    pub fn bond_intact(&self, history: &[f64]) -> bool {
        matches!(self.layout.bond, Some(at) if history[at] == BOND_INTACT)
    }

    /// The bond status kept in a pair's history row.
    #[inline]
    pub fn bond_status(&self, history: &[f64]) -> BondStatus {
        match self.layout.bond {
            Some(at) if history[at] == BOND_INTACT => BondStatus::Intact,
            Some(at) if history[at] == BOND_BROKEN => BondStatus::Broken(history[at + 1]),
            _ => BondStatus::None,
        }
    }

    /// Bonds the pair (i, j) of materials a and b, radii `r_i`, `r_j` and centre distance
    /// `dist`, if it has never been bonded and is closer than the bond law's contact radius
    /// sum. Returns whether a bond formed. The new bond carries no load.
    pub fn form_bond(
        &self,
        a: usize,
        b: usize,
        r: (f64, f64),
        dist: f64,
        history: &mut [f64],
    ) -> bool {
        let Some(at) = self.layout.bond else {
            return false;
        };
        let Some(bond) = self.pairs[a * self.materials.len() + b]
            .as_ref()
            .and_then(|l| l.bond.as_ref())
        else {
            return false;
        };
        let within = dist < bond.contact_ratio() * (r.0 + r.1);
        if history[at] != BOND_NONE || !within {
            return false;
        }
        history[at..].fill(0.0);
        history[at] = BOND_INTACT;
        true
    }

    /// The bond's time scale between materials `a` and `b` (see [`BondLaw::time_scale`]), or
    /// `None` when that pair has no bond law.
    pub fn bond_time_scale(&self, a: usize, b: usize, mass: f64, r: (f64, f64)) -> Option<f64> {
        self.pairs[a * self.materials.len() + b]
            .as_ref()
            .and_then(|l| l.bond.as_ref())
            .map(|bond| bond.time_scale(mass, r.0, r.1))
    }

    /// The loads of a bonded pair (zero once broken) and the time it broke, or `None` when
    /// the pair was never bonded.
    pub fn bond_loads(
        &self,
        a: usize,
        b: usize,
        history: &[f64],
    ) -> Option<(BondLoads, Option<f64>)> {
        let at = self.layout.bond?;
        match self.bond_status(history) {
            BondStatus::None => None,
            BondStatus::Broken(t) => Some((BondLoads::default(), Some(t))),
            BondStatus::Intact => {
                let bond = self.pairs[a * self.materials.len() + b]
                    .as_ref()?
                    .bond
                    .as_ref()?;
                Some((bond.loads(&history[at + BOND_HEAD..]), None))
            }
        }
    }

    /// Evaluates one contact between materials a and b. Returns `None` (and clears the
    /// history row) when there is no force: not touching and not established, or separated
    /// beyond the laws' reach.
    #[inline]
    pub fn evaluate(
        &self,
        a: usize,
        b: usize,
        c: &Contact,
        history: &mut [f64],
    ) -> Option<ContactOut> {
        let laws = self.pairs[a * self.materials.len() + b].as_ref()?;
        self.evaluate_laws(laws, c, history)
    }

    /// Evaluates one particle pair between materials a and b: the contact laws as
    /// [`ContactModel::evaluate`], plus the bond while it is intact. A bond that breaks is
    /// marked broken at `time` (s) and carries nothing from this step on.
    #[inline]
    pub fn evaluate_pair(
        &self,
        a: usize,
        b: usize,
        c: &Contact,
        time: f64,
        history: &mut [f64],
    ) -> Option<ContactOut> {
        let laws = self.pairs[a * self.materials.len() + b].as_ref()?;
        let out = self.evaluate_laws(laws, c, history);
        let (Some(at), Some(bond)) = (self.layout.bond, &laws.bond) else {
            return out;
        };
        if history[at] != BOND_INTACT {
            return out;
        }
        let (head, own) = history[at..].split_at_mut(BOND_HEAD);
        match bond.force(c, own) {
            Some(b) => Some(match out {
                Some(o) => ContactOut {
                    force: o.force + b.force,
                    torque_i: o.torque_i + b.torque_i,
                    torque_j: o.torque_j + b.torque_j,
                },
                None => b,
            }),
            None => {
                head[0] = BOND_BROKEN;
                head[1] = time;
                own.fill(0.0);
                out
            }
        }
    }

    /// The stiffnesses of one touching contact between materials a and b, for step checks:
    /// normal and tangential (N/m) and the tangential dashpot (N s/m). `None` when the pair
    /// has no laws or does not overlap. Reads the history without changing it.
    pub fn stiffness(
        &self,
        a: usize,
        b: usize,
        c: &Contact,
        history: &[f64],
    ) -> Option<ContactStiffness> {
        let laws = self.pairs[a * self.materials.len() + b].as_ref()?;
        if c.overlap <= 0.0 {
            return None;
        }
        // A hysteretic normal law writes its history; this is a look, not a step.
        let mut scratch = history[self.layout.normal.clone()].to_vec();
        let normal = laws.normal.force(c, &mut scratch);
        let tangential = match &laws.tangential {
            Some(t) => t.stiffness(c, &normal),
            None => 0.0,
        };
        let damping = match &laws.damping {
            Some(d) if tangential > 0.0 => d.coefficient(tangential, c.m_eff),
            _ => 0.0,
        };
        Some(ContactStiffness {
            normal: normal.stiffness,
            tangential,
            tangential_damping: damping,
        })
    }

    // Always inlined: with a second caller (`evaluate_pair`) and plain `#[inline]`, the
    // settling-bed benchmark ran 3.7 % more instructions (cachegrind), in the wall loop.
    #[inline(always)]
    fn evaluate_laws(
        &self,
        laws: &PairLaws,
        c: &Contact,
        history: &mut [f64],
    ) -> Option<ContactOut> {
        if history[ACTIVE] == 0.0 {
            if c.overlap <= 0.0 {
                return None;
            }
            history[ACTIVE] = 1.0;
        } else if c.overlap <= 0.0 && c.overlap <= -self.reach_of(laws, c) {
            history[..self.layout.contact_len].fill(0.0);
            return None;
        }
        let l = &self.layout;
        let normal = laws.normal.force(c, &mut history[l.normal.clone()]);
        // Damping acts wherever the contact has stiffness: for JKR also in tension (negative
        // overlap, positive contact radius), or a particle hanging by adhesion would
        // oscillate undamped.
        let damp_n = match &laws.damping {
            Some(d) if normal.stiffness > 0.0 => d.coefficient(normal.stiffness, c.m_eff) * c.v_n,
            _ => 0.0,
        };
        let coulomb_load = (normal.friction_load + damp_n).abs();
        let mut f_normal = normal.elastic + damp_n;
        let mut tangential = DVec3::ZERO;
        if let Some(t) = &laws.tangential {
            let s_t = t.stiffness(c, &normal);
            let eta_t = match &laws.damping {
                Some(d) if s_t > 0.0 => d.coefficient(s_t, c.m_eff),
                _ => 0.0,
            };
            tangential = t.force(
                c,
                coulomb_load,
                s_t,
                eta_t,
                &mut history[l.tangential.clone()],
            );
        }
        let (mut torque_i, mut torque_j) = (DVec3::ZERO, DVec3::ZERO);
        if let Some(r) = &laws.rolling {
            (torque_i, torque_j) =
                r.torques(c, &normal, coulomb_load, &mut history[l.rolling.clone()]);
        }
        for (x, range) in laws.extras.iter().zip(&l.extras) {
            let h = &mut history[range.clone()];
            f_normal += x.force(c, h);
            let (ti, tj) = x.torques(c, &normal, coulomb_load, h);
            torque_i += ti;
            torque_j += tj;
        }
        let n = c.normal;
        torque_i += (n * c.arm_i).cross(tangential);
        if c.arm_j.is_finite() {
            torque_j += (n * c.arm_j).cross(tangential);
        }
        Some(ContactOut {
            force: tangential - n * f_normal,
            torque_i,
            torque_j,
        })
    }

    #[inline]
    fn reach_of(&self, laws: &PairLaws, c: &Contact) -> f64 {
        if !self.has_reach && laws.extras.is_empty() {
            return 0.0;
        }
        let mut r = laws.normal.reach(c.r_eff);
        for x in &laws.extras {
            r = r.max(x.reach_between(c));
        }
        r
    }
}
