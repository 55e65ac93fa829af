//! Neighbour search: linked cells build a Verlet pair list with a skin; the list carries the
//! contact history, which survives every rebuild (matched by particle pair).

pub mod cells;
pub mod pairs;

pub use cells::CellGrid;
pub use pairs::PairList;

/// Rows handled by one parallel task. Fixed, so the work split (and every sum) is the same
/// on any number of threads.
pub const CHUNK: usize = 512;
