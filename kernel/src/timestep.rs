//! Time step limits.
//!
//! Rayleigh time T_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766)  (s), the period of a
//! Rayleigh surface wave crossing a particle; EDEM practice is dt = 0.2-0.4 T_R.
//! Reference: docs/physics.md; Li, Xu, Thornton (2005) Powder Technol. 160:219.
//!
//! ```
//! use tilth_kernel::timestep::rayleigh_time;
//! // The study's soil: E = 13.5 MPa, nu = 0.2, rho = 1380, R = 1 mm -> T_R ~ 5.4e-5 s.
//! let t = rayleigh_time(1e-3, 1380.0, 13.5e6 / 2.4, 0.2);
//! assert!((t - 5.4e-5).abs() < 0.1e-5);
//! ```

/// T_R (s) for radius `r` (m), density `rho` (kg/m^3), shear modulus `g` (Pa), Poisson ratio `nu`.
pub fn rayleigh_time(r: f64, rho: f64, g: f64, nu: f64) -> f64 {
    std::f64::consts::PI * r * (rho / g).sqrt() / (0.1631 * nu + 0.8766)
}

/// Fraction of T_R above which a time step earns a warning.
pub const WARN_FRACTION: f64 = 0.4;

/// Fraction of a bond's time scale sqrt(m / (S A)) above which a time step earns a warning.
/// A particle carries several bonds in parallel, with their bending and twisting springs: in
/// the virtual lab's UCS test a step of 0.2 of the scale gained energy until it blew up and
/// 0.07 ran clean (the lab uses 0.08).
pub const BOND_WARN_FRACTION: f64 = 0.1;

/// Mean coordination number assumed by [`loaded_packing_step`]: a dense frictional packing
/// under load has 4.5-6 contacts a grain, a frictionless one 6 (isostatic); the lab's 2 mm
/// shear specimen, over-compacted when its friction was lost, had 7.7.
pub const LOADED_COORDINATION: f64 = 6.0;

/// A packing of equal spheres under a mean pressure: what [`loaded_packing_step`]
/// needs to know.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoadedPacking {
    /// Sphere radius, m.
    pub radius: f64,
    /// Particle density, kg/m^3.
    pub density: f64,
    /// Young's modulus, Pa.
    pub youngs_modulus: f64,
    /// Poisson ratio.
    pub poisson_ratio: f64,
    /// Coefficient of restitution of the restitution damping law.
    pub restitution: f64,
    /// Mean pressure the packing carries, Pa.
    pub pressure: f64,
    /// Contacts a grain.
    pub coordination: f64,
    /// Solid fraction.
    pub solid_fraction: f64,
}

