//! The step loop of a run: the protocol says how far to step, the frames that fall due are
//! recorded, and the stop flag and progress are looked at along the way.

use super::{Live, PROGRESS_SCALE};
use crate::lab::observe::{self, Tray};
use crate::lab::protocol::{Control, Protocol};
use crate::record::{FrameRates, Recorder, snapshot};
use crate::sweep::plan::Plan;
use anyhow::Result;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use tilth_kernel::sim::Simulation;

/// Steps between looks at the stop flag.
const STOP_CHECK: u64 = 1000;

/// What the step loop needs besides the simulation: how often to record, when to stop and
/// where to show progress.
pub(super) struct Stepping<'a> {
    pub(super) plan: &'a Plan,
    /// Frame intervals in steps, for the time step `rates_dt`. They are resolved again
    /// whenever the protocol changes the time step (bonded specimens), so that frames keep
    /// their rates in simulated time.
    pub(super) rates: FrameRates,
    pub(super) rates_dt: f64,
    pub(super) tray: Option<Tray>,
    pub(super) stop: &'a AtomicBool,
    pub(super) live: &'a Live,
    /// The run's name in errors.
    pub(super) origin: &'a str,
}

/// How the step loop ended.
pub(super) struct Stepped {
    /// When stepping began, for the run's wall time.
    pub(super) started: Instant,
    /// Steps times particles, for the cost per particle step.
    pub(super) particle_steps: u64,
    /// Stopped by the stop flag.
    pub(super) interrupted: bool,
    /// The error that ended the run early, with the run's name.
    pub(super) failure: Option<anyhow::Error>,
}

impl Stepping<'_> {
    /// Steps `sim` as `protocol` says until it is done, fails or the stop flag is set,
    /// recording the frames that fall due. An error of the recording itself is returned as
    /// an `Err`; one of the simulation or protocol ends the loop as `failure`.
    pub(super) fn run(
        &mut self,
        sim: &mut Simulation,
        protocol: &mut dyn Protocol,
        recorder: &mut Recorder,
    ) -> Result<Stepped> {
        let started = Instant::now();
        let mut particle_steps: u64 = 0;
        let mut interrupted = false;
        let mut failure = None;
        record_due(sim, protocol, recorder, self.rates, self.tray)?;
        loop {
            if self.stop.load(Ordering::Relaxed) {
                interrupted = true;
                break;
            }
            let k = match protocol.control(sim) {
                Ok(Control::Done) => break,
                Ok(Control::Step(k)) => k.max(1),
                Err(e) => {
                    failure = Some(e.context(self.origin.to_string()));
                    break;
                }
            };
            if sim.dt != self.rates_dt {
                self.rates = self.plan.record.resolve(sim.dt)?;
                self.rates_dt = sim.dt;
            }
            // Stop at the next frame due and often enough to see the stop flag.
            let n = self
                .rates
                .steps_to_next(sim.step, k)
                .min(STOP_CHECK - sim.step % STOP_CHECK);
            let before = sim.particles.len() as u64;
            if let Err(e) = sim.run(n) {
                failure = Some(anyhow::Error::from(e).context(self.origin.to_string()));
                break;
            }
            particle_steps += n * before.max(sim.particles.len() as u64);
            let done = (protocol.progress(sim).clamp(0.0, 1.0) * PROGRESS_SCALE as f64) as u64;
            self.live.step.store(done, Ordering::Relaxed);
            record_due(sim, protocol, recorder, self.rates, self.tray)?;
        }
        Ok(Stepped {
            started,
            particle_steps,
            interrupted,
            failure,
        })
    }
}

/// Sends the frames due at the current step: particles, walls, scalars and bonds, each at
/// its own rate.
fn record_due(
    sim: &Simulation,
    protocol: &dyn Protocol,
    rec: &mut Recorder,
    rates: FrameRates,
    tray: Option<Tray>,
) -> Result<()> {
    let step = sim.step;
    if FrameRates::due(rates.particles, step) {
        rec.send(snapshot::particles(sim))?;
    }
    if FrameRates::due(rates.walls, step) {
        rec.send(snapshot::walls(sim))?;
    }
    if FrameRates::due(rates.scalars, step) {
        rec.send(snapshot::scalars(sim, &extra_scalars(sim, protocol, tray)))?;
    }
    if FrameRates::due(rates.bonds, step) {
        if let Some(b) = snapshot::bonds(sim) {
            rec.send(b)?;
        }
    }
    Ok(())
}

/// Scalars recorded besides the kernel's: the protocol's own, or else the heap on the tray.
fn extra_scalars(
    sim: &Simulation,
    protocol: &dyn Protocol,
    tray: Option<Tray>,
) -> Vec<(String, f64)> {
    let own = protocol.scalars(sim);
    if !own.is_empty() {
        return own;
    }
    tray.map(|t| {
        let h = observe::heap(sim, t);
        vec![
            ("heap_cone_angle_deg".to_string(), h.cone_angle_deg),
            ("heap_height".to_string(), h.height_m),
        ]
    })
    .unwrap_or_default()
}
