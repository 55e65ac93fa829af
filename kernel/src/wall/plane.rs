//! Infinite plane, one-sided: particles live on the side its normal points to.

use super::{Hit, Shape};
use glam::DVec3;

#[derive(Debug, Clone)]
pub struct Plane {
    pub point: DVec3,
    /// Unit normal pointing into the particle side.
    pub normal: DVec3,
}

impl Plane {
    /// `normal` need not be unit length; it must not be zero.
    pub fn new(point: DVec3, normal: DVec3) -> Option<Plane> {
        let n = normal.try_normalize()?;
        Some(Plane { point, normal: n })
    }
}

impl Shape for Plane {
    fn hits(&self, x: DVec3, range: f64, out: &mut Vec<Hit>) {
        let d = (x - self.point).dot(self.normal);
        // A centre behind the plane by more than `range` has tunnelled through; ignore it.
        if d < range && d > -range {
            out.push(self.hit(0, x));
        }
    }

    fn hit(&self, _feature: u32, x: DVec3) -> Hit {
        let d = (x - self.point).dot(self.normal);
        Hit {
            feature: 0,
            point: x - self.normal * d,
            normal: self.normal,
            distance: d,
        }
    }

    fn reference_point(&self) -> DVec3 {
        self.point
    }
}
