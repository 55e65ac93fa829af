//! A cone fitted to the whole upper surface of a heap: the cross-check of the photograph
//! method, which sees only two outlines.
//!
//! The horizontal plane is cut into square cells of side w (about one particle diameter);
//! each cell contributes its highest particle top, at that particle's radial distance
//! rho = sqrt((x - x_c)^2 + (y - y_c)^2) from the tray axis. A right circular cone with its
//! apex up on that axis is
//!
//! ```text
//! h(rho) = h_0 - tan(theta) rho          (h: height above the tray top, m; theta: slope angle)
//! ```
//!
//! so a least-squares line through the (rho, h) points in the same height band as the
//! silhouette fits gives theta = arctan(-slope) and the apex height h_0. A cell the surface
//! layer happens to miss offers a particle of the layer below, a diameter or so lower; such
//! points would pull the line down and flatten it (by 2 to 3 degrees on a loosely covered
//! synthetic cone), so points more than `trim` (half a diameter) below the fitted cone are
//! dropped and the line fitted again, until none is dropped. The cone is centred on
//! the tray axis, not on the heap's own apex: a heap poured off-centre shows up as a low R^2
//! and an angle that disagrees with the silhouettes, which is what a cross-check is for.

use super::error::ReduceError;
use super::line_fit::{LineFit, fit_line};
use serde::{Deserialize, Serialize};

/// The fitted cone h = apex_height_m - tan(angle_deg) rho.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConeFit {
    /// Slope angle of the cone's side, degrees (positive for a heap, apex up).
    pub angle_deg: f64,
    /// Height of the fitted apex above the tray top, m.
    pub apex_height_m: f64,
    pub r_squared: f64,
    /// Surface cells fitted: their top lies in the band and not below the cone.
    pub points: usize,
}

/// Fits the cone to particles at `(u, v)` relative to the axis with tops `h` above the tray
/// top, using cells of side `cell` over the square of half-width `half`, only cell tops with
/// `band.0 <= h <= band.1`, and dropping points more than `trim` below the fitted cone.
pub fn cone_fit(
    u: &[f64],
    v: &[f64],
    h: &[f64],
    cell: f64,
    half: f64,
    band: (f64, f64),
    trim: f64,
) -> Result<ConeFit, ReduceError> {
    let n = ((2.0 * half) / cell).ceil().max(1.0) as usize;
    let mut best: Vec<Option<(f64, f64)>> = vec![None; n * n];
    let index = |c: f64| (((c + half) / cell).floor().max(0.0) as usize).min(n - 1);
    for ((&ui, &vi), &hi) in u.iter().zip(v).zip(h) {
        let k = index(ui) * n + index(vi);
        match best[k] {
            Some((_, t)) if t >= hi => {}
            _ => best[k] = Some((ui.hypot(vi), hi)),
        }
    }
    let mut points: Vec<(f64, f64)> = best
        .into_iter()
        .flatten()
        .filter(|&(_, t)| (band.0..=band.1).contains(&t))
        .collect();
    let mut fit = fit_enough(&points)?;
    // A cell with no particle on the surface offers one from the layer below; drop points more
    // than `trim` below the fitted cone and fit again, until no point is dropped.
    for _ in 0..MAX_TRIMS {
        let before = points.len();
        points.retain(|&(rho, t)| t - fit.at(rho) >= -trim);
        if points.len() == before {
            break;
        }
        fit = fit_enough(&points)?;
    }
    Ok(ConeFit {
        angle_deg: (-fit.slope).atan().to_degrees(),
        apex_height_m: fit.intercept,
        r_squared: fit.r_squared,
        points: fit.points,
    })
}

/// Most rounds of dropping points below the cone.
const MAX_TRIMS: usize = 10;

fn fit_enough(points: &[(f64, f64)]) -> Result<LineFit, ReduceError> {
    if points.len() < 3 {
        return Err(ReduceError::TooFewPoints {
            what: "cone fit over the heap's surface cells in the height band".to_string(),
            have: points.len(),
            need: 3,
        });
    }
    fit_line(points, "cone fit")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_cone_surface_points() {
        // Points on h = 10 - tan(30 deg) rho on a polar grid: one per cell, all on the cone.
        let t = 30f64.to_radians().tan();
        let (mut u, mut v, mut h) = (vec![], vec![], vec![]);
        for i in -10..=10 {
            for j in -10..=10 {
                let (x, y) = (i as f64 + 0.5, j as f64 + 0.5);
                u.push(x);
                v.push(y);
                h.push(10.0 - t * x.hypot(y));
            }
        }
        let c = cone_fit(&u, &v, &h, 1.0, 11.0, (1.5, 8.5), 0.5).unwrap();
        assert!((c.angle_deg - 30.0).abs() < 1e-9, "{c:?}");
        assert!((c.apex_height_m - 10.0).abs() < 1e-9);
    }
}
