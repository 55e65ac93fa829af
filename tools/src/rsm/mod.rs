//! Response surfaces: regression, ANOVA, solving and steepest ascent on tables of runs, as
//! Design-Expert and R's `rsm` do them.
//!
//! - [`Table`] reads a CSV of runs; [`Data`] picks the factors and the response and codes
//!   the factors to -1..+1.
//! - [`fit`] fits a linear, two-factor-interaction or quadratic model and returns its
//!   [`Anova`]: Type III sums of squares, F and p per term, curvature, lack of fit, R^2,
//!   adjusted and predicted R^2, adequate precision, the equation in coded and real units,
//!   with optional backward elimination.
//! - [`solve`] traces every setting that hits a target (a ridge when the target cannot
//!   separate the factors) and says so.
//! - [`steepest_path`] and [`next_region`] lead from a screening fit to the next design.
//! - [`compare_reported`] checks a fit against a published ANOVA table, value by value.

mod anova;
mod coding;
mod data;
mod equation;
mod error;
mod ols;
mod path;
pub mod plot;
mod reported;
mod solve;
mod table;
mod terms;

pub use anova::{Anova, FitOptions, RunDiagnostic, SourceRow, TermRow, fit};
pub use coding::Coding;
pub use data::Data;
pub use equation::{format as format_equation, significant};
pub use error::RsmError;
pub use path::{NextRegion, SteepestPath, next_region, steepest_path};
pub use reported::{Check, compare_reported};
pub use solve::{Setting, Solution, solve};
pub use table::Table;
pub use terms::{Order, Term, canonical};