/// Longest stable step (s) for a [`LoadedPacking`]: radius r, density rho, Young's modulus
/// E, Poisson ratio nu, coordination Z, solid fraction phi, pressure p.
///
/// The Rayleigh time does not see the load: a Hertz contact stiffens as it is pressed, and
/// a grain in a packing sits on several springs at once. So:
///
/// 1. Mean contact force from the stress of a packing, p = Z phi f / (pi d^2) (the
///    Love-Weber average sigma = (1/V) sum f l for equal spheres): f = pi d^2 p / (Z phi).
/// 2. Hertz overlap from f = (4/3) E* sqrt(R*) delta^(3/2), with E* = E / (2 (1 - nu^2)),
///    R* = r / 2, and the contact radius a = sqrt(R* delta).
/// 3. Contact stiffnesses k_n = 2 E* a and k_t = 8 G* a (Mindlin), G* = G / (2 (2 - nu)).
/// 4. One contact's stiffest mode: the tangential spring with both grains sliding and
///    rolling, effective inverse mass 2/m + 2 r^2 / I = 7/m (I = 2/5 m r^2), so
///    omega_1^2 = 7 k_t / m; the normal mode has 2 k_n / m, smaller for any nu >= 0.
/// 5. A grain on Z such springs: omega^2 <= Z omega_1^2 (a row-sum bound on the
///    mass-weighted stiffness matrix).
/// 6. Velocity Verlet is stable for omega dt < 2 undamped and for
///    omega dt < 2 (sqrt(1 + zeta^2) - zeta) with damping ratio zeta. The restitution law's
///    tangential dashpot, 2 sqrt(5/6) |beta| sqrt(k_t m*) with m* = m / 2, acts on the
///    rolling-sliding mode's mass m / 7: zeta = sqrt(5/6) |beta| sqrt(7/2), with
///    beta = ln(e) / sqrt(ln(e)^2 + pi^2). The step is taken at omega dt = 1, half the
///    undamped limit, while that is below the damped one (zeta up to 0.75, restitution from
///    0.22 up), and at the damped limit below that.
///
/// The step scales as r sqrt(rho / E) (p / E)^(-1/6): with the study's soil (E = 13.5 MPa,
/// nu = 0.2) it is about 12 % of the Rayleigh time at 100 kPa and 20 % at 4 kPa. Above it a
/// frictional packing loses its friction (tests/tests/loaded_packing.rs: at restitution
/// 0.45 it holds at this step and not at twice it; at 0.1 it holds at the damped limit and
/// not at omega dt = 1; measured once, at 0.2 it held at omega dt = 1 and not at 1.5).
///
/// Reference: Hertz and Mindlin as in docs/physics.md; Love-Weber stress (Christoffersen, Mehrabadi
/// and Nemat-Nasser 1981, J. Appl. Mech. 48:339); the explicit scheme's limit as in O'Sullivan
/// and Bray (2004), Eng. Comput. 21:278, who bound it with the same row sums.
pub fn loaded_packing_step(packing: &LoadedPacking) -> f64 {
    use std::f64::consts::PI;
    let LoadedPacking {
        radius: r,
        density: rho,
        youngs_modulus: e,
        poisson_ratio: nu,
        restitution,
        pressure,
        coordination,
        solid_fraction: phi,
    } = *packing;
    let d = 2.0 * r;
    let force = PI * d * d * pressure / (coordination * phi);
    let e_star = e / (2.0 * (1.0 - nu * nu));
    let r_star = r / 2.0;
    let delta = (3.0 * force / (4.0 * e_star * r_star.sqrt())).powf(2.0 / 3.0);
    let a = (r_star * delta).sqrt();
    let g_star = e / (2.0 * (1.0 + nu)) / (2.0 * (2.0 - nu));
    let (k_n, k_t) = (2.0 * e_star * a, 8.0 * g_star * a);
    let mass = rho * 4.0 / 3.0 * PI * r.powi(3);
    let one = (7.0 * k_t).max(2.0 * k_n) / mass;
    let zeta = (5.0f64 / 6.0).sqrt()
        * crate::contact::laws::restitution::beta(restitution).abs()
        * 3.5f64.sqrt();
    damped_verlet_limit(zeta).min(1.0) / (coordination * one).sqrt()
}

/// The largest omega dt at which velocity Verlet stays stable for an oscillator of damping
/// ratio `zeta`: 2 (sqrt(1 + zeta^2) - zeta), 2 undamped.
pub fn damped_verlet_limit(zeta: f64) -> f64 {
    2.0 * ((1.0 + zeta * zeta).sqrt() - zeta)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_loaded_packing_steps_at_a_fraction_of_the_rayleigh_time_falling_with_the_load() {
        // The study's soil, 2 mm grains, phi 0.6, Z 6: the doc comment's numbers.
        let t_r = rayleigh_time(1e-3, 1380.0, 13.5e6 / 2.4, 0.2);
        let step = |pressure, restitution| {
            loaded_packing_step(&LoadedPacking {
                radius: 1e-3,
                density: 1380.0,
                youngs_modulus: 13.5e6,
                poisson_ratio: 0.2,
                restitution,
                pressure,
                coordination: 6.0,
                solid_fraction: 0.6,
            }) / t_r
        };
        assert!((step(1e5, 0.45) - 0.12).abs() < 0.01, "{}", step(1e5, 0.45));
        assert!((step(4e3, 0.45) - 0.20).abs() < 0.01, "{}", step(4e3, 0.45));
        // (p / E)^(-1/6): a 64-fold load halves the step.
        assert!((step(1e3, 0.45) / step(64e3, 0.45) - 2.0).abs() < 1e-9);
        // Damping shortens it only below restitution 0.22 (zeta = 0.75), and continuously:
        // at 0.2 (zeta = 0.78) by 2 %.
        assert_eq!(step(1e5, 0.22), step(1e5, 1.0));
        assert!(step(1e5, 0.2) < step(1e5, 0.22) && step(1e5, 0.2) > 0.97 * step(1e5, 0.22));
        // At e = 0.1: beta = -0.591, zeta = 1.011, limit 2 (sqrt(1 + zeta^2) - zeta) = 0.82.
        assert!((step(1e5, 0.1) / step(1e5, 1.0) - 0.82).abs() < 0.01);
    }
}
