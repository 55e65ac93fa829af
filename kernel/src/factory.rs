//! Dynamic particle generation (EDEM "dynamic factory").
//!
//! A factory creates particles inside a region at a rate (particles/s) up to a total, at
//! random positions that overlap neither existing particles nor each other, with radii from
//! a discrete size distribution given by number or by mass fraction. All randomness comes
//! from one seeded generator (ChaCha8), so a seed fixes the whole run.

use crate::error::{KernelError, Result};
use crate::particles::Particles;
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Where particles are created. The whole sphere lies inside the region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Region {
    Box {
        min: DVec3,
        max: DVec3,
    },
    /// Vertical cylinder: base centre, radius, height (m).
    Cylinder {
        base: DVec3,
        radius: f64,
        height: f64,
    },
}

/// Whether size fractions count particles or mass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Basis {
    Number,
    Mass,
}

#[derive(Debug, Clone)]
pub struct FactorySpec {
    pub region: Region,
    /// (radius m, fraction) pairs; fractions are normalised.
    pub sizes: Vec<(f64, f64)>,
    pub basis: Basis,
    pub material: u16,
    pub density: f64,
    /// Particles per second; `f64::INFINITY` creates all at once.
    pub rate: f64,
    pub count: usize,
    pub velocity: DVec3,
    pub start_time: f64,
    pub seed: u64,
}

#[derive(Debug, Clone)]
pub struct Factory {
    pub spec: FactorySpec,
    /// Cumulative number probabilities of the size classes.
    cumulative: Vec<f64>,
    rng: ChaCha8Rng,
    pub inserted: usize,
    /// Times a position was rejected for overlap (a crowded region shows here).
    pub rejections: u64,
}

/// Random placement attempts per particle per call before it is deferred to a later step.
const ATTEMPTS: usize = 200;

impl Factory {
    pub fn new(spec: FactorySpec) -> Result<Factory> {
        if spec.sizes.is_empty() {
            return Err(KernelError::Invalid(
                "factory: 'sizes' is empty; give at least one size class".into(),
            ));
        }
        for (k, &(r, w)) in spec.sizes.iter().enumerate() {
            if !(r > 0.0 && r.is_finite()) {
                return Err(KernelError::OutOfRange {
                    key: format!("factory.sizes[{k}].radius"),
                    value: r,
                    range: "(0, inf)".into(),
                    unit: "m".into(),
                });
            }
            if !(w >= 0.0 && w.is_finite()) {
                return Err(KernelError::OutOfRange {
                    key: format!("factory.sizes[{k}].fraction"),
                    value: w,
                    range: "[0, inf)".into(),
                    unit: "-".into(),
                });
            }
        }
        if !(spec.rate > 0.0) {
            return Err(KernelError::OutOfRange {
                key: "factory.rate".into(),
                value: spec.rate,
                range: "(0, inf]".into(),
                unit: "1/s".into(),
            });
        }
        // Mass fractions -> number weights: w_k / m_k, m_k ~ r_k^3 at one density.
        let weights: Vec<f64> = spec
            .sizes
            .iter()
            .map(|&(r, w)| {
                if spec.basis == Basis::Mass {
                    w / r.powi(3)
                } else {
                    w
                }
            })
            .collect();
        let total: f64 = weights.iter().sum();
        if !(total > 0.0) {
            return Err(KernelError::Invalid(
                "factory: size fractions sum to zero".into(),
            ));
        }
        let mut acc = 0.0;
        let cumulative = weights
            .iter()
            .map(|w| {
                acc += w / total;
                acc
            })
            .collect();
        let r_max = spec.sizes.iter().map(|s| s.0).fold(0.0, f64::max);
        let fits = match spec.region {
            Region::Box { min, max } => (max - min).min_element() > 2.0 * r_max,
            Region::Cylinder { radius, height, .. } => radius > r_max && height > 2.0 * r_max,
        };
        if !fits {
            return Err(KernelError::Invalid(format!(
                "factory region is too small for particles of radius {r_max} m"
            )));
        }
        let rng = ChaCha8Rng::seed_from_u64(spec.seed);
        Ok(Factory {
            spec,
            cumulative,
            rng,
            inserted: 0,
            rejections: 0,
        })
    }

    pub fn max_radius(&self) -> f64 {
        self.spec.sizes.iter().map(|s| s.0).fold(0.0, f64::max)
    }

    pub fn min_radius(&self) -> f64 {
        self.spec
            .sizes
            .iter()
            .map(|s| s.0)
            .fold(f64::INFINITY, f64::min)
    }

    pub fn done(&self) -> bool {
        self.inserted >= self.spec.count
    }

    /// How many particles should exist by time `t`.
    fn due(&self, t: f64) -> usize {
        if t < self.spec.start_time {
            return 0;
        }
        let n = ((t - self.spec.start_time) * self.spec.rate).floor();
        if n.is_finite() {
            (n as usize).min(self.spec.count)
        } else {
            self.spec.count
        }
    }

