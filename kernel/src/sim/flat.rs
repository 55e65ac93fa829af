//! Arrays of vectors as flat coordinates, [`LANES`] particles (24 coordinates, three lanes)
//! at a time, for the particle phase's element-wise loops. Each lane's coordinates repeat
//! the same axes group after group (lane 0: x y z x y z x y, lane 1: z x y ..., lane 2:
//! y z x ...), so one running value per lane position is one per axis; the few per-particle
//! values (kick factors, a mass) are spread over their particle's three coordinates, and a
//! per-particle sum (a squared length) gathers each axis into a lane first.

use crate::contact::lanes::{F, LANES, map};

/// Defines `$vis fn $name(args) -> $ret` running `$body(args)` compiled for the CPU's widest
/// instruction set (AVX-512, AVX2 or the baseline), picked at run time, as the pair phase
/// picks its lanes: the flat loops become vector instructions of that width. `$body` must be
/// `#[inline(always)]` so that each copy compiles it with its own features.
macro_rules! on_widest {
    ($(#[$doc:meta])* $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty => $body:ident) => {
        $(#[$doc])*
        #[inline]
        $vis fn $name($($arg: $ty),*) -> $ret {
            #[cfg(target_arch = "x86_64")]
            {
                #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx2,avx")]
                unsafe fn avx512($($arg: $ty),*) -> $ret {
                    $body($($arg),*)
                }
                #[target_feature(enable = "avx2,avx")]
                unsafe fn avx2($($arg: $ty),*) -> $ret {
                    $body($($arg),*)
                }
                if std::arch::is_x86_feature_detected!("avx512f") {
                    // SAFETY: the CPU has the features the function is compiled for.
                    return unsafe { avx512($($arg),*) };
                }
                if std::arch::is_x86_feature_detected!("avx2") {
                    // SAFETY: as above.
                    return unsafe { avx2($($arg),*) };
                }
            }
            $body($($arg),*)
        }
    };
}
pub(super) use on_widest;

/// Particles per group.
pub(super) const GROUP: usize = LANES;
/// Coordinates per group.
pub(super) const FLAT: usize = 3 * GROUP;

/// Coordinates `at..at + FLAT` of a flat slice as three lanes.
#[inline(always)]
pub(super) fn load3(s: &[f64], at: usize) -> [F; 3] {
    let s: &[f64; FLAT] = s[at..at + FLAT].try_into().unwrap();
    std::array::from_fn(|r| map!(|k| s[r * LANES + k]))
}

#[inline(always)]
pub(super) fn store3(s: &mut [f64], at: usize, v: [F; 3]) {
    let s: &mut [f64; FLAT] = (&mut s[at..at + FLAT]).try_into().unwrap();
    for r in 0..3 {
        s[r * LANES..(r + 1) * LANES].copy_from_slice(&v[r].0);
    }
}

/// Each of a group's particles' values spread over its three coordinates: lane r holds
/// coordinates `8 r..8 r + 8`, which belong to particles `(8 r + k) / 3`.
#[inline(always)]
pub(super) fn spread3(p: F) -> [F; 3] {
    std::array::from_fn(|r| map!(|k| p.0[(r * LANES + k) / 3]))
}

/// A vector repeated over a group: lane r's coordinate k is axis `(8 r + k) % 3`.
#[inline(always)]
pub(super) fn repeat3(v: [f64; 3]) -> [F; 3] {
    std::array::from_fn(|r| map!(|k| v[(r * LANES + k) % 3]))
}

/// Axis `c` (0: x, 1: y, 2: z) of each particle of a group, from its three lanes.
#[inline(always)]
pub(super) fn axis(v: &[F; 3], c: usize) -> F {
    map!(|k| {
        let at = 3 * k + c;
        v[at / LANES].0[at % LANES]
    })
}

/// Each particle's squared length, summed as `DVec3::length_squared` sums: (x x + y y) + z z.
#[inline(always)]
pub(super) fn length_squared(v: &[F; 3]) -> F {
    let sq: [F; 3] = std::array::from_fn(|r| v[r] * v[r]);
    axis(&sq, 0) + axis(&sq, 1) + axis(&sq, 2)
}
