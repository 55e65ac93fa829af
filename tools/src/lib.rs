//! tilth-tools: offline reductions of runs (repose angle, peak shear force, compressive
//! strength: [`reduce`]) and statistics (experimental designs: [`design`]).

pub mod calibrate;
pub mod compare;
pub mod consistency;
pub mod design;
pub mod diagnose;
pub mod reduce;
pub mod rsm;
