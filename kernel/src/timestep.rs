//! Time step limits.
//!
//! Rayleigh time T_R = pi R sqrt(rho / G) / (0.1631 nu + 0.8766)  (s), the period of a
//! Rayleigh surface wave crossing a particle; EDEM practice is dt = 0.2-0.4 T_R.
//! Reference: physics.md; Li, Xu, Thornton (2005) Powder Technol. 160:219.
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
