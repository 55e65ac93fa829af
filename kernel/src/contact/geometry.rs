//! Contact geometry and kinematics, computed once per contact and shared by all slots.

use crate::particles::Particles;
use glam::DVec3;

/// One contact between particle i and particle j (or a wall, which has infinite radius,
/// mass and inertia and no spin).
#[derive(Debug, Clone, Copy)]
pub struct Contact {
    /// Normal overlap delta_n, m; positive in contact, negative across a gap.
    pub overlap: f64,
    /// Unit normal from i to j.
    pub normal: DVec3,
    /// R* = R_i R_j / (R_i + R_j), m (R_i for a wall).
    pub r_eff: f64,
    /// m* = m_i m_j / (m_i + m_j), kg (m_i for a wall).
    pub m_eff: f64,
    /// Radii of the two bodies, m (infinite for a wall).
    pub radius_i: f64,
    pub radius_j: f64,
    /// Distances from the centres to the contact point, m.
    pub arm_i: f64,
    pub arm_j: f64,
    /// Relative normal velocity of i toward j, m/s; positive when approaching.
    pub v_n: f64,
    /// Relative tangential velocity of i's contact point with respect to j's, m/s.
    pub v_t: DVec3,
    pub omega_i: DVec3,
    pub omega_j: DVec3,
    pub mass_i: f64,
    pub mass_j: f64,
    /// Moments of inertia about the centre, kg m^2 (infinite for a wall).
    pub inertia_i: f64,
    pub inertia_j: f64,
    /// Time step, s.
    pub dt: f64,
}

impl Contact {
    /// The contact of particles i and j of `p`, as [`Contact::between_spheres`] from their
    /// state. `d = x_j - x_i`, `dist = |d| > 0`.
    #[inline]
    pub fn between_particles(
        p: &Particles,
        i: usize,
        j: usize,
        d: DVec3,
        dist: f64,
        dt: f64,
    ) -> Contact {
        Contact::between_spheres(
            d,
            dist,
            (p.radius[i], p.radius[j]),
            (p.mass[i], p.mass[j]),
            (p.inertia[i], p.inertia[j]),
            (p.velocity[i], p.velocity[j]),
            (p.angular_velocity[i], p.angular_velocity[j]),
            dt,
        )
    }

    /// Builds the contact of two spheres. `d = x_j - x_i`, `dist = |d| > 0`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn between_spheres(
        d: DVec3,
        dist: f64,
        r: (f64, f64),
        m: (f64, f64),
        inertia: (f64, f64),
        v: (DVec3, DVec3),
        w: (DVec3, DVec3),
        dt: f64,
    ) -> Contact {
        let n = d / dist;
        let overlap = r.0 + r.1 - dist;
        // Contact point halfway through the overlap zone (LAMMPS convention).
        let arm_i = r.0 - 0.5 * overlap;
        let arm_j = r.1 - 0.5 * overlap;
        let v_rel = v.0 - v.1 + w.0.cross(n * arm_i) + w.1.cross(n * arm_j);
        let v_n = v_rel.dot(n);
        Contact {
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

    /// Builds the contact of a sphere (centre `x`, radius `r`) with a wall whose closest
    /// surface point is `p` and which moves at `wall_velocity`.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn with_wall(
        x: DVec3,
        p: DVec3,
        r: f64,
        mass: f64,
        inertia: f64,
        v: DVec3,
        w: DVec3,
        wall_velocity: DVec3,
        dt: f64,
    ) -> Option<Contact> {
        let d = p - x;
        let dist = d.length();
        if dist <= 0.0 {
            return None;
        }
        let n = d / dist;
        let overlap = r - dist;
        let arm_i = dist.min(r);
        let v_rel = v - wall_velocity + w.cross(n * arm_i);
        let v_n = v_rel.dot(n);
        Some(Contact {
            overlap,
            normal: n,
            r_eff: r,
            m_eff: mass,
            radius_i: r,
            radius_j: f64::INFINITY,
            arm_i,
            arm_j: f64::INFINITY,
            v_n,
            v_t: v_rel - n * v_n,
            omega_i: w,
            omega_j: DVec3::ZERO,
            mass_i: mass,
            mass_j: f64::INFINITY,
            inertia_i: inertia,
            inertia_j: f64::INFINITY,
            dt,
        })
    }
}

/// Rotates a history vector (a tangential spring, a rolling torque) into the plane normal to
/// `n`, keeping its length: the contact turned, the spring turns with it.
#[inline]
pub fn rotate_into_plane(v: DVec3, n: DVec3) -> DVec3 {
    let len2 = v.length_squared();
    if len2 == 0.0 {
        return v;
    }
    let p = v - n * n.dot(v);
    let l2 = p.length_squared();
    if l2 > 0.0 { p * (len2 / l2).sqrt() } else { p }
}