    /// Creates the particles due by time `t`; returns how many were created.
    pub fn insert(&mut self, t: f64, particles: &mut Particles) -> usize {
        let due = self.due(t);
        if due <= self.inserted {
            return 0;
        }
        let r_max = self.max_radius();
        let (lo, hi) = self.bounds();
        // Existing particles that could touch the region, binned so that each placement
        // attempt checks only its neighbourhood.
        let margin = DVec3::splat(2.0 * r_max);
        let mut near = LocalGrid::new(lo - margin, hi + margin, 2.0 * r_max);
        for i in 0..particles.len() {
            near.insert(particles.position[i], particles.radius[i]);
        }
        let mut made = 0;
        while self.inserted < due {
            let u: f64 = self.rng.random();
            let class = self
                .cumulative
                .iter()
                .position(|&c| u < c)
                .unwrap_or(self.cumulative.len() - 1);
            let r = self.spec.sizes[class].0;
            let mut placed = None;
            for _ in 0..ATTEMPTS {
                let p = self.sample(r);
                if near.is_free(p, r) {
                    placed = Some(p);
                    break;
                }
                self.rejections += 1;
            }
            let Some(p) = placed else { break };
            particles.push(
                p,
                self.spec.velocity,
                r,
                self.spec.density,
                self.spec.material,
            );
            near.insert(p, r);
            self.inserted += 1;
            made += 1;
        }
        made
    }

    fn bounds(&self) -> (DVec3, DVec3) {
        match self.spec.region {
            Region::Box { min, max } => (min, max),
            Region::Cylinder {
                base,
                radius,
                height,
            } => (
                base - DVec3::new(radius, radius, 0.0),
                base + DVec3::new(radius, radius, height),
            ),
        }
    }

    fn sample(&mut self, r: f64) -> DVec3 {
        match self.spec.region {
            Region::Box { min, max } => {
                let (a, b) = (min + DVec3::splat(r), max - DVec3::splat(r));
                DVec3::new(
                    self.rng.random_range(a.x..b.x),
                    self.rng.random_range(a.y..b.y),
                    self.rng.random_range(a.z..b.z),
                )
            }
            Region::Cylinder {
                base,
                radius,
                height,
            } => {
                let rr = radius - r;
                // Uniform over the disc: radius ~ sqrt(u).
                let rho = rr * self.rng.random::<f64>().sqrt();
                let phi = self.rng.random_range(0.0..std::f64::consts::TAU);
                let z = self.rng.random_range(r..height - r);
                base + DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
            }
        }
    }
}

/// A uniform grid of spheres over a box; spheres outside the box are ignored (they cannot
/// touch a particle placed inside the region). Linked cells in three flat vectors (each
/// cell's last sphere, each sphere's predecessor in its cell, the spheres), as LAMMPS bins
/// atoms: a vector per cell was one small allocation per occupied cell, about 100,000 for
/// the settling bench's bed, and glibc kept their ~10 MB resident long after the grid was
/// dropped.
struct LocalGrid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// The last sphere put in each cell, [`NONE`] for an empty cell.
    head: Vec<u32>,
    /// The sphere put in the same cell before this one, [`NONE`] for the first.
    next: Vec<u32>,
    spheres: Vec<(DVec3, f64)>,
    r_max: f64,
}

/// No sphere.
const NONE: u32 = u32::MAX;

impl LocalGrid {
    fn new(lo: DVec3, hi: DVec3, cell: f64) -> LocalGrid {
        let d = ((hi - lo) / cell).ceil().max(DVec3::ONE);
        let dims = [d.x as usize, d.y as usize, d.z as usize];
        LocalGrid {
            lo,
            cell,
            dims,
            head: vec![NONE; dims[0] * dims[1] * dims[2]],
            next: vec![],
            spheres: vec![],
            r_max: 0.0,
        }
    }

    fn coords(&self, p: DVec3) -> Option<[usize; 3]> {
        let q = (p - self.lo) / self.cell;
        let ok = (0..3).all(|k| q[k] >= 0.0 && (q[k] as usize) < self.dims[k]);
        ok.then_some([q.x as usize, q.y as usize, q.z as usize])
    }

    fn insert(&mut self, p: DVec3, r: f64) {
        if let Some(c) = self.coords(p) {
            self.r_max = self.r_max.max(r);
            let cell = (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0];
            self.next.push(self.head[cell]);
            self.head[cell] = self.spheres.len() as u32;
            self.spheres.push((p, r));
        }
    }

    /// No stored sphere overlaps a sphere of radius `r` at `p`.
    fn is_free(&self, p: DVec3, r: f64) -> bool {
        let reach = ((r + self.r_max) / self.cell).ceil() as i64;
        let q = ((p - self.lo) / self.cell).floor();
        for z in q.z as i64 - reach..=q.z as i64 + reach {
            for y in q.y as i64 - reach..=q.y as i64 + reach {
                for x in q.x as i64 - reach..=q.x as i64 + reach {
                    if x < 0
                        || y < 0
                        || z < 0
                        || x >= self.dims[0] as i64
                        || y >= self.dims[1] as i64
                        || z >= self.dims[2] as i64
                    {
                        continue;
                    }
                    let c = (z as usize * self.dims[1] + y as usize) * self.dims[0] + x as usize;
                    let mut k = self.head[c];
                    while k != NONE {
                        let (s, rs) = self.spheres[k as usize];
                        if (p - s).length_squared() < (r + rs) * (r + rs) {
                            return false;
                        }
                        k = self.next[k as usize];
                    }
                }
            }
        }
        true
    }
}
