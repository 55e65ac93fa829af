//! Neighbour search: linked cells build a Verlet pair list with a skin; the list carries the
//! contact history, which survives every rebuild (matched by particle pair).

pub mod cells;
pub mod pairs;
pub mod schedule;
pub(crate) mod wall_list;

pub use cells::CellGrid;
pub use pairs::PairList;
pub use schedule::PairSchedule;
pub(crate) use wall_list::{WallContacts, build_wall_contacts};

/// Rows (particles, or pairs in the pair phase) handled by one parallel task. Fixed, so the
/// work split (and every sum) is the same on any number of threads. Small enough that the
/// last task of a phase is short (at 20,000 particles, 157 tasks of a few microseconds); the
/// settling bed's 2-thread speed was the same at 128 and 256 and lower at 64 and 512
/// (measured with `tilth bench settling-bed --threads 2`).
pub const CHUNK: usize = 128;

/// The most chunks one task of a parallel loop takes (rayon's `with_max_len`): one when
/// several threads share the work, so that an idle thread can always take the next chunk
/// and the threads finish a phase together. Rayon's adaptive split otherwise hands out
/// pieces of many chunks that cannot be shared once started. No limit on one thread, where
/// splitting is overhead only. Call it inside the pool. The bits do not depend on it.
pub fn chunks_per_task() -> usize {
    if rayon::current_num_threads() > 1 {
        1
    } else {
        usize::MAX
    }
}
