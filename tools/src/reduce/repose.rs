//! Angle of repose of a heap on the tray, measured the way the reference study measures it
//! from a photograph (Li et al. 2022; docs/experiments.md, "Angle of repose").
//!
//! The study photographs the heap, extracts its boundary, takes one half, fits a straight
//! line to it and reports theta = arctan(slope). Here, from the final particle frame:
//!
//! 1. **Heap**: the particles whose centre is within the tray radius R of the tray axis and
//!    above the tray top, rho <= R and z > z_tray. Particles that overflowed the tray lie
//!    below its top (the ring knife stands 20 mm high) and are left out.
//! 2. **Silhouette** ([`silhouette`](super::silhouette)) in the x-z plane and, as a second
//!    photograph at right angles, the y-z plane: the height of the outline of the projected
//!    particles, sampled every quarter of a particle diameter (the heap's median diameter;
//!    [`ENVELOPE_BINS_PER_DIAMETER`] says why a quarter). Optionally, as first specified,
//!    the highest particle top per bin of one diameter instead
//!    ([`SilhouetteMethod::HighestTop`]).
//! 3. **Halves**: split at the apex, the highest silhouette point; the left half is the
//!    points before it, the right half the points after it.
//! 4. **Band**: only points with `band.0 * H <= h <= band.1 * H` are fitted, H the heap
//!    height (highest particle top above the tray). The default band is **15 % to 85 %**: a
//!    person fitting a line to a photograph leaves out the rounded top and the foot, where
//!    the outline bends away from the straight flank (the apex is rounded over a few
//!    particles, and at the foot grains roll out onto the tray and over its rim).
//! 5. **Fit**: a least-squares line h = a + b u per half, theta = arctan(|b|).
//!
//! Checked on synthetic cones of 2 mm spheres on the 61.8 mm tray (tests/reduce/cone.rs,
//! 20 seeds each, `photograph_method_accuracy_over_seeds`): with a surface layer of touching spheres the method reads
//! 0.10 degrees low at 30 and 40 degrees (spread 0.02, worst 0.15); on a much rougher,
//! randomly laid surface (55 % covered) the outline itself is flatter than the cone the
//! spheres touch and it reads about 0.3 degrees low (spread 0.09). The cone fit finds the
//! cone to within 0.05 degrees on both.
//!
//! `repose_angle_deg` is the mean of the halves of all views (four halves with the default
//! two views: one photograph gives two halves, the second adds two independent ones). Each
//! half, its R^2 and a cone fitted to the whole upper surface
//! ([`cone_fit`](super::cone_fit), the cross-check) are reported beside it.

use super::cone_fit::{ConeFit, cone_fit};
use super::error::ReduceError;
use super::line_fit::fit_line;
use super::read::{Run, RunSource};
use super::silhouette::{SilhouetteMethod, View, silhouette};
use crate::reduce::cloud::ParticleCloud;
use serde::{Deserialize, Serialize};

/// `tilth.experiment` type of a repose run.
pub const REPOSE: &str = "repose";

/// Outline samples per particle diameter with [`SilhouetteMethod::Envelope`]. The outline of
/// one-size spheres is scalloped with a period of about one diameter; sampled once per
/// diameter, the samples beat against the scallops and the fitted slope swings by tenths of
/// a degree with the heap's phase (synthetic cones: -0.4 to +0.15 degrees), while four
/// samples per diameter trace the outline as a photograph does (errors within 0.15 degrees).
pub const ENVELOPE_BINS_PER_DIAMETER: f64 = 4.0;

/// Fewest silhouette points a half may be fitted with.
const MIN_HALF_POINTS: usize = 3;

/// The tray (ring knife) the heap stands on, m, from `tilth.experiment`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tray {
    pub radius_m: f64,
    pub top_z_m: f64,
    pub centre_x_m: f64,
    pub centre_y_m: f64,
    /// Particles higher than this above the tray top are not part of the heap (those still
    /// in the funnel), m; from `drop_height_m` when the run has one.
    #[serde(default = "unbounded")]
    pub ceiling_m: f64,
}

fn unbounded() -> f64 {
    f64::INFINITY
}

