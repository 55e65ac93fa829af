//! The observable a run reports as it develops, until the virtual lab's reducers exist.
//!
//! `heap_cone_angle_deg`: the heap on a disc wall named `tray` seen as a cone standing on the
//! whole tray, atan(H / R), with H the highest particle top above the tray and R the tray's
//! radius. It is the cone-fit cross-check EDEM users make by eye, not the study's
//! boundary-fit method (that comes with the repose reducer).

use crate::config::WallShape;
use serde::Serialize;
use tilth_kernel::sim::Simulation;

/// The disc the heap stands on.
#[derive(Debug, Clone, Copy)]
pub struct Tray {
    pub centre: [f64; 3],
    pub radius: f64,
    /// Particles above this height (m) are not part of the heap (e.g. still in a funnel).
    pub ceiling: f64,
}

/// The heap on the tray.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Heap {
    /// Highest particle top above the tray, m.
    pub height_m: f64,
    /// Particles above the tray's face.
    pub particles_on_tray: usize,
    /// Their mass, kg.
    pub mass_on_tray_kg: f64,
    /// atan(height / tray radius), degrees.
    pub cone_angle_deg: f64,
}

/// The wall named `tray`, if it is a horizontal disc.
pub fn find_tray(names: &[String], shapes: &[WallShape]) -> Option<Tray> {
    let k = names.iter().position(|n| n == "tray")?;
    match &shapes[k] {
        WallShape::Axisymmetric {
            base,
            axis,
            radius_base,
            length,
            ..
        } if *length == 0.0 && axis[0] == 0.0 && axis[1] == 0.0 => Some(Tray {
            centre: *base,
            radius: *radius_base,
            ceiling: f64::INFINITY,
        }),
        _ => None,
    }
}

/// A grain slower than this (m/s) counts as part of the heap; a faster one is taken for a
/// grain still falling onto it.
pub const HEAP_SPEED: f64 = 0.05;

/// Measures the heap on `tray` now.
pub fn heap(sim: &Simulation, tray: Tray) -> Heap {
    let p = &sim.particles;
    let [cx, cy, cz] = tray.centre;
    let mut top: f64 = 0.0;
    let mut n = 0;
    let mut mass = 0.0;
    for k in 0..p.len() {
        let x = p.position[k];
        let r = p.radius[k];
        let inside = (x.x - cx).hypot(x.y - cy) <= tray.radius;
        // Resting on the tray or on particles on it; falling particles far above are ignored.
        if inside && x.z > cz && x.z < tray.ceiling && p.velocity[k].length() < HEAP_SPEED {
            top = top.max(x.z + r - cz);
            n += 1;
            mass += p.mass[k];
        }
    }
    Heap {
        height_m: top,
        particles_on_tray: n,
        mass_on_tray_kg: mass,
        cone_angle_deg: (top / tray.radius).atan().to_degrees(),
    }
}
