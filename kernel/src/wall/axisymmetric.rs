//! Surfaces of revolution with a straight profile: disc, cylinder, cone frustum.
//!
//! The profile is the segment from (h0, r0) to (h1, r1) in (axial, radial) coordinates about
//! an axis through `origin` along `axis`. The closest surface point to a sphere centre lies
//! in the centre's own azimuthal half-plane, so it is the closest point of the 2-D segment.
//! Two-sided: a cylinder confines particles inside it and deflects those outside.

use super::{Hit, Shape, closest_on_segment};
use glam::{DVec2, DVec3};

#[derive(Debug, Clone)]
pub struct Axisymmetric {
    pub origin: DVec3,
    /// Unit axis.
    pub axis: DVec3,
    /// Profile end points (axial position, radius), m.
    pub p0: DVec2,
    pub p1: DVec2,
    /// A fixed unit vector normal to the axis, used for centres exactly on the axis.
    perp: DVec3,
}

impl Axisymmetric {
    fn new(origin: DVec3, axis: DVec3, p0: DVec2, p1: DVec2) -> Option<Axisymmetric> {
        let axis = axis.try_normalize()?;
        if p0.y < 0.0 || p1.y < 0.0 || p0 == p1 {
            return None;
        }
        Some(Axisymmetric {
            origin,
            axis,
            p0,
            p1,
            perp: axis.any_orthonormal_vector(),
        })
    }

    /// Flat disc of `radius` centred at `centre`, normal to `axis`.
    pub fn disc(centre: DVec3, axis: DVec3, radius: f64) -> Option<Self> {
        Self::annulus(centre, axis, 0.0, radius)
    }

    /// Flat ring between radii `inner` and `outer` (m) centred at `centre`, normal to
    /// `axis`: a flange, or a disc with a hole.
    pub fn annulus(centre: DVec3, axis: DVec3, inner: f64, outer: f64) -> Option<Self> {
        if !(inner >= 0.0 && outer > inner) {
            return None;
        }
        Self::new(centre, axis, DVec2::new(0.0, inner), DVec2::new(0.0, outer))
    }

    /// Open cylinder (no caps) of `radius` from axial position 0 to `length` above `base`.
    pub fn cylinder(base: DVec3, axis: DVec3, radius: f64, length: f64) -> Option<Self> {
        if !(length > 0.0 && radius > 0.0) {
            return None;
        }
        Self::new(
            base,
            axis,
            DVec2::new(0.0, radius),
            DVec2::new(length, radius),
        )
    }

    /// Open cone frustum: radius `r0` at `base`, `r1` at `length` along `axis` (a funnel
    /// with its outlet at the base has r0 < r1).
    pub fn frustum(base: DVec3, axis: DVec3, r0: f64, r1: f64, length: f64) -> Option<Self> {
        if !(length > 0.0) {
            return None;
        }
        Self::new(base, axis, DVec2::new(0.0, r0), DVec2::new(length, r1))
    }
}

impl Shape for Axisymmetric {
    fn hits(&self, x: DVec3, range: f64, out: &mut Vec<Hit>) {
        let h = self.hit(0, x);
        if h.distance < range {
            out.push(h);
        }
    }

    fn hit(&self, _feature: u32, x: DVec3) -> Hit {
        let rel = x - self.origin;
        let h = rel.dot(self.axis);
        let radial = rel - self.axis * h;
        let rho = radial.length();
        let e = if rho > 0.0 { radial / rho } else { self.perp };
        let (q2, _) = closest_on_segment(
            self.p0.extend(0.0),
            self.p1.extend(0.0),
            DVec3::new(h, rho, 0.0),
        );
        let point = self.origin + self.axis * q2.x + e * q2.y;
        let d = x - point;
        let dist = d.length();
        let normal = if dist > 0.0 {
            d / dist
        } else {
            // Centre on the surface: take the profile's normal in this half-plane.
            let t = (self.p1 - self.p0).normalize();
            (self.axis * -t.y + e * t.x).normalize()
        };
        Hit {
            feature: 0,
            point,
            normal,
            distance: dist,
        }
    }

    fn reference_point(&self) -> DVec3 {
        self.origin
    }
}
