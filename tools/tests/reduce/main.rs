//! The reducers through the real reading path: MCAP files written in the runner's layout
//! (fixture.rs), read back with `read_run`, reduced, and drawn.
//!
//! Pictures and files land in `<target>/tmp/reduce-tests/` for a person to look at.

mod cone;
mod fixture;
mod reading;
mod repose;
mod shear;
mod ucs;
