//! What the simulation thread hands to the writer: compact copies taken between steps.

use tilth_kernel::sim::Simulation;

/// Bytes per point in `/particles`: x, y, z, radius, speed (f32), id, material (u32).
pub const POINT_STRIDE: usize = 28;

/// One frame of one channel group, stamped with simulated time (s).
#[derive(Debug, Clone)]
pub enum Record {
    /// Every particle, packed as [`POINT_STRIDE`]-byte little-endian points.
    Particles {
        time: f64,
        count: u32,
        points: Vec<u8>,
    },
    /// Each wall's displacement from its initial pose (m), force and torque (N, N m).
    Walls {
        time: f64,
        offsets: Vec<[f64; 3]>,
        forces: Vec<[f64; 3]>,
        torques: Vec<[f64; 3]>,
    },
    /// Every bond ever formed, packed as [`BOND_STRIDE`]-byte points at the bond's middle.
    Bonds { time: f64, points: Vec<u8> },
    /// Named scalar values, one topic `/scalars/<name>` each.
    Scalars {
        time: f64,
        values: Vec<(String, f64)>,
    },
}

/// Bytes per bond in `/bonds`: x, y, z (the middle, f32, m), i, j (u32 ids), normal force,
/// shear force x, y, z (f32, N, on i; normal force positive in compression), twisting
/// moment, bending moment x, y, z (f32, N m), intact (u32: 1 or 0), broken time (f32, s;
/// -1 while intact).
pub const BOND_STRIDE: usize = 60;

/// Packs every particle of `sim` into a [`Record::Particles`].
pub fn particles(sim: &Simulation) -> Record {
    let p = &sim.particles;
    let mut points = Vec::with_capacity(p.len() * POINT_STRIDE);
    for k in 0..p.len() {
        let x = p.position[k];
        for v in [
            x.x as f32,
            x.y as f32,
            x.z as f32,
            p.radius[k] as f32,
            p.velocity[k].length() as f32,
        ] {
            points.extend_from_slice(&v.to_le_bytes());
        }
        points.extend_from_slice(&p.id[k].to_le_bytes());
        points.extend_from_slice(&(p.material[k] as u32).to_le_bytes());
    }
    Record::Particles {
        time: sim.time,
        count: p.len() as u32,
        points,
    }
}

/// Wall offsets, forces and torques of `sim`.
pub fn walls(sim: &Simulation) -> Record {
    Record::Walls {
        time: sim.time,
        offsets: sim.walls.iter().map(|w| w.offset.to_array()).collect(),
        forces: sim.walls.iter().map(|w| w.force.to_array()).collect(),
        torques: sim.walls.iter().map(|w| w.torque.to_array()).collect(),
    }
}

/// The standard scalar channels of `sim`, plus `extra` (an observable as it develops).
pub fn scalars(sim: &Simulation, extra: &[(String, f64)]) -> Record {
    let (pp, pw) = sim.contact_counts();
    let mut values = vec![
        ("kinetic_energy".to_string(), sim.particles.kinetic_energy()),
        ("particles".to_string(), sim.particles.len() as f64),
        ("contacts".to_string(), (pp + pw) as f64),
    ];
    values.extend(extra.iter().cloned());
    Record::Scalars {
        time: sim.time,
        values,
    }
}

/// Packs every bond of `sim` into a [`Record::Bonds`] (`None` without bonds).
pub fn bonds(sim: &Simulation) -> Option<Record> {
    let bonds = sim.bonds();
    if bonds.is_empty() {
        return None;
    }
    let p = &sim.particles;
    let max_id = p.id.iter().copied().max().unwrap_or(0) as usize;
    let mut index = vec![usize::MAX; max_id + 1];
    for (k, &id) in p.id.iter().enumerate() {
        index[id as usize] = k;
    }
    let mut points = Vec::with_capacity(bonds.len() * BOND_STRIDE);
    for b in &bonds {
        let at = |id: u32| index.get(id as usize).copied().filter(|&k| k != usize::MAX);
        let mid = match (at(b.i), at(b.j)) {
            (Some(a), Some(c)) => 0.5 * (p.position[a] + p.position[c]),
            _ => continue,
        };
        let l = &b.loads;
        for v in [mid.x, mid.y, mid.z] {
            points.extend_from_slice(&(v as f32).to_le_bytes());
        }
        points.extend_from_slice(&b.i.to_le_bytes());
        points.extend_from_slice(&b.j.to_le_bytes());
        for v in [
            l.normal_force,
            l.shear_force.x,
            l.shear_force.y,
            l.shear_force.z,
            l.normal_moment,
            l.shear_moment.x,
            l.shear_moment.y,
            l.shear_moment.z,
        ] {
            points.extend_from_slice(&(v as f32).to_le_bytes());
        }
        points.extend_from_slice(&(b.intact() as u32).to_le_bytes());
        points.extend_from_slice(&(b.broken_time.unwrap_or(-1.0) as f32).to_le_bytes());
    }
    Some(Record::Bonds {
        time: sim.time,
        points,
    })
}