impl Tray {
    /// Reads `tray_radius_m`, `tray_top_z_m`, `tray_centre_x_m`, `tray_centre_y_m`.
    pub fn from_run(run: &Run) -> Result<Tray, ReduceError> {
        Ok(Tray {
            radius_m: run.experiment_number("tray_radius_m")?,
            top_z_m: run.experiment_number("tray_top_z_m")?,
            centre_x_m: run.experiment_number("tray_centre_x_m")?,
            centre_y_m: run.experiment_number("tray_centre_y_m")?,
            ceiling_m: run
                .experiment_number("drop_height_m")
                .unwrap_or(f64::INFINITY),
        })
    }
}

/// How to measure.
#[derive(Debug, Clone, PartialEq)]
pub struct ReposeOptions {
    /// Height band fitted, as fractions of the heap height (default 0.15 to 0.85).
    pub band: (f64, f64),
    /// Silhouette bin width, m; `None`: a quarter of the heap's median particle diameter for
    /// [`SilhouetteMethod::Envelope`] (outline samples), one diameter for
    /// [`SilhouetteMethod::HighestTop`].
    pub bin_width_m: Option<f64>,
    /// The photographs taken (default both x-z and y-z).
    pub views: Vec<View>,
    /// How each bin's silhouette point is taken (default the outline at the bin centre).
    pub method: SilhouetteMethod,
}

impl Default for ReposeOptions {
    fn default() -> Self {
        ReposeOptions {
            band: (0.15, 0.85),
            bin_width_m: None,
            views: vec![View::Xz, View::Yz],
            method: SilhouetteMethod::Envelope,
        }
    }
}

impl ReposeOptions {
    /// The defaults, with the photographs the run asks for (`photographs` in its
    /// `tilth.experiment` record; two when it has none).
    pub fn of_run(run: &Run) -> ReposeOptions {
        let n = run
            .experiment_number("photographs")
            .ok()
            .filter(|n| (1.0..=180.0).contains(n))
            .map_or(2, |n| n as usize);
        ReposeOptions {
            views: View::around(n),
            ..ReposeOptions::default()
        }
    }
}

/// The line fitted to one half of a silhouette: h = intercept_m + slope u (h above the tray
/// top, u horizontal from the tray axis, both m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HalfFit {
    /// arctan(|slope|), degrees.
    pub angle_deg: f64,
    pub slope: f64,
    pub intercept_m: f64,
    pub r_squared: f64,
    /// Silhouette points in the band.
    pub points: usize,
}

/// One photograph: its silhouette, apex and two halves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ViewFit {
    pub view: View,
    /// Horizontal position of the apex relative to the tray axis, m.
    pub apex_m: f64,
    /// Side with smaller u (towards -x or -y).
    pub left: HalfFit,
    pub right: HalfFit,
    /// Mean of the two halves, degrees.
    pub mean_deg: f64,
    /// Silhouette points (u, h), m: u from the tray axis, h above the tray top.
    pub silhouette_m: Vec<(f64, f64)>,
}

/// The measurement, independent of the file it came from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReposeAnalysis {
    /// Mean of the halves of all views, degrees: the angle of repose.
    pub repose_angle_deg: f64,
    pub views: Vec<ViewFit>,
    /// Cone fitted to the whole upper surface (cross-check).
    pub cone: ConeFit,
    /// Particles on the tray.
    pub heap_particles: usize,
    /// Highest particle top above the tray top, m.
    pub heap_height_m: f64,
    pub bin_width_m: f64,
    pub silhouette_method: SilhouetteMethod,
    /// Band fitted, as fractions of the heap height.
    pub band_fraction: (f64, f64),
    /// Band fitted, heights above the tray top, m.
    pub band_m: (f64, f64),
    pub tray: Tray,
    /// Time of the particle frame measured, s.
    pub cloud_time_s: f64,
}

/// A repose run's result: where it came from and the measurement (one flat JSON object).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReposeResult {
    #[serde(flatten)]
    pub source: RunSource,
    #[serde(flatten)]
    pub analysis: ReposeAnalysis,
}

