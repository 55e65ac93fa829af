//! tilth-tools: offline reductions of runs (repose angle, peak shear force, compressive
//! strength: [`reduce`]) and statistics (experimental designs: [`design`]).

// Range checks are written `!(x > 0.0)` on purpose: the negation also refuses NaN, which
// `x <= 0.0` would let through.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod calibrate;
pub mod compare;
pub mod consistency;
pub mod design;
pub mod diagnose;
pub mod reduce;
pub mod rsm;
