//! Whether a direct-shear peak and an unconfined compressive strength can come from one
//! material: a check on measurements, before any simulation is asked to match both.
//!
//! **The bound.** An unconfined compression test loads a specimen with sigma_3 = 0 and
//! sigma_1 rising to q, its strength. The Mohr circles of these states all pass through the
//! origin, centred at q/2 with radius q/2, so a smaller load's circle lies inside a larger
//! one's: the specimen fails at the first load whose circle touches the material's failure
//! envelope tau_f(sigma). Hence over 0 <= sigma <= q the envelope lies on or above the
//! failure circle,
//!
//! ```text
//! tau_f(sigma) >= sqrt(sigma (q - sigma))                                   (1)
//! ```
//!
//! whatever the envelope's shape (Mohr-Coulomb, curved, with a tension cut-off). A direct
//! shear test at normal stress sigma_n over a shear plane of area A reads the envelope there,
//! F = A tau_f(sigma_n) (the reading behind every Mohr-Coulomb fit of shear-box data), so
//! for sigma_n < q
//!
//! ```text
//! F >= A sqrt(sigma_n (q - sigma_n))          q <= sigma_n + (F / A)^2 / sigma_n     (2)
//! ```
//!
//! (Units: N, Pa, m^2.) Two measurements that break (2) cannot both be met by a model whose
//! specimens are one homogeneous material in both tests, however its parameters are set; a
//! model can meet them only through something that differs between the tests (end friction
//! on a squat compression specimen, progressive failure in the shear box, different
//! specimens). With sigma_n >= q, (1) says nothing at sigma_n and the pair is compatible.
//!
//! Reference: the Mohr circle and failure envelope, e.g. Craig's Soil Mechanics (8th ed.),
//! ch. 4 (unconfined compression as the triaxial test with sigma_3 = 0).

use crate::rsm::plot::PALETTE;
use plotters::prelude::*;
use serde::Serialize;

/// The smallest shear force (N) a shear plane of `area` (m^2) under `normal_stress` (Pa) can
/// carry at failure in a material whose unconfined compressive strength is `ucs` (Pa): bound
/// (2). Zero when the normal stress reaches the strength (the bound says nothing there).
pub fn min_shear_force(area: f64, normal_stress: f64, ucs: f64) -> f64 {
    if normal_stress >= ucs || normal_stress <= 0.0 {
        return 0.0;
    }
    area * (normal_stress * (ucs - normal_stress)).sqrt()
}

/// The largest unconfined compressive strength (Pa) of a material whose shear plane of `area`
/// (m^2) fails at `force` (N) under `normal_stress` (Pa): bound (2) solved for q.
/// Infinite at zero normal stress (a shear test without load does not bound q).
pub fn max_ucs(area: f64, normal_stress: f64, force: f64) -> f64 {
    if normal_stress <= 0.0 {
        return f64::INFINITY;
    }
    let tau = force / area;
    normal_stress + tau * tau / normal_stress
}

/// One direct-shear measurement and one unconfined compression measurement of the same soil
/// (same conditions), checked against bound (2).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ShearUcsCheck {
    /// Measured peak shear force, N.
    pub shear_force_n: f64,
    /// The shear test's normal stress, Pa.
    pub normal_stress_pa: f64,
    /// The shear plane's area, m^2.
    pub area_m2: f64,
    /// Measured unconfined compressive strength, Pa.
    pub ucs_pa: f64,
    /// Bound (2): the least shear force the measured strength allows, N.
    pub min_shear_force_n: f64,
    /// Bound (2): the largest strength the measured shear force allows, Pa.
    pub max_ucs_pa: f64,
    /// Both measurements can come from one material.
    pub compatible: bool,
    /// The smallest relative error band `b` (the same for both, as a fraction) within which
    /// some pair of values can come from one material: the smallest `b` with
    /// F (1 + b) >= A sqrt(sigma_n (q (1 - b) - sigma_n)). Zero when compatible.
    pub band_needed: f64,
}

