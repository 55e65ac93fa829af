//! Struct-of-arrays particle storage.

use glam::DVec3;
use std::f64::consts::PI;

/// Spheres as parallel arrays (index = particle). Mass and inertia follow from radius and
/// the material density: m = 4/3 pi r^3 rho, I = 2/5 m r^2.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    pub position: Vec<DVec3>,
    pub velocity: Vec<DVec3>,
    pub angular_velocity: Vec<DVec3>,
    pub force: Vec<DVec3>,
    pub torque: Vec<DVec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inertia: Vec<f64>,
    /// Index into the model's material list.
    pub material: Vec<u16>,
    /// Stable identifier (insertion order), kept for output.
    pub id: Vec<u32>,
}

impl Particles {
    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Appends a sphere of radius `radius` (m) and density `density` (kg/m^3).
    pub fn push(
        &mut self,
        position: DVec3,
        velocity: DVec3,
        radius: f64,
        density: f64,
        material: u16,
    ) {
        let mass = 4.0 / 3.0 * PI * radius.powi(3) * density;
        self.id.push(self.position.len() as u32);
        self.position.push(position);
        self.velocity.push(velocity);
        self.angular_velocity.push(DVec3::ZERO);
        self.force.push(DVec3::ZERO);
        self.torque.push(DVec3::ZERO);
        self.radius.push(radius);
        self.mass.push(mass);
        self.inertia.push(0.4 * mass * radius * radius);
        self.material.push(material);
    }

    /// Reorders every array so that new particle k is old particle `old_of_new[k]`.
    pub fn permute(&mut self, old_of_new: &[u32]) {
        fn apply<T: Copy>(v: &mut Vec<T>, order: &[u32]) {
            *v = order.iter().map(|&o| v[o as usize]).collect();
        }
        apply(&mut self.position, old_of_new);
        apply(&mut self.velocity, old_of_new);
        apply(&mut self.angular_velocity, old_of_new);
        apply(&mut self.force, old_of_new);
        apply(&mut self.torque, old_of_new);
        apply(&mut self.radius, old_of_new);
        apply(&mut self.mass, old_of_new);
        apply(&mut self.inertia, old_of_new);
        apply(&mut self.material, old_of_new);
        apply(&mut self.id, old_of_new);
    }

    /// Translational plus rotational kinetic energy, J.
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for i in 0..self.len() {
            e += 0.5 * self.mass[i] * self.velocity[i].length_squared()
                + 0.5 * self.inertia[i] * self.angular_velocity[i].length_squared();
        }
        e
    }

    /// Bytes of heap memory held (capacity, not length).
    pub fn heap_bytes(&self) -> usize {
        let v3 = std::mem::size_of::<DVec3>();
        5 * self.position.capacity() * v3
            + 3 * self.radius.capacity() * 8
            + self.material.capacity() * 2
            + self.id.capacity() * 4
    }
}
