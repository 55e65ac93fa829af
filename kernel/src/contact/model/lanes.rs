//! The pipeline on [`LANES`] touching contacts at once: `ContactModel::evaluate_laws`
//! written in lanes, step for step, so that every lane gets the scalar pipeline's bits.

use super::{ACTIVE, ContactModel, HistoryLayout};
use crate::contact::dispatch::OfAny;
#[cfg(doc)]
use crate::contact::lanes::LANES;
use crate::contact::lanes::{F, M, V};
use crate::contact::{AnyDamping, AnyExtra, AnyNormal, AnyRolling, AnyTangential};
use crate::contact::{ContactLanes, DampingLaw, ExtraLaw, NormalLaw, RollingLaw, TangentialLaw};

/// [`super::ContactOut`] per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactOutLanes {
    pub force: V,
    pub torque_i: V,
    pub torque_j: V,
}

/// What evaluates [`LANES`] touching contacts at once: a model through its slots' enums, or
/// its laws with their types named ([`TypedModel`]), with the same bits.
pub trait LaneLaws {
    /// Evaluates lanes `0..c.count` of `c`, contacts between materials a and b that all
    /// touch (`overlap > 0`), as [`ContactModel::evaluate`] would one by one; `history[v]`
    /// holds value `v` of each lane's history row. Marks each contact established. `None`
    /// (and the history untouched) when the pair has no laws. Bonds are not evaluated here,
    /// and a row's bond block is left as it is: the simulation runs its pairs one at a time
    /// once bonds are formed, and a wall never bonds.
    fn evaluate_lanes(
        &self,
        a: usize,
        b: usize,
        c: &ContactLanes,
        history: &mut [F],
    ) -> Option<ContactOutLanes>;
}

impl LaneLaws for ContactModel {
    #[inline(always)]
    fn evaluate_lanes(
        &self,
        a: usize,
        b: usize,
        c: &ContactLanes,
        history: &mut [F],
    ) -> Option<ContactOutLanes> {
        let laws = self.pairs[a * self.materials.len() + b].as_ref()?;
        let typed = TypedLaws {
            normal: &laws.normal,
            damping: laws.damping.as_ref(),
            tangential: laws.tangential.as_ref(),
            rolling: laws.rolling.as_ref(),
            extras: &laws.extras[..],
        };
        Some(typed.evaluate_lanes(&self.layout, c, history))
    }
}

impl ContactModel {
    /// The model's laws with their types named (see [`TypedModel`]): `Some` when every
    /// material pair's laws are of types N, D, T, R (or leave that slot empty) with at most
    /// one extra law, of type X. A bond law does not matter: bonds are never evaluated in
    /// lanes.
    pub fn typed_laws<N, D, T, R, X>(&self) -> Option<TypedModel<'_, N, D, T, R, X>>
    where
        N: OfAny<AnyNormal>,
        D: OfAny<AnyDamping>,
        T: OfAny<AnyTangential>,
        R: OfAny<AnyRolling>,
        X: OfAny<AnyExtra>,
    {
        fn opt<L: OfAny<A>, A>(a: Option<&A>) -> Option<Option<&L>> {
            match a {
                None => Some(None),
                Some(a) => L::of_any(a).map(Some),
            }
        }
        let mut pairs = Vec::with_capacity(self.pairs.len());
        for laws in &self.pairs {
            let Some(laws) = laws else {
                pairs.push(None);
                continue;
            };
            if laws.extras.len() > 1 {
                return None;
            }
            pairs.push(Some(TypedLaws {
                normal: N::of_any(&laws.normal)?,
                damping: opt(laws.damping.as_ref())?,
                tangential: opt(laws.tangential.as_ref())?,
                rolling: opt(laws.rolling.as_ref())?,
                extras: match laws.extras.first() {
                    None => &[][..],
                    Some(x) => std::slice::from_ref(X::of_any(x)?),
                },
            }));
        }
        Some(TypedModel {
            materials: self.materials.len(),
            layout: &self.layout,
            pairs,
        })
    }
}

/// A model's laws with their types named, so that the pipeline in lanes can be compiled
/// for one law set, as LIGGGHTS compiles a pair style per contact-model combination.
/// Through the slots' enums, the compiler builds one body that serves every law: each
/// enum's `match` joins its arms' results in memory, and every value of [`ContactLanes`]
/// any law might read stays alive. Compiled for named types, the body holds only what
/// those laws do. Same operations in the same order as the enums'
/// [`LaneLaws::evaluate_lanes`], so the same bits (`tests/tests/determinism.rs` checks it on
/// every path).
pub struct TypedModel<'a, N, D, T, R, X> {
    materials: usize,
    layout: &'a HistoryLayout,
    pairs: Vec<PairLaws<'a, N, D, T, R, X>>,
}

/// One material pair's laws, or none when the pair has no contact model.
type PairLaws<'a, N, D, T, R, X> = Option<TypedLaws<'a, N, D, T, R, X>>;

impl<N, D, T, R, X> LaneLaws for TypedModel<'_, N, D, T, R, X>
where
    N: NormalLaw,
    D: DampingLaw,
    T: TangentialLaw,
    R: RollingLaw,
    X: ExtraLaw,
{
    #[inline(always)]
    fn evaluate_lanes(
        &self,
        a: usize,
        b: usize,
        c: &ContactLanes,
        history: &mut [F],
    ) -> Option<ContactOutLanes> {
        let laws = self.pairs[a * self.materials + b].as_ref()?;
        Some(laws.evaluate_lanes(self.layout, c, history))
    }
}

/// One material pair's laws, typed.
pub struct TypedLaws<'a, N, D, T, R, X> {
    normal: &'a N,
    damping: Option<&'a D>,
    tangential: Option<&'a T>,
    rolling: Option<&'a R>,
    extras: &'a [X],
}

impl<N, D, T, R, X> TypedLaws<'_, N, D, T, R, X>
where
    N: NormalLaw,
    D: DampingLaw,
    T: TangentialLaw,
    R: RollingLaw,
    X: ExtraLaw,
{
    /// The pipeline of `ContactModel::evaluate_laws` in lanes, step for step: the body of
    /// [`LaneLaws::evaluate_lanes`] for these types.
    #[inline(always)]
    fn evaluate_lanes(
        &self,
        l: &HistoryLayout,
        c: &ContactLanes,
        history: &mut [F],
    ) -> ContactOutLanes {
        history[ACTIVE] = F::splat(1.0);
        let normal = self.normal.force_lanes(c, &mut history[l.normal.clone()]);
        let damp_n = match self.damping {
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
        if let Some(t) = self.tangential {
            let s_t = t.stiffness_lanes(c, &normal);
            let eta_t = match self.damping {
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
        if let Some(r) = self.rolling {
            (torque_i, torque_j) =
                r.torques_lanes(c, &normal, coulomb_load, &mut history[l.rolling.clone()]);
        }
        for (x, range) in self.extras.iter().zip(&l.extras) {
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
        ContactOutLanes {
            force: tangential - n * f_normal,
            torque_i,
            torque_j,
        }
    }
}