/// Measures the angle of repose of a repose run read with a particle frame (the last one for
/// the final heap: [`super::CloudChoice::Last`]).
pub fn repose(run: &Run, options: &ReposeOptions) -> Result<ReposeResult, ReduceError> {
    run.expect_experiment(REPOSE)?;
    let tray = Tray::from_run(run)?;
    let analysis = repose_angle(run.cloud()?, &tray, options).map_err(|e| e.in_file(&run.file))?;
    Ok(ReposeResult {
        source: run.source(),
        analysis,
    })
}

/// Measures the angle of repose of the heap on `tray` in `cloud` (see the module doc).
pub fn repose_angle(
    cloud: &ParticleCloud,
    tray: &Tray,
    options: &ReposeOptions,
) -> Result<ReposeAnalysis, ReduceError> {
    let (lo, hi) = options.band;
    if !(0.0 <= lo && lo < hi && hi <= 1.0) {
        return Err(ReduceError::Degenerate(format!(
            "repose: height band {lo}..{hi} is not a range within 0..1"
        )));
    }
    if options.views.is_empty() {
        return Err(ReduceError::Degenerate(
            "repose: no view to measure".to_string(),
        ));
    }
    // Heap particles, relative to the tray axis and top.
    let (mut u, mut v, mut h, mut rad) = (vec![], vec![], vec![], vec![]);
    for k in 0..cloud.len() {
        let (dx, dy) = (cloud.x[k] - tray.centre_x_m, cloud.y[k] - tray.centre_y_m);
        if dx.hypot(dy) <= tray.radius_m
            && cloud.z[k] > tray.top_z_m
            && cloud.z[k] < tray.top_z_m + tray.ceiling_m
        {
            u.push(dx);
            v.push(dy);
            h.push(cloud.z[k] + cloud.radius[k] - tray.top_z_m);
            rad.push(cloud.radius[k]);
        }
    }
    if u.len() < 2 * MIN_HALF_POINTS {
        return Err(ReduceError::TooFewPoints {
            what: "repose: particles on the tray".to_string(),
            have: u.len(),
            need: 2 * MIN_HALF_POINTS,
        });
    }
    // The particle size of the heap: the median, so that a few fines do not set the scale.
    let diameter = 2.0 * median(&mut rad.clone());
    let width = match options.bin_width_m {
        Some(w) if w > 0.0 => w,
        Some(w) => {
            return Err(ReduceError::Degenerate(format!(
                "repose: bin width {w} m is not positive"
            )));
        }
        None => match options.method {
            SilhouetteMethod::Envelope => diameter / ENVELOPE_BINS_PER_DIAMETER,
            SilhouetteMethod::HighestTop => diameter,
        },
    };
    let height = h.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    // Centre heights above the tray top, for the discs of the silhouette.
    let centre: Vec<f64> = h.iter().zip(&rad).map(|(t, r)| t - r).collect();
    let band_m = (lo * height, hi * height);
    let r = tray.radius_m;

    let mut views = Vec::with_capacity(options.views.len());
    for &view in &options.views {
        let sil = match view {
            View::Xz => silhouette(options.method, &u, &centre, &rad, width, -r, r + width),
            View::Yz => silhouette(options.method, &v, &centre, &rad, width, -r, r + width),
            View::Azimuth(_) => {
                let (cx, cy) = view.direction();
                let w: Vec<f64> = u.iter().zip(&v).map(|(x, y)| x * cx + y * cy).collect();
                silhouette(options.method, &w, &centre, &rad, width, -r, r + width)
            }
        };
        views.push(fit_view(view, sil, band_m)?);
    }
    let cone = cone_fit(&u, &v, &h, diameter, r, band_m, 0.5 * diameter)?;
    let halves: Vec<f64> = views
        .iter()
        .flat_map(|w| [w.left.angle_deg, w.right.angle_deg])
        .collect();
    Ok(ReposeAnalysis {
        repose_angle_deg: halves.iter().sum::<f64>() / halves.len() as f64,
        views,
        cone,
        heap_particles: u.len(),
        heap_height_m: height,
        bin_width_m: width,
        silhouette_method: options.method,
        band_fraction: options.band,
        band_m,
        tray: *tray,
        cloud_time_s: cloud.time_s,
    })
}

