//! Protocols: what happens during a run, phase by phase (fill, settle, compact, bond, load).
//!
//! The runner steps the simulation in blocks; between blocks it asks the protocol what to
//! do next. A plain scene runs to its end; an experiment moves walls, forms bonds, removes a
//! mould and decides when it is finished (a settled heap, 5 mm of shear, a peak load).

use anyhow::Result;
use std::collections::BTreeMap;
use tilth_kernel::sim::Simulation;

/// What the runner does next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Control {
    /// Step at most this many steps, then ask again.
    Step(u64),
    /// The run is complete.
    Done,
}

/// A run's script.
pub trait Protocol: Send {
    /// Called before every block of steps (and once at the start): may act on `sim`
    /// (walls, bonds) and says how far to go.
    fn control(&mut self, sim: &mut Simulation) -> Result<Control>;
    /// The experiment's own scalar channels now (name, value); units in [`Protocol::units`].
    fn scalars(&self, _sim: &Simulation) -> Vec<(String, f64)> {
        vec![]
    }
    /// Units of the scalar channels.
    fn units(&self) -> Vec<(String, String)> {
        vec![]
    }
    /// The `tilth.experiment` metadata record (type and dimensions for the reducers).
    fn metadata(&self) -> BTreeMap<String, String> {
        BTreeMap::new()
    }
    /// The current phase, for progress bars.
    fn phase(&self) -> String {
        String::new()
    }
    /// Fraction done in [0, 1], for progress bars.
    fn progress(&self, sim: &Simulation) -> f64;
    /// Results and warnings worth putting in the run summary.
    fn summary(&self, _sim: &Simulation) -> serde_json::Value {
        serde_json::Value::Null
    }
}

/// A plain scene: run its steps.
pub struct RunSteps {
    pub steps: u64,
}

impl Protocol for RunSteps {
    fn control(&mut self, sim: &mut Simulation) -> Result<Control> {
        Ok(if sim.step >= self.steps {
            Control::Done
        } else {
            Control::Step(self.steps - sim.step)
        })
    }

    fn progress(&self, sim: &Simulation) -> f64 {
        sim.step as f64 / self.steps.max(1) as f64
    }
}
