//! [`Contact`] and [`NormalForce`] for [`LANES`] contacts side by side, for the laws' lane
//! forms (see `lanes.rs`).

use super::lanes::{F, LANES, V};
use super::{Contact, NormalForce};
use glam::DVec3;

/// [`LANES`] contacts of one material pair, field by field as [`Contact`]. Lanes
/// `count..` hold copies of lane 0, so that every lane computes something finite; what
/// they compute is dropped.
#[derive(Debug, Clone, Copy)]
pub struct ContactLanes {
    /// Lanes holding contacts: `0..count`.
    pub count: usize,
    pub overlap: F,
    pub normal: V,
    pub r_eff: F,
    pub m_eff: F,
    pub radius_i: F,
    pub radius_j: F,
    pub arm_i: F,
    pub arm_j: F,
    pub v_n: F,
    pub v_t: V,
    pub omega_i: V,
    pub omega_j: V,
    pub mass_i: F,
    pub mass_j: F,
    pub inertia_i: F,
    pub inertia_j: F,
    pub dt: f64,
}

/// The bodies of [`LANES`] sphere pairs, as [`Contact::between_spheres`] takes them
/// (`d = x_j - x_i`, `dist = |d| > 0`).
#[derive(Debug, Clone, Copy)]
pub struct SpheresLanes {
    pub d: V,
    pub dist: F,
    pub r: (F, F),
    pub m: (F, F),
    pub inertia: (F, F),
    pub v: (V, V),
    pub w: (V, V),
}

impl SpheresLanes {
    pub const ZERO: SpheresLanes = SpheresLanes {
        d: V::ZERO,
        dist: F::ZERO,
        r: (F::ZERO, F::ZERO),
        m: (F::ZERO, F::ZERO),
        inertia: (F::ZERO, F::ZERO),
        v: (V::ZERO, V::ZERO),
        w: (V::ZERO, V::ZERO),
    };
}

impl ContactLanes {
    /// [`Contact::between_spheres`], lane by lane, in its operations and their order.
    #[inline(always)]
    pub fn between_spheres(s: &SpheresLanes, dt: f64, count: usize) -> ContactLanes {
        let SpheresLanes {
            d,
            dist,
            r,
            m,
            inertia,
            v,
            w,
        } = *s;
        let n = d / dist;
        let overlap = r.0 + r.1 - dist;
        let arm_i = r.0 - 0.5 * overlap;
        let arm_j = r.1 - 0.5 * overlap;
        let v_rel = v.0 - v.1 + w.0.cross(n * arm_i) + w.1.cross(n * arm_j);
        let v_n = v_rel.dot(n);
        ContactLanes {
            count,
            overlap,
            normal: n,
            r_eff: r.0 * r.1 / (r.0 + r.1),
            m_eff: m.0 * m.1 / (m.0 + m.1),
            radius_i: r.0,
            radius_j: r.1,
            arm_i,
            arm_j,
            v_n,
            v_t: v_rel - n * v_n,
            omega_i: w.0,
            omega_j: w.1,
            mass_i: m.0,
            mass_j: m.1,
            inertia_i: inertia.0,
            inertia_j: inertia.1,
            dt,
        }
    }

    /// All lanes zero, `count` 0: room to fill with [`ContactLanes::set_lane`].
    pub const ZERO: ContactLanes = ContactLanes {
        count: 0,
        overlap: F::ZERO,
        normal: V::ZERO,
        r_eff: F::ZERO,
        m_eff: F::ZERO,
        radius_i: F::ZERO,
        radius_j: F::ZERO,
        arm_i: F::ZERO,
        arm_j: F::ZERO,
        v_n: F::ZERO,
        v_t: V::ZERO,
        omega_i: V::ZERO,
        omega_j: V::ZERO,
        mass_i: F::ZERO,
        mass_j: F::ZERO,
        inertia_i: F::ZERO,
        inertia_j: F::ZERO,
        dt: 0.0,
    };

