//! A synthetic heap: 2 mm spheres filling a cone of known slope on the study's tray.
//!
//! How it is built (all lengths in metres, heights from the tray top):
//!
//! - The cone stands on the tray (radius R = 30.9 mm, the 61.8 mm ring knife), apex up on
//!   the tray axis, base radius R, slope theta: surface h(rho) = R tan(theta) - rho tan(theta).
//! - **Surface layer**: spheres tangent to the cone's side from inside, placed by random
//!   sequential addition: a point P is drawn uniformly on the lateral surface (azimuth
//!   uniform, rho = R sqrt(U) so that the density per area is uniform), the sphere's centre is
//!   P - r n (n the outward unit normal), and it is kept if it overlaps no sphere placed
//!   before, rests on or above the tray (centre height >= r) and stays inside the cone at
//!   the apex (centre at least r from the apex, rho >= 0). Attempts stop after
//!   `surface_attempts`, close to the jamming limit of random sequential addition (about
//!   55 % of the surface covered), so the surface is as rough as a loose random layer is.
//! - **Interior**: the same for centres drawn uniformly in the cylinder around the cone,
//!   kept if the whole sphere is inside the cone (distance to the side >= r) and overlaps
//!   nothing: a loose random packing under the surface layer.
//! - **Overflow**: spheres on the floor (tray top - 20 mm) in a ring outside the tray, as the
//!   particles that ran off the ring knife; the reducer must leave them out.
//!
//! Everything is shifted to a tray centred off the origin, with its top at z = 20 mm, so the
//! reducer's use of the tray metadata is tested too.

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use std::collections::HashMap;
use std::f64::consts::TAU;
use tilth_tools::reduce::ParticleCloud;

pub const TRAY_RADIUS: f64 = 0.0309;
pub const TRAY_TOP: f64 = 0.020;
pub const CENTRE: (f64, f64) = (0.0012, -0.0007);
pub const DIAMETER: f64 = 0.002;

/// Spheres of one diameter with a hash grid for overlap tests.
struct Packing {
    d: f64,
    cells: HashMap<(i64, i64, i64), Vec<usize>>,
    centres: Vec<[f64; 3]>,
}

impl Packing {
    fn new(d: f64) -> Packing {
        Packing {
            d,
            cells: HashMap::new(),
            centres: Vec::new(),
        }
    }

    fn cell(&self, c: [f64; 3]) -> (i64, i64, i64) {
        let k = |v: f64| (v / self.d).floor() as i64;
        (k(c[0]), k(c[1]), k(c[2]))
    }

    /// Adds a sphere at `c` unless it overlaps one already placed.
    fn try_add(&mut self, c: [f64; 3]) -> bool {
        let (i, j, k) = self.cell(c);
        for di in -1..=1 {
            for dj in -1..=1 {
                for dk in -1..=1 {
                    if let Some(list) = self.cells.get(&(i + di, j + dj, k + dk)) {
                        for &n in list {
                            let o = self.centres[n];
                            let d2 = (0..3).map(|a| (o[a] - c[a]).powi(2)).sum::<f64>();
                            if d2 < self.d * self.d {
                                return false;
                            }
                        }
                    }
                }
            }
        }
        self.cells
            .entry((i, j, k))
            .or_default()
            .push(self.centres.len());
        self.centres.push(c);
        true
    }
}

/// How the spheres touching the cone's side are laid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Surface {
    /// Rings one diameter apart along the side, each full of spheres at a random phase:
    /// about 79 % of the side covered.
    Rings,
    /// Random sequential addition until jammed: about 55 % covered, a very rough surface.
    Random,
}

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// The synthetic heap at slope `theta_deg`, from `seed`; returns the cloud and how many
/// particles are on the tray.
pub fn synthetic_cone(theta_deg: f64, seed: u64, surface: Surface) -> (ParticleCloud, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (r, big_r) = (0.5 * DIAMETER, TRAY_RADIUS);
    let th = theta_deg.to_radians();
    let (t, s, c) = (th.tan(), th.sin(), th.cos());
    let height = big_r * t;
    let mut p = Packing::new(DIAMETER);
    // Heap coordinates: origin on the tray axis at the tray top.
    let inside = |rho: f64, z: f64| {
        z >= r
            && rho >= 0.0
            && (height - z - rho * t) * c >= r - 1e-12
            && (rho * rho + (height - z).powi(2)).sqrt() >= r
    };
    match surface {
        Surface::Rings => {
            // Ring k touches the side at slant distance k d from the foot; its centres lie
            // on a circle of radius rho_c at height z_c, spaced so that neighbours' centres are
            // at least d apart (chord 2 rho_c sin(pi / n) >= d), at a random phase.
            let mut k = 0.0;
            loop {
                let rho_p = big_r - (r + k * DIAMETER) * c;
                let (rho, z) = (rho_p - r * s, height - rho_p * t - r * c);
                if rho < 0.0 {
                    break;
                }
                let n = if rho < r {
                    1
                } else {
                    (std::f64::consts::PI / (r / rho).min(1.0).asin()).floor() as usize
                };
                let phase = TAU * uniform(&mut rng);
                for j in 0..n {
                    let a = phase + TAU * j as f64 / n as f64;
                    let rho = if n == 1 { 0.0 } else { rho };
                    if inside(rho, z) {
                        p.try_add([rho * a.cos(), rho * a.sin(), z]);
                    }
                }
                k += 1.0;
            }
        }
        Surface::Random => {
            let surface_area = std::f64::consts::PI * big_r * big_r / c;
            let attempts = (60.0 * surface_area / (std::f64::consts::PI * r * r)) as usize;
            for _ in 0..attempts {
                let (rho_p, phi) = (big_r * uniform(&mut rng).sqrt(), TAU * uniform(&mut rng));
                let rho = rho_p - r * s;
                let z = height - rho_p * t - r * c;
                if inside(rho, z) {
                    p.try_add([rho * phi.cos(), rho * phi.sin(), z]);
                }
            }
        }
    }
    let volume_attempts = 60_000;
    for _ in 0..volume_attempts {
        let (x, y) = (
            big_r * (2.0 * uniform(&mut rng) - 1.0),
            big_r * (2.0 * uniform(&mut rng) - 1.0),
        );
        let z = height * uniform(&mut rng);
        if inside(x.hypot(y), z) {
            p.try_add([x, y, z]);
        }
    }
    let on_tray = p.centres.len();
    // Overflow on the floor, 20 mm below the tray top, outside the ring knife.
    for _ in 0..4000 {
        let rho = big_r + 0.003 + 0.02 * uniform(&mut rng);
        let phi = TAU * uniform(&mut rng);
        p.try_add([rho * phi.cos(), rho * phi.sin(), r - 0.020]);
    }
    let mut cloud = ParticleCloud::default();
    for (k, q) in p.centres.iter().enumerate() {
        cloud.x.push(q[0] + CENTRE.0);
        cloud.y.push(q[1] + CENTRE.1);
        cloud.z.push(q[2] + TRAY_TOP);
        cloud.radius.push(r);
        cloud.speed.push(0.0);
        cloud.id.push(k as u32);
        cloud.material.push(0);
    }
    (cloud, on_tray)
}