impl ShearUcsCheck {
    pub fn new(area: f64, normal_stress: f64, shear_force: f64, ucs: f64) -> ShearUcsCheck {
        let min_f = min_shear_force(area, normal_stress, ucs);
        ShearUcsCheck {
            shear_force_n: shear_force,
            normal_stress_pa: normal_stress,
            area_m2: area,
            ucs_pa: ucs,
            min_shear_force_n: min_f,
            max_ucs_pa: max_ucs(area, normal_stress, shear_force),
            compatible: shear_force >= min_f,
            band_needed: band_needed(area, normal_stress, shear_force, ucs),
        }
    }

    /// Whether some shear force within `shear_band` (a fraction) of the measured one and some
    /// strength within `ucs_band` of the measured one can come from one material: the
    /// highest force and the lowest strength in the bands are the most compatible pair.
    pub fn compatible_within(&self, shear_band: f64, ucs_band: f64) -> bool {
        fits_within(
            self.area_m2,
            self.normal_stress_pa,
            self.shear_force_n,
            self.ucs_pa,
            (shear_band, ucs_band),
        )
    }
}

/// Bound (2) for the most compatible pair within the bands (fractions): the highest force
/// and the lowest strength.
fn fits_within(area: f64, normal_stress: f64, force: f64, ucs: f64, bands: (f64, f64)) -> bool {
    force * (1.0 + bands.0) >= min_shear_force(area, normal_stress, ucs * (1.0 - bands.1))
}

/// The smallest equal band b in [0, 1] that makes the pair compatible (bisection on a
/// monotone condition: widening the band raises the force and lowers the strength).
fn band_needed(area: f64, normal_stress: f64, force: f64, ucs: f64) -> f64 {
    let ok = |b: f64| fits_within(area, normal_stress, force, ucs, (b, b));
    if ok(0.0) {
        return 0.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) { hi = mid } else { lo = mid }
    }
    hi
}