    /// Puts contact `s` in lane `k` (and its `dt` for every lane): the inverse of
    /// [`ContactLanes::lane`]. For contacts whose geometry is not computed in lanes (a
    /// particle and a wall: each wall shape finds its own closest point).
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, s: &Contact) {
        self.overlap.0[k] = s.overlap;
        self.normal.set_lane(k, s.normal);
        self.r_eff.0[k] = s.r_eff;
        self.m_eff.0[k] = s.m_eff;
        self.radius_i.0[k] = s.radius_i;
        self.radius_j.0[k] = s.radius_j;
        self.arm_i.0[k] = s.arm_i;
        self.arm_j.0[k] = s.arm_j;
        self.v_n.0[k] = s.v_n;
        self.v_t.set_lane(k, s.v_t);
        self.omega_i.set_lane(k, s.omega_i);
        self.omega_j.set_lane(k, s.omega_j);
        self.mass_i.0[k] = s.mass_i;
        self.mass_j.0[k] = s.mass_j;
        self.inertia_i.0[k] = s.inertia_i;
        self.inertia_j.0[k] = s.inertia_j;
        self.dt = s.dt;
    }

    /// Contacts `cs` (1 to [`LANES`], all with the same `dt`) side by side; lanes past
    /// `cs.len()` repeat `cs[0]`, so that every lane computes something finite.
    pub fn gather(cs: &[Contact]) -> ContactLanes {
        debug_assert!(!cs.is_empty() && cs.len() <= LANES);
        let mut c = ContactLanes::ZERO;
        for k in 0..LANES {
            c.set_lane(k, &cs[if k < cs.len() { k } else { 0 }]);
        }
        c.count = cs.len();
        c
    }

    /// Lane `k` as a scalar contact (what a law without a lane form is given).
    #[inline(always)]
    pub fn lane(&self, k: usize) -> Contact {
        Contact {
            overlap: self.overlap.0[k],
            normal: self.normal.lane(k),
            r_eff: self.r_eff.0[k],
            m_eff: self.m_eff.0[k],
            radius_i: self.radius_i.0[k],
            radius_j: self.radius_j.0[k],
            arm_i: self.arm_i.0[k],
            arm_j: self.arm_j.0[k],
            v_n: self.v_n.0[k],
            v_t: self.v_t.lane(k),
            omega_i: self.omega_i.lane(k),
            omega_j: self.omega_j.lane(k),
            mass_i: self.mass_i.0[k],
            mass_j: self.mass_j.0[k],
            inertia_i: self.inertia_i.0[k],
            inertia_j: self.inertia_j.0[k],
            dt: self.dt,
        }
    }
}

/// [`crate::contact::geometry::rotate_into_plane`] lane by lane.
#[inline(always)]
pub fn rotate_into_plane_lanes(v: V, n: V) -> V {
    let len2 = v.length_squared();
    let p = v - n * n.dot(v);
    let l2 = p.length_squared();
    let turned = V::select(l2.gt(F::ZERO), p * (len2 / l2).sqrt(), p);
    V::select(len2.eq(F::ZERO), v, turned)
}

/// [`NormalForce`] per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NormalForceLanes {
    pub elastic: F,
    pub stiffness: F,
    pub friction_load: F,
    pub contact_radius: F,
}

impl NormalForceLanes {
    pub const ZERO: NormalForceLanes = NormalForceLanes {
        elastic: F::ZERO,
        stiffness: F::ZERO,
        friction_load: F::ZERO,
        contact_radius: F::ZERO,
    };

    #[inline(always)]
    pub fn lane(&self, k: usize) -> NormalForce {
        NormalForce {
            elastic: self.elastic.0[k],
            stiffness: self.stiffness.0[k],
            friction_load: self.friction_load.0[k],
            contact_radius: self.contact_radius.0[k],
        }
    }

    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, f: NormalForce) {
        self.elastic.0[k] = f.elastic;
        self.stiffness.0[k] = f.stiffness;
        self.friction_load.0[k] = f.friction_load;
        self.contact_radius.0[k] = f.contact_radius;
    }
}

/// The most history values one contact law may keep and still run in lanes through its
/// scalar form (a registry test checks every law).
pub const MAX_LAW_HISTORY: usize = 8;

/// Runs `f` on lane `k`'s history (value `v` of lane `k` is `h[v].0[k]`), as the slice a
/// scalar law form takes, and writes back what it changed.
#[inline(always)]
pub fn with_lane_history<R>(h: &mut [F], k: usize, f: impl FnOnce(&mut [f64]) -> R) -> R {
    let mut row = [0.0; MAX_LAW_HISTORY];
    let row = &mut row[..h.len()];
    for (v, x) in row.iter_mut().enumerate() {
        *x = h[v].0[k];
    }
    let out = f(row);
    for (v, x) in row.iter().enumerate() {
        h[v].0[k] = *x;
    }
    out
}

/// A scalar torque form (`torques` of a rolling or extra law) run lane by lane, with its
/// bits: the default of both slots' `torques_lanes`.
#[inline(always)]
pub fn torques_by_lane(
    c: &ContactLanes,
    normal: &NormalForceLanes,
    coulomb_load: F,
    history: &mut [F],
    torques: impl Fn(&Contact, &NormalForce, f64, &mut [f64]) -> (DVec3, DVec3),
) -> (V, V) {
    let (mut ti, mut tj) = (V::ZERO, V::ZERO);
    for k in 0..c.count {
        let (n, load) = (normal.lane(k), coulomb_load.0[k]);
        let (a, b) = with_lane_history(history, k, |h| torques(&c.lane(k), &n, load, h));
        ti.set_lane(k, a);
        tj.set_lane(k, b);
    }
    (ti, tj)
}
