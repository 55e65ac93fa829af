//! Where a run's time goes: wall-clock time per part of the step, summed over the steps (as
//! the "Pair / Neigh / Modify / Other" breakdown LAMMPS and LIGGGHTS print after a run).
//!
//! Timing reads the clock a few times a step (tens of nanoseconds each, against a step of
//! microseconds to milliseconds) and never touches the state: a run gives the same bits
//! whether anyone looks at its times or not.

use std::ops::Sub;
use std::time::{Duration, Instant};

/// Time spent in each part of [`crate::sim::Simulation::advance`], summed since the
/// simulation was built.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PhaseTimes {
    /// First half kick and drift (v += F dt/2m, omega += T dt/2I, x += v dt), and the walls'
    /// motion. Within [`crate::sim::Simulation::run`] the kick and drift of every step after
    /// the first are done in the step before's particle phase, and counted there.
    pub integrate: Duration,
    /// Factories creating particles.
    pub insert: Duration,
    /// Spatial reordering, neighbour-list rebuilds, and the loaded-step check made at each
    /// reorder.
    pub neighbor: Duration,
    /// Pair forces: every listed pair through the contact laws (and bonds).
    pub pair: Duration,
    /// Each particle's sums of its pairs, its wall contacts (the wall laws), gravity, the
    /// second half kick and the failure checks (within a run, also the next step's first
    /// half kick and drift); then the walls' totals.
    pub particle: Duration,
}

impl PhaseTimes {
    /// The parts with their names, in step order.
    pub fn parts(&self) -> [(&'static str, Duration); 5] {
        [
            ("integrate", self.integrate),
            ("insert", self.insert),
            ("neighbor", self.neighbor),
            ("pair", self.pair),
            ("particle", self.particle),
        ]
    }

    /// The sum of the parts.
    pub fn total(&self) -> Duration {
        self.parts().iter().map(|(_, d)| *d).sum()
    }
}

impl Sub for PhaseTimes {
    type Output = PhaseTimes;

    /// The time spent between two readings (`later - earlier`).
    fn sub(self, earlier: PhaseTimes) -> PhaseTimes {
        PhaseTimes {
            integrate: self.integrate.saturating_sub(earlier.integrate),
            insert: self.insert.saturating_sub(earlier.insert),
            neighbor: self.neighbor.saturating_sub(earlier.neighbor),
            pair: self.pair.saturating_sub(earlier.pair),
            particle: self.particle.saturating_sub(earlier.particle),
        }
    }
}

/// A stopwatch over consecutive parts: each `lap` returns the time since the previous one.
pub(crate) struct Laps(Instant);

impl Laps {
    pub(crate) fn start() -> Laps {
        Laps(Instant::now())
    }

    pub(crate) fn lap(&mut self) -> Duration {
        let now = Instant::now();
        let d = now - self.0;
        self.0 = now;
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_total_is_the_sum_of_the_parts_and_a_difference_is_per_part() {
        let ms = Duration::from_millis;
        let a = PhaseTimes {
            integrate: ms(1),
            insert: ms(2),
            neighbor: ms(3),
            pair: ms(4),
            particle: ms(5),
        };
        assert_eq!(a.total(), ms(15));
        let b = PhaseTimes {
            integrate: ms(11),
            insert: ms(2),
            neighbor: ms(6),
            pair: ms(24),
            particle: ms(9),
        };
        let d = b - a;
        assert_eq!(
            d.parts().map(|(_, t)| t),
            [ms(10), ms(0), ms(3), ms(20), ms(4)]
        );
        assert_eq!(
            d.parts().map(|(n, _)| n),
            ["integrate", "insert", "neighbor", "pair", "particle"]
        );
    }
}
