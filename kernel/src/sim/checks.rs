//! The failure checks of the particle phase: the cheap test (branch-free, on every
//! particle), the exact one (for a chunk the cheap one flagged), and the error a failed
//! particle stops the run with.

use super::{Aabb, Simulation};
use crate::error::KernelError;
use crate::timestep::WARN_FRACTION;
use glam::DVec3;

impl Simulation {
    /// The error that stops the run at particle `i`, failed as `kind`: what is wrong, and
    /// its most likely cause (first a time step too long for the Rayleigh time).
    pub(super) fn failure(&self, i: usize, kind: Failure) -> KernelError {
        let p = &self.particles;
        let (x, v) = (p.position[i], p.velocity[i]);
        let frac = self.dt / self.rayleigh_time;
        let dt_cause = (frac > WARN_FRACTION).then(|| {
            format!(
                "the time step {:.3e} s is {:.0} % of the Rayleigh time {:.3e} s; use at most 40 % (EDEM practice 20-40 %)",
                self.dt,
                100.0 * frac,
                self.rayleigh_time
            )
        });
        let (what, cause) = match kind {
            Failure::NonFinite => (
                format!("particle {i} has a non-finite position, velocity or spin (x = {:?})", x.to_array()),
                dt_cause.unwrap_or_else(|| "a contact produced a non-finite force: check for particles created on top of each other or walls, and for extreme law parameters".into()),
            ),
            Failure::Runaway => (
                format!("particle {i} moves at {:.3e} m/s, above the {:.3e} m/s any physical motion here can reach (runaway kinetic energy)", v.length(), self.speed_limit),
                dt_cause.unwrap_or_else(|| "energy is being injected: particles created overlapping, a wall moving or a servo pushing too fast, an unstable law parameter, or a step too long for strongly damped contacts (a low restitution coefficient, such as 0.15, lowers the explicit scheme's stability limit for the tangential spring: try 20 % of the Rayleigh time)".into()),
            ),
            Failure::Escaped => {
                // Faster than free fall plus every imposed speed: it was shot out, not spilled.
                let physical = (self.speed_limit - 1.0) / 10.0;
                let shot = v.length() > 2.0 * physical;
                (
                    format!(
                        "particle {i} left the domain [{:?}, {:?}] at x = {:?} m, v = {:?} m/s",
                        self.domain.min.to_array(),
                        self.domain.max.to_array(),
                        x.to_array(),
                        v.to_array()
                    ),
                    dt_cause.unwrap_or_else(|| {
                        if shot {
                            format!("it moves at {:.3} m/s, faster than anything in this set-up can make it ({physical:.3} m/s): energy was injected, most often by particles created overlapping a wall (check factory regions against the geometry) or by a wall moving too fast", v.length())
                        } else {
                            "the geometry is open (a missing wall) or particles tunnelled through a wall; enlarge the domain or close the geometry".into()
                        }
                    }),
                )
            }
        };
        KernelError::BlowUp {
            step: self.step,
            time: self.time,
            what,
            cause,
        }
    }
}

/// The cheap test, as the two halves below make it: false for every state [`check`]
/// refuses (and for a few it accepts, such as a finite spin too large to square).
#[cfg(test)]
fn plausible(x: DVec3, v: DVec3, w: DVec3, limit2: f64, dom: Aabb) -> bool {
    plausible_position(x, dom) & plausible_motion(v, w, limit2)
}

// The cheap test in two halves, each made where what it tests changes: the position in the
// drift, while it is in registers; the velocities in the particle phase, after its kick.
// Written with `&`, not `&&`: no branch per particle. The exact test on each particle took
// about a fifth of the particle phase in a dilute flow; the cheap one about half as much,
// and loading each position again for it was most of what was left.

/// The velocity half of the cheap test.
#[inline(always)]
pub(super) fn plausible_motion(v: DVec3, w: DVec3, limit2: f64) -> bool {
    let (v2, w2) = (v.length_squared(), w.length_squared());
    // A NaN fails every comparison; an infinity makes its square infinite.
    (v2 <= limit2) & (v2 < f64::INFINITY) & (w2 < f64::INFINITY)
}

/// The position half of the cheap test.
#[inline(always)]
pub(super) fn plausible_position(x: DVec3, dom: Aabb) -> bool {
    (x.length_squared() < f64::INFINITY)
        & (x.x >= dom.min.x)
        & (x.y >= dom.min.y)
        & (x.z >= dom.min.z)
        & (x.x <= dom.max.x)
        & (x.y <= dom.max.y)
        & (x.z <= dom.max.z)
}

/// What is wrong with a particle after its kick, if anything.
#[inline]
pub(super) fn check(x: DVec3, v: DVec3, w: DVec3, limit2: f64, dom: Aabb) -> Option<Failure> {
    if !(x.is_finite() && v.is_finite() && w.is_finite()) {
        Some(Failure::NonFinite)
    } else if v.length_squared() > limit2 {
        Some(Failure::Runaway)
    } else if x.cmplt(dom.min).any() || x.cmpgt(dom.max).any() {
        Some(Failure::Escaped)
    } else {
        None
    }
}

/// What is wrong with a failed particle.
#[derive(Debug, Clone, Copy)]
pub(super) enum Failure {
    NonFinite,
    Runaway,
    Escaped,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every state the exact test refuses, the cheap one flags: a failure is never missed.
    /// Components from finite, huge, infinite and NaN values, against finite and infinite
    /// domains and speed limits.
    #[test]
    fn the_cheap_test_flags_every_state_the_exact_one_refuses() {
        let values = [
            0.0,
            0.5,
            -0.5,
            2.0,
            -2.0,
            1e200,
            -1e200,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let domains = [
            Aabb {
                min: DVec3::splat(-1.0),
                max: DVec3::splat(1.0),
            },
            Aabb {
                min: DVec3::splat(f64::NEG_INFINITY),
                max: DVec3::splat(f64::INFINITY),
            },
        ];
        let mut refused = 0;
        for dom in domains {
            for limit2 in [1.0, f64::INFINITY] {
                for &a in &values {
                    for &b in &values {
                        // One odd component on each vector in turn, the rest ordinary.
                        let odd = [
                            (DVec3::new(a, 0.1, b), DVec3::splat(0.1), DVec3::splat(0.1)),
                            (DVec3::splat(0.1), DVec3::new(0.1, a, b), DVec3::splat(0.1)),
                            (DVec3::splat(0.1), DVec3::splat(0.1), DVec3::new(b, 0.1, a)),
                        ];
                        for (x, v, w) in odd {
                            let exact = check(x, v, w, limit2, dom);
                            let cheap = plausible(x, v, w, limit2, dom);
                            if exact.is_some() {
                                refused += 1;
                                assert!(!cheap, "missed {exact:?} at x {x} v {v} w {w}");
                            }
                        }
                    }
                }
            }
        }
        // The grid does reach the failures, and the cheap test passes ordinary states.
        assert!(refused > 500, "{refused}");
        assert!(plausible(
            DVec3::splat(0.1),
            DVec3::splat(0.1),
            DVec3::splat(0.1),
            1.0,
            domains[0]
        ));
    }
}