/// A Mohr diagram (SVG) of labelled pairs: each UCS's failure circle (through 0 and q,
/// upper half) and, in the same colour, the shear test's point (sigma_n, F / A). A point
/// inside its circle is a pair no single material gives (bound (1)); kPa on both axes,
/// equal scales.
pub fn mohr_svg(pairs: &[(String, &ShearUcsCheck)]) -> Result<String, String> {
    let err = |e: String| format!("Mohr plot: {e}");
    let kpa = 1e-3;
    let q_max = pairs.iter().map(|(_, k)| k.ucs_pa).fold(0.0, f64::max);
    let tau_max = pairs
        .iter()
        .map(|(_, k)| k.shear_force_n / k.area_m2)
        .fold(0.5 * q_max, f64::max);
    let sigma_max = pairs
        .iter()
        .map(|(_, k)| k.normal_stress_pa)
        .fold(q_max, f64::max);
    // Room on the right for the legend, clear of the circles.
    let (xmax, ymax) = (1.4 * kpa * sigma_max, 1.1 * kpa * tau_max);
    let width = 860u32;
    let height = (f64::from(width - 90) * ymax / xmax) as u32 + 120;
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (width, height.clamp(300, 900))).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "UCS failure circles and shear points: a point inside its circle, no one material",
                ("sans-serif", 17),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..xmax, 0.0..ymax)
            .map_err(|e| err(e.to_string()))?;
        chart
            .configure_mesh()
            .x_desc("normal stress sigma, kPa")
            .y_desc("shear stress tau, kPa")
            .draw()
            .map_err(|e| err(e.to_string()))?;
        for (k, (label, c)) in pairs.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            let r = 0.5 * kpa * c.ucs_pa;
            chart
                .draw_series(LineSeries::new(
                    (0..=180).map(|a| {
                        let t = f64::from(a).to_radians();
                        (r - r * t.cos(), r * t.sin())
                    }),
                    colour.stroke_width(2),
                ))
                .map_err(|e| err(e.to_string()))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            let point = (kpa * c.normal_stress_pa, kpa * c.shear_force_n / c.area_m2);
            chart
                .draw_series(std::iter::once(Circle::new(point, 5, colour.filled())))
                .map_err(|e| err(e.to_string()))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(e.to_string()))?;
        root.present().map_err(|e| err(e.to_string()))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mohr-Coulomb's strength in unconfined compression, written independently of (1):
    /// q = 2 c tan(45 deg + phi / 2).
    fn mc_ucs(c: f64, phi: f64) -> f64 {
        2.0 * c * (std::f64::consts::FRAC_PI_4 + 0.5 * phi).tan()
    }

    #[test]
    fn every_mohr_coulomb_material_respects_the_bound() {
        let area = 3.0e-3;
        for c in [1e3, 1e4, 5e4, 2e5] {
            for phi_deg in [0.0, 10.0, 20.0, 30.0, 40.0, 50.0] {
                let phi = f64::to_radians(phi_deg);
                let q = mc_ucs(c, phi);
                for sigma in [1e3, 2e4, 1e5, 3e5] {
                    let f = area * (c + sigma * phi.tan());
                    assert!(
                        f >= min_shear_force(area, sigma, q) * (1.0 - 1e-12),
                        "c {c} phi {phi_deg}: F {f} below the bound"
                    );
                    assert!(q <= max_ucs(area, sigma, f) * (1.0 + 1e-12));
                }
            }
        }
    }

    #[test]
    fn the_bound_is_reached_by_the_line_tangent_to_the_failure_circle() {
        // The Mohr-Coulomb line touching the circle of strength q at sigma_n: slope from the
        // circle's normal there, c from the point. Its own strength must be q, and its shear
        // force at sigma_n the bound.
        let (area, q): (f64, f64) = (3.0e-3, 259.1e3);
        for sigma in [2e4_f64, 1e5, 2e5] {
            let tau = (sigma * (q - sigma)).sqrt();
            let tan_phi = (0.5 * q - sigma) / tau;
            let c = tau - sigma * tan_phi;
            let phi = tan_phi.atan();
            assert!((mc_ucs(c, phi) - q).abs() < 1e-9 * q, "sigma {sigma}");
            let f = area * (c + sigma * tan_phi);
            assert!((f - min_shear_force(area, sigma, q)).abs() < 1e-9 * f);
            assert!((max_ucs(area, sigma, f) - q).abs() < 1e-9 * q);
        }
    }

    #[test]
    fn the_mohr_plot_draws_a_circle_and_a_point_per_pair() {
        let a = ShearUcsCheck::new(3e-3, 1e5, 197.4, 259.1e3);
        let b = ShearUcsCheck::new(3e-3, 1e5, 149.4, 94.25e3);
        let svg = mohr_svg(&[("6 %, 1.55 MPa".into(), &a), ("6 %, 0.34 MPa".into(), &b)]).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("6 %, 1.55 MPa") && svg.contains("6 %, 0.34 MPa"));
        assert_eq!(svg.matches("<circle").count(), 2, "one point per pair");
        assert!(svg.matches("<polyline").count() >= 2, "one circle per pair");
    }

    #[test]
    fn a_normal_stress_at_or_above_the_strength_bounds_nothing() {
        assert_eq!(min_shear_force(3e-3, 1e5, 9e4), 0.0);
        assert!(ShearUcsCheck::new(3e-3, 1e5, 1.0, 9e4).compatible);
        assert_eq!(max_ucs(3e-3, 0.0, 100.0), f64::INFINITY);
    }

    #[test]
    fn the_band_needed_is_where_the_widened_pair_first_fits() {
        let k = ShearUcsCheck::new(3e-3, 1e5, 197.4, 259.1e3);
        assert!(!k.compatible);
        let b = k.band_needed;
        assert!(b > 0.0 && b < 1.0);
        assert!(k.compatible_within(b + 1e-9, b + 1e-9));
        assert!(!k.compatible_within(b - 1e-6, b - 1e-6));
        let ok = ShearUcsCheck::new(3e-3, 1e5, 400.0, 259.1e3);
        assert!(ok.compatible);
        assert_eq!(ok.band_needed, 0.0);
    }
}
