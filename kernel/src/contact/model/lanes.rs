//! The pipeline on [`LANES`] touching contacts at once: [`ContactModel::evaluate_laws`]
//! written in lanes, step for step, so that every lane gets the scalar pipeline's bits.

use super::{ACTIVE, ContactModel};
#[cfg(doc)]
use crate::contact::lanes::LANES;
use crate::contact::lanes::{F, M, V};
use crate::contact::{ContactLanes, DampingLaw, ExtraLaw, NormalLaw, RollingLaw, TangentialLaw};

/// [`super::ContactOut`] per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactOutLanes {
    pub force: V,
    pub torque_i: V,
    pub torque_j: V,
}

impl ContactModel {
    /// Evaluates lanes `0..c.count` of `c`, contacts between materials a and b that all
    /// touch (`overlap > 0`), as [`ContactModel::evaluate`] would one by one; `history[v]`
    /// holds value `v` of each lane's history row. Marks each contact established. `None`
    /// (and the history untouched) when the pair has no laws. Bonds are not evaluated here,
    /// and a row's bond block is left as it is: the simulation runs its pairs one at a time
    /// once bonds are formed, and a wall never bonds.
    #[inline(always)]
    pub fn evaluate_lanes(
        &self,
        a: usize,
        b: usize,
        c: &ContactLanes,
        history: &mut [F],
    ) -> Option<ContactOutLanes> {
        let laws = self.pairs[a * self.materials.len() + b].as_ref()?;
        let l = &self.layout;
        history[ACTIVE] = F::splat(1.0);
        let normal = laws.normal.force_lanes(c, &mut history[l.normal.clone()]);
        let damp_n = match &laws.damping {
            Some(d) => F::select(
                normal.stiffness.gt(F::ZERO),
                d.coefficient_lanes(normal.stiffness, c.m_eff) * c.v_n,
                F::ZERO,
            ),
            None => F::ZERO,
        };
        let coulomb_load = (normal.friction_load + damp_n).abs();
        let mut f_normal = normal.elastic + damp_n;
        let mut tangential = V::ZERO;
        if let Some(t) = &laws.tangential {
            let s_t = t.stiffness_lanes(c, &normal);
            let eta_t = match &laws.damping {
                Some(d) => F::select(s_t.gt(F::ZERO), d.coefficient_lanes(s_t, c.m_eff), F::ZERO),
                None => F::ZERO,
            };
            tangential = t.force_lanes(
                c,
                coulomb_load,
                s_t,
                eta_t,
                &mut history[l.tangential.clone()],
            );
        }
        let (mut torque_i, mut torque_j) = (V::ZERO, V::ZERO);
        if let Some(r) = &laws.rolling {
            (torque_i, torque_j) =
                r.torques_lanes(c, &normal, coulomb_load, &mut history[l.rolling.clone()]);
        }
        for (x, range) in laws.extras.iter().zip(&l.extras) {
            let h = &mut history[range.clone()];
            f_normal += x.force_lanes(c, h);
            let (ti, tj) = x.torques_lanes(c, &normal, coulomb_load, h);
            torque_i += ti;
            torque_j += tj;
        }
        let n = c.normal;
        torque_i += (n * c.arm_i).cross(tangential);
        let finite: M = c.arm_j.is_finite();
        torque_j = V::select(finite, torque_j + (n * c.arm_j).cross(tangential), torque_j);
        Some(ContactOutLanes {
            force: tangential - n * f_normal,
            torque_i,
            torque_j,
        })
    }
}