/// Splits a silhouette at its apex and fits each half within the band.
fn fit_view(
    view: View,
    silhouette_m: Vec<(f64, f64)>,
    band_m: (f64, f64),
) -> Result<ViewFit, ReduceError> {
    let apex = silhouette_m
        .iter()
        .copied()
        .reduce(|a, b| if b.1 > a.1 { b } else { a })
        .map_or(0.0, |p| p.0);
    let in_band = |p: &&(f64, f64)| (band_m.0..=band_m.1).contains(&p.1);
    let half = |side: &str, keep: &dyn Fn(f64) -> bool| -> Result<HalfFit, ReduceError> {
        let pts: Vec<(f64, f64)> = silhouette_m
            .iter()
            .filter(|p| keep(p.0))
            .filter(in_band)
            .copied()
            .collect();
        let what = format!(
            "repose: {side} half of the {} silhouette in the height band",
            view.axis()
        );
        if pts.len() < MIN_HALF_POINTS {
            return Err(ReduceError::TooFewPoints {
                what,
                have: pts.len(),
                need: MIN_HALF_POINTS,
            });
        }
        let f = fit_line(&pts, &what)?;
        Ok(HalfFit {
            angle_deg: f.slope.abs().atan().to_degrees(),
            slope: f.slope,
            intercept_m: f.intercept,
            r_squared: f.r_squared,
            points: f.points,
        })
    };
    let left = half("left", &|x| x < apex)?;
    let right = half("right", &|x| x > apex)?;
    Ok(ViewFit {
        view,
        apex_m: apex,
        mean_deg: 0.5 * (left.angle_deg + right.angle_deg),
        left,
        right,
        silhouette_m,
    })
}

/// Median of `values` (reorders them); the lower middle value for an even count.
fn median(values: &mut [f64]) -> f64 {
    let mid = (values.len() - 1) / 2;
    *values.select_nth_unstable_by(mid, f64::total_cmp).1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Particles of radius 1 on the surface of an ideal cone, as rings 1 apart: every top
    /// sits exactly on h = 20 - tan(theta) rho, and every ring has a particle at azimuth 0,
    /// 90, 180 and 270 degrees, so each silhouette point lies on the cone's outline.
    fn ring_cone(theta_deg: f64) -> ParticleCloud {
        let t = theta_deg.to_radians().tan();
        let mut c = ParticleCloud::default();
        let mut rho: f64 = 0.0;
        while rho <= 20.0 / t && rho <= 30.0 {
            let n = 4 * ((std::f64::consts::TAU * rho / 8.0).floor() as usize).max(1);
            for k in 0..n {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                c.x.push(rho * a.cos());
                c.y.push(rho * a.sin());
                c.z.push(20.0 - t * rho - 1.0);
                c.radius.push(1.0);
            }
            rho += 1.0;
        }
        c
    }

    #[test]
    fn ideal_ring_cone_gives_its_angle_in_every_half() {
        let tray = Tray {
            radius_m: 30.0,
            top_z_m: 0.0,
            centre_x_m: 0.0,
            centre_y_m: 0.0,
            ceiling_m: f64::INFINITY,
        };
        for theta in [30.0, 40.0] {
            let a = repose_angle(&ring_cone(theta), &tray, &ReposeOptions::default()).unwrap();
            for w in &a.views {
                for half in [w.left, w.right] {
                    assert!((half.angle_deg - theta).abs() < 0.05, "{theta}: {half:?}");
                }
            }
            assert!((a.repose_angle_deg - theta).abs() < 0.05);
            assert!((a.cone.angle_deg - theta).abs() < 0.05, "{:?}", a.cone);
        }
    }

    #[test]
    fn refuses_a_band_outside_zero_to_one() {
        let tray = Tray {
            radius_m: 30.0,
            top_z_m: 0.0,
            centre_x_m: 0.0,
            centre_y_m: 0.0,
            ceiling_m: f64::INFINITY,
        };
        let options = ReposeOptions {
            band: (0.5, 0.2),
            ..ReposeOptions::default()
        };
        assert!(repose_angle(&ring_cone(30.0), &tray, &options).is_err());
    }
}
