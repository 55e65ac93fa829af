//! Parameter uncertainty for a calibration: linearised confidence intervals from the
//! Jacobian of the residuals, and a posterior sample by sequential Monte Carlo.
//!
//! Both work on a cheap model of the observables (a fitted response surface), never on DEM
//! runs directly: a posterior needs tens of thousands of evaluations.

mod check_line;
mod jacobian;
mod least_squares;
mod smc;

pub use check_line::{Check, next_from_checks};
pub use jacobian::{Linearised, linearised};
pub use least_squares::{gauss_newton_step, minimise_in_box};
pub use smc::{Posterior, smc};
