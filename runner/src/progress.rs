//! The progress bar on stderr: shown only when stderr is a terminal and not `--quiet`.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};
use tilth_kernel::sim::Simulation;

/// A step counter bar that redraws at most every [`Self::PERIOD`].
pub struct Progress {
    bar: ProgressBar,
    last: Instant,
}

impl Progress {
    const PERIOD: Duration = Duration::from_millis(200);

    pub fn new(steps: u64, show: bool) -> Progress {
        let bar = if show && std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(Some(steps), ProgressDrawTarget::stderr());
            let style = ProgressStyle::with_template(
                "{bar:20} {pos}/{len} steps, {elapsed} elapsed, ETA {eta}: {wide_msg}",
            )
            .expect("valid template")
            .progress_chars("=> ");
            bar.set_style(style);
            bar
        } else {
            ProgressBar::hidden()
        };
        Progress {
            bar,
            last: Instant::now() - Self::PERIOD,
        }
    }

    /// Redraws with the state of `sim` if enough time has passed (cheap to call every step).
    pub fn update(&mut self, sim: &Simulation) {
        if self.bar.is_hidden() || self.last.elapsed() < Self::PERIOD {
            return;
        }
        self.last = Instant::now();
        let (pairs, walls) = sim.contact_counts();
        self.bar.set_position(sim.step);
        self.bar.set_message(format!(
            "t = {:.4} s, {} particles, {} contacts",
            sim.time,
            sim.particles.len(),
            pairs + walls
        ));
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
