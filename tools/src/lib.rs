//! tilth-tools: offline reductions of runs (repose angle, peak shear force, compressive
//! strength) and statistics. This issue only provides the crate; the reducers land with the
//! virtual-laboratory issue.

pub mod design;
