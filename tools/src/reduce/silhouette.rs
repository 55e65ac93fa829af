//! The outline of a heap as a photograph taken from the side sees it.
//!
//! A photograph of the heap is (close to) an orthographic projection onto a vertical plane
//! through its axis: every particle projects to a disc of its radius, and the heap's outline
//! is the upper edge of all the discs. The horizontal coordinate u (x or y relative to the
//! tray axis) is cut into bins of width w (about one particle diameter); each bin gives one
//! point. Two ways of taking it are offered ([`SilhouetteMethod`]):
//!
//! - [`SilhouetteMethod::Envelope`] (default): the outline itself at the bin centre u_k, the highest
//!   point of any particle's disc above it,
//!
//!   ```text
//!   E(u_k) = max over particles with |u_k - u_i| <= r_i of  z_i + sqrt(r_i^2 - (u_k - u_i)^2)
//!   ```
//!
//!   which is what the photograph shows at u_k. Bins no disc covers give no point.
//!
//! - [`SilhouetteMethod::HighestTop`]: the particle with the highest top z + r in the bin, placed at
//!   its own u. Simpler, but biased: a particle off the plane of the photograph (azimuth a
//!   from it) sits at u = rho cos(a) < rho with the height of radius rho, so it plots inside
//!   the outline, and more so near the apex where rho is small; the slope comes out too
//!   steep (see the synthetic-cone tests).

use serde::{Deserialize, Serialize};

/// The vertical plane a silhouette is projected onto.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    /// The x-z plane: horizontal coordinate x.
    Xz,
    /// The y-z plane: horizontal coordinate y (a second photograph at right angles).
    Yz,
    /// The vertical plane through the tray axis at this azimuth from the x axis, degrees:
    /// horizontal coordinate x cos(a) + y sin(a) (0 is the x-z view, 90 the y-z view).
    Azimuth(f64),
}

impl View {
    /// Name of the horizontal axis ("x", "y" or "azimuth A").
    pub fn axis(self) -> String {
        match self {
            View::Xz => "x".to_string(),
            View::Yz => "y".to_string(),
            View::Azimuth(a) => format!("azimuth {a:.1} deg"),
        }
    }

    /// The unit vector of the view's horizontal coordinate in the x-y plane.
    pub fn direction(self) -> (f64, f64) {
        match self {
            View::Xz => (1.0, 0.0),
            View::Yz => (0.0, 1.0),
            View::Azimuth(a) => {
                let r = a.to_radians();
                (r.cos(), r.sin())
            }
        }
    }

    /// `n` photographs evenly around the heap: azimuths k 180/n degrees, k = 0..n (a
    /// photograph and the one from the opposite side see mirror images of one outline). Two
    /// are the x-z and y-z views.
    pub fn around(n: usize) -> Vec<View> {
        match n {
            1 => vec![View::Xz],
            2 => vec![View::Xz, View::Yz],
            _ => (0..n)
                .map(|k| View::Azimuth(180.0 * k as f64 / n as f64))
                .collect(),
        }
    }
}

/// How a bin's silhouette point is taken (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SilhouetteMethod {
    /// Height of the projected outline at the bin centre.
    #[default]
    Envelope,
    /// Highest particle top in the bin, at that particle's position.
    HighestTop,
}

/// The silhouette of particles at horizontal coordinate `u` with centre height `z` and
/// radius `r` (same units), in bins of `width` over `[lo, hi)`: one `(u, height)` point per
/// bin that has one, in increasing u.
pub fn silhouette(
    method: SilhouetteMethod,
    u: &[f64],
    z: &[f64],
    r: &[f64],
    width: f64,
    lo: f64,
    hi: f64,
) -> Vec<(f64, f64)> {
    assert!(
        width > 0.0 && hi > lo,
        "silhouette needs width > 0 and hi > lo"
    );
    let bins = ((hi - lo) / width).ceil() as usize;
    let bin = |x: f64| ((x - lo) / width).floor();
    match method {
        SilhouetteMethod::HighestTop => {
            let mut best: Vec<Option<(f64, f64)>> = vec![None; bins];
            for ((&ui, &zi), &ri) in u.iter().zip(z).zip(r) {
                let k = bin(ui);
                if !(0.0..bins as f64).contains(&k) {
                    continue;
                }
                let top = zi + ri;
                match best[k as usize] {
                    Some((_, t)) if t >= top => {}
                    _ => best[k as usize] = Some((ui, top)),
                }
            }
            best.into_iter().flatten().collect()
        }
        SilhouetteMethod::Envelope => {
            // Each particle raises the outline at every bin centre its disc covers.
            let mut best: Vec<Option<f64>> = vec![None; bins];
            for ((&ui, &zi), &ri) in u.iter().zip(z).zip(r) {
                // Bins whose centre may lie within the disc (the test below decides).
                let first = bin(ui - ri - 0.5 * width).max(0.0);
                let last = bin(ui + ri).min(bins as f64 - 1.0);
                let mut k = first;
                while k <= last {
                    let du = lo + (k + 0.5) * width - ui;
                    if du.abs() <= ri {
                        let e = zi + (ri * ri - du * du).sqrt();
                        let slot = &mut best[k as usize];
                        if slot.is_none_or(|b| e > b) {
                            *slot = Some(e);
                        }
                    }
                    k += 1.0;
                }
            }
            best.into_iter()
                .enumerate()
                .filter_map(|(k, e)| e.map(|e| (lo + (k as f64 + 0.5) * width, e)))
                .collect()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn highest_top_keeps_the_highest_top_per_bin_at_its_own_position() {
        let u = [0.1, 0.4, 1.2, 1.9, 5.0];
        let z = [0.9, 2.9, 1.9, 2.4, 8.9];
        let r = [0.1; 5];
        // Bins of width 1 over [0, 3): bin 0 -> (0.4, 3), bin 1 -> (1.9, 2.5); 5.0 is outside.
        let s = silhouette(SilhouetteMethod::HighestTop, &u, &z, &r, 1.0, 0.0, 3.0);
        assert_eq!(s.len(), 2);
        assert!((s[0].0 - 0.4).abs() < 1e-12 && (s[0].1 - 3.0).abs() < 1e-12);
        assert!((s[1].0 - 1.9).abs() < 1e-12 && (s[1].1 - 2.5).abs() < 1e-12);
    }

    #[test]
    fn envelope_is_the_upper_edge_of_the_discs_at_bin_centres() {
        // One disc of radius 1 at u = 0, z = 0 over bins of width 0.5 on [-1, 1): centres
        // -0.75, -0.25, 0.25, 0.75 -> heights sqrt(1 - u^2).
        let s = silhouette(
            SilhouetteMethod::Envelope,
            &[0.0],
            &[0.0],
            &[1.0],
            0.5,
            -1.0,
            1.0,
        );
        let expected = [-0.75f64, -0.25, 0.25, 0.75].map(|u| (u, (1.0 - u * u).sqrt()));
        assert_eq!(s.len(), 4);
        for (p, e) in s.iter().zip(expected) {
            assert!(
                (p.0 - e.0).abs() < 1e-12 && (p.1 - e.1).abs() < 1e-12,
                "{p:?} {e:?}"
            );
        }
        // A second, higher disc at u = 0.75 covers the centres 0.25 and 0.75.
        let s = silhouette(
            SilhouetteMethod::Envelope,
            &[0.0, 0.75],
            &[0.0, 1.0],
            &[1.0, 0.5],
            0.5,
            -1.0,
            1.0,
        );
        assert!((s[2].1 - 1.0).abs() < 1e-12);
        assert!((s[3].1 - 1.5).abs() < 1e-12);
    }
}
