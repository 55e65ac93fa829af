//! Lanes: [`LANES`] contacts evaluated side by side, one value per lane.
//!
//! The pair phase evaluates touching contacts in batches of [`LANES`] through the laws' lane
//! forms (`NormalLaw::force_lanes`, ...). Each lane type is a plain array with element-wise
//! operations written as loops of fixed length: the compiler turns each loop into one or
//! two vector instructions (`vsqrtpd`, `vdivpd`, ... on 8 doubles with AVX-512), and the
//! pair phase is compiled once per instruction set and picks one at run time
//! (`sim/pair_forces/lanes.rs`).
//!
//! Every operation is the IEEE operation of the scalar code, lane by lane, in the same
//! order: a lane form written as its scalar form gives the scalar form's bits (the Rust
//! compiler never fuses a multiply and an add by itself). Comparisons give masks, and a
//! branch of the scalar code becomes a [`F::select`] of both sides; the side not taken
//! may compute a NaN in a lane, which the select drops.
//!
//! Why not a crate: `std::simd` is not stable, and the crates that wrap intrinsics (`wide`)
//! choose the instruction set when the crate is compiled, not when the program runs.

use std::ops::{Add, AddAssign, BitAnd, BitOr, Div, Mul, Neg, Not, Sub, SubAssign};

/// Contacts per batch: 8 doubles fill one AVX-512 register (two AVX2 ones).
pub const LANES: usize = 8;

/// One f64 per lane.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(transparent)]
pub struct F(pub [f64; LANES]);

/// One flag per lane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(transparent)]
pub struct M(pub [bool; LANES]);

/// A vector per lane (three lanes of components).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V {
    pub x: F,
    pub y: F,
    pub z: F,
}

// Macros rather than functions taking closures: a closure is a function of its own, and one
// the compiler leaves out of line is compiled without the caller's vector instructions.

/// `F` from an expression of lane `k`.
macro_rules! map {
    (|$k:ident| $e:expr) => {{
        let mut out = [0.0; LANES];
        for $k in 0..LANES {
            out[$k] = $e;
        }
        F(out)
    }};
}
pub(crate) use map;

/// `M` from a condition on lane `k`.
macro_rules! mask {
    (|$k:ident| $e:expr) => {{
        let mut out = [false; LANES];
        for $k in 0..LANES {
            out[$k] = $e;
        }
        M(out)
    }};
}

impl F {
    pub const ZERO: F = F([0.0; LANES]);

    #[inline(always)]
    pub fn splat(v: f64) -> F {
        F([v; LANES])
    }

    #[inline(always)]
    pub fn sqrt(self) -> F {
        map!(|k| self.0[k].sqrt())
    }

    #[inline(always)]
    pub fn abs(self) -> F {
        map!(|k| self.0[k].abs())
    }

    /// `if m { a } else { b }`, lane by lane.
    #[inline(always)]
    pub fn select(m: M, a: F, b: F) -> F {
        map!(|k| if m.0[k] { a.0[k] } else { b.0[k] })
    }

    #[inline(always)]
    pub fn lt(self, o: F) -> M {
        mask!(|k| self.0[k] < o.0[k])
    }

    #[inline(always)]
    pub fn le(self, o: F) -> M {
        mask!(|k| self.0[k] <= o.0[k])
    }

    #[inline(always)]
    pub fn gt(self, o: F) -> M {
        mask!(|k| self.0[k] > o.0[k])
    }

    #[inline(always)]
    pub fn eq(self, o: F) -> M {
        mask!(|k| self.0[k] == o.0[k])
    }

    /// Each lane is finite (not infinite, not NaN).
    #[inline(always)]
    pub fn is_finite(self) -> M {
        mask!(|k| self.0[k].is_finite())
    }
}

impl M {
    #[inline(always)]
    pub fn splat(v: bool) -> M {
        M([v; LANES])
    }

    /// Whether any lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.0.iter().fold(false, |a, &b| a | b)
    }
}

impl Not for M {
    type Output = M;
    #[inline(always)]
    fn not(self) -> M {
        mask!(|k| !self.0[k])
    }
}

impl BitAnd for M {
    type Output = M;
    #[inline(always)]
    fn bitand(self, o: M) -> M {
        mask!(|k| self.0[k] & o.0[k])
    }
}

impl BitOr for M {
    type Output = M;
    #[inline(always)]
    fn bitor(self, o: M) -> M {
        mask!(|k| self.0[k] | o.0[k])
    }
}

/// `F op F`, `F op f64` and `f64 op F`, each lane by lane with the scalar operation.
macro_rules! lane_op {
    ($tr:ident, $f:ident, $op:tt) => {
        impl $tr for F {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: F) -> F {
                map!(|k| self.0[k] $op o.0[k])
            }
        }
        impl $tr<f64> for F {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: f64) -> F {
                map!(|k| self.0[k] $op o)
            }
        }
        impl $tr<F> for f64 {
            type Output = F;
            #[inline(always)]
            fn $f(self, o: F) -> F {
                map!(|k| self $op o.0[k])
            }
        }
    };
}
lane_op!(Add, add, +);
lane_op!(Sub, sub, -);
lane_op!(Mul, mul, *);
lane_op!(Div, div, /);

impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        map!(|k| -self.0[k])
    }
}

impl AddAssign for F {
    #[inline(always)]
    fn add_assign(&mut self, o: F) {
        *self = *self + o;
    }
}

impl V {
    pub const ZERO: V = V {
        x: F::ZERO,
        y: F::ZERO,
        z: F::ZERO,
    };

    /// `DVec3::dot`: (x x') + (y y') + (z z').
    #[inline(always)]
    pub fn dot(self, o: V) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    #[inline(always)]
    pub fn length_squared(self) -> F {
        self.dot(self)
    }

    #[inline(always)]
    pub fn length(self) -> F {
        self.dot(self).sqrt()
    }

    /// `DVec3::cross`, term for term.
    #[inline(always)]
    pub fn cross(self, o: V) -> V {
        V {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    #[inline(always)]
    pub fn select(m: M, a: V, b: V) -> V {
        V {
            x: F::select(m, a.x, b.x),
            y: F::select(m, a.y, b.y),
            z: F::select(m, a.z, b.z),
        }
    }

    /// Lane `k` as a vector.
    #[inline(always)]
    pub fn lane(&self, k: usize) -> glam::DVec3 {
        glam::DVec3::new(self.x.0[k], self.y.0[k], self.z.0[k])
    }

    /// Sets lane `k`.
    #[inline(always)]
    pub fn set_lane(&mut self, k: usize, v: glam::DVec3) {
        self.x.0[k] = v.x;
        self.y.0[k] = v.y;
        self.z.0[k] = v.z;
    }
}

impl Add for V {
    type Output = V;
    #[inline(always)]
    fn add(self, o: V) -> V {
        V {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for V {
    type Output = V;
    #[inline(always)]
    fn sub(self, o: V) -> V {
        V {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Neg for V {
    type Output = V;
    #[inline(always)]
    fn neg(self) -> V {
        V {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl AddAssign for V {
    #[inline(always)]
    fn add_assign(&mut self, o: V) {
        *self = *self + o;
    }
}

impl SubAssign for V {
    #[inline(always)]
    fn sub_assign(&mut self, o: V) {
        *self = *self - o;
    }
}

/// `DVec3 * f64`: each component times the lane's value.
impl Mul<F> for V {
    type Output = V;
    #[inline(always)]
    fn mul(self, s: F) -> V {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// `DVec3 * f64`, one factor for every lane.
impl Mul<f64> for V {
    type Output = V;
    #[inline(always)]
    fn mul(self, s: f64) -> V {
        V {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// `f64 * DVec3`.
impl Mul<V> for F {
    type Output = V;
    #[inline(always)]
    fn mul(self, v: V) -> V {
        V {
            x: self * v.x,
            y: self * v.y,
            z: self * v.z,
        }
    }
}

/// `DVec3 / f64`: each component divided (glam divides, it does not multiply by 1/s).
impl Div<F> for V {
    type Output = V;
    #[inline(always)]
    fn div(self, s: F) -> V {
        V {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn lanes(f: impl Fn(usize) -> DVec3) -> V {
        let mut v = V::ZERO;
        for k in 0..LANES {
            v.set_lane(k, f(k));
        }
        v
    }

    #[test]
    fn vector_operations_give_glams_bits() {
        let a = |k: usize| DVec3::new(0.1 + k as f64, -1.0 / (k as f64 + 3.0), 7.0e-3 * k as f64);
        let b = |k: usize| DVec3::new(1.0 / 3.0, 2.5e-4 * k as f64, -(k as f64).sqrt());
        let (va, vb) = (lanes(a), lanes(b));
        let s = map!(|k| 0.3 + k as f64);
        for k in 0..LANES {
            assert_eq!(va.cross(vb).lane(k), a(k).cross(b(k)));
            assert_eq!(va.dot(vb).0[k].to_bits(), a(k).dot(b(k)).to_bits());
            assert_eq!(va.length().0[k].to_bits(), a(k).length().to_bits());
            assert_eq!((va / s).lane(k), a(k) / s.0[k]);
            assert_eq!((s * va).lane(k), s.0[k] * a(k));
            assert_eq!((va * s).lane(k), a(k) * s.0[k]);
        }
    }

    #[test]
    fn select_takes_each_lane_from_its_side() {
        let a = map!(|k| k as f64);
        let m = a.lt(F::splat(3.0));
        let s = F::select(m, a, F::splat(-1.0));
        assert_eq!(s.0, [0.0, 1.0, 2.0, -1.0, -1.0, -1.0, -1.0, -1.0]);
        assert!((!m).0[3]);
        assert_eq!((m & !m), M::splat(false));
    }
}
