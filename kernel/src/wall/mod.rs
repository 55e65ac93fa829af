//! Walls: rigid geometry that particles touch through the same contact laws, with the
//! wall's material in the pair table (a wall has infinite radius, mass and inertia).
//!
//! Shapes: [`plane::Plane`] (infinite, one-sided), [`axisymmetric::Axisymmetric`] (disc,
//! cylinder, cone frustum: a straight profile revolved about an axis, two-sided, so one
//! cylinder serves as a mould from inside and as a post from outside) and
//! [`mesh::Mesh`] (triangles from an STL file). Each wall is static, moves at a prescribed
//! velocity or is servo-driven to hold a force ([`Motion`]); the force and torque the
//! particles exert on every wall are summed every step.

pub mod axisymmetric;
pub mod mesh;
pub mod plane;

use glam::DVec3;
use std::fmt::Debug;

/// The surface point of one feature closest to a sphere centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Which part of the shape (triangle index for meshes, 0 otherwise).
    pub feature: u32,
    /// Closest surface point, shape frame.
    pub point: DVec3,
    /// Unit normal pointing from the surface toward the sphere centre.
    pub normal: DVec3,
    /// Signed distance from the surface to the centre along `normal`, m.
    pub distance: f64,
}

/// A rigid surface in its own frame (the wall's translation is applied outside).
pub trait Shape: Send + Sync + Debug {
    /// Pushes every feature whose surface lies within `range` of `x`, in ascending feature.
    fn hits(&self, x: DVec3, range: f64, out: &mut Vec<Hit>);
    /// The closest point of feature `feature` to `x`.
    fn hit(&self, feature: u32, x: DVec3) -> Hit;
    /// Distance from `p` to feature `feature` (used to drop duplicate mesh contacts).
    fn feature_distance(&self, feature: u32, p: DVec3) -> f64 {
        (self.hit(feature, p).point - p).length()
    }
    /// The point torques are taken about, shape frame.
    fn reference_point(&self) -> DVec3;
}

/// How a wall moves.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    Fixed,
    /// Constant translation velocity, m/s.
    Velocity(DVec3),
    /// Moves along `axis` (unit) to make the force the particles exert against that motion
    /// equal `target_force` (N): v = clamp(gain (target - F_resist), -max_speed, max_speed)
    /// with F_resist = -F_wall . axis, from the previous step's force.
    Servo {
        axis: DVec3,
        target_force: f64,
        gain: f64,
        max_speed: f64,
    },
    /// A servo along `axis` as [`Motion::Servo`], carried along at `velocity` (m/s, normal
    /// to the axis): the lid of a shear box that follows the upper ring.
    ServoCarried {
        axis: DVec3,
        target_force: f64,
        gain: f64,
        max_speed: f64,
        velocity: DVec3,
    },
}

/// A wall: a shape, its material index, its motion and its current state.
#[derive(Debug)]
pub struct Wall {
    pub name: String,
    pub shape: Box<dyn Shape>,
    pub material: u16,
    pub motion: Motion,
    /// Translation from the shape frame to the world, m.
    pub offset: DVec3,
    /// Current velocity, m/s.
    pub velocity: DVec3,
    /// Force and torque (about the reference point) exerted by the particles on the wall
    /// in the last step, N and N m.
    pub force: DVec3,
    pub torque: DVec3,
    /// Time integral of `force` since the start, N s. The force on a wall swings from step
    /// to step as contacts come and go; the change of impulse over an interval divided by
    /// its length is the interval's mean force, which a sample every few thousand steps is not.
    pub impulse: DVec3,
    /// An inactive wall touches nothing (see `Simulation::set_wall_active`).
    pub active: bool,
}

impl Wall {
    pub fn new(name: &str, shape: Box<dyn Shape>, material: u16, motion: Motion) -> Wall {
        let velocity = match motion {
            Motion::Velocity(v) => v,
            _ => DVec3::ZERO,
        };
        Wall {
            name: name.into(),
            shape,
            material,
            motion,
            offset: DVec3::ZERO,
            velocity,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            impulse: DVec3::ZERO,
            active: true,
        }
    }

    /// Sets the velocity for the coming step from the motion rule and the last force.
    pub fn update_velocity(&mut self) {
        self.velocity = match self.motion {
            Motion::Fixed => DVec3::ZERO,
            Motion::Velocity(v) => v,
            Motion::Servo {
                axis,
                target_force,
                gain,
                max_speed,
            } => {
                let resist = -self.force.dot(axis);
                axis * (gain * (target_force - resist)).clamp(-max_speed, max_speed)
            }
            Motion::ServoCarried {
                axis,
                target_force,
                gain,
                max_speed,
                velocity,
            } => {
                let resist = -self.force.dot(axis);
                velocity + axis * (gain * (target_force - resist)).clamp(-max_speed, max_speed)
            }
        };
    }

    /// The largest speed this wall can have, m/s.
    pub fn max_speed(&self) -> f64 {
        match self.motion {
            Motion::Fixed => 0.0,
            Motion::Velocity(v) => v.length(),
            Motion::Servo { max_speed, .. } => max_speed,
            Motion::ServoCarried {
                max_speed,
                velocity,
                ..
            } => max_speed + velocity.length(),
        }
    }
}

/// Closest point to `p` on the segment a-b (any dimension via DVec3), and its parameter t.
pub(crate) fn closest_on_segment(a: DVec3, b: DVec3, p: DVec3) -> (DVec3, f64) {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t, t)
}
