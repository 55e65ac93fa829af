//! Peak shear stress against normal stress with the Mohr-Coulomb line.

use super::{BLUE, DARK_BLUE, RED, legend, mesh, plot_error, titled};
use crate::reduce::error::ReduceError;
use crate::reduce::mohr_coulomb::MohrCoulombFit;
use plotters::prelude::*;

const WHAT: &str = "the Mohr-Coulomb plot";

/// Each run's (sigma, tau_peak) in kPa (red if its file is incomplete) and the fitted line
/// tau = c + sigma tan(phi) from sigma = 0, so the cohesion is read off the axis.
pub fn mohr_coulomb_svg(fit: &MohrCoulombFit) -> Result<String, ReduceError> {
    let kpa = 1e-3;
    let tan = fit.friction_angle_deg.to_radians().tan();
    let line = |s: f64| (fit.cohesion_pa + s * tan) * kpa;
    let smax = fit
        .points
        .iter()
        .map(|p| p.normal_stress_pa)
        .fold(0.0, f64::max)
        .max(1.0)
        * 1.1;
    let tmax = fit
        .points
        .iter()
        .map(|p| p.shear_strength_pa * kpa)
        .chain([line(0.0), line(smax)])
        .fold(0.0, f64::max)
        * 1.15;
    let tmin = fit
        .points
        .iter()
        .map(|p| p.shear_strength_pa * kpa)
        .chain([line(0.0)])
        .fold(0.0, f64::min);
    let incomplete = fit.points.iter().filter(|p| !p.complete).count();
    let subtitle = if incomplete == 0 {
        format!("{} runs, all files complete", fit.points.len())
    } else {
        format!(
            "{} runs, {incomplete} from INCOMPLETE files (red)",
            fit.points.len()
        )
    };
    let title = format!(
        "Mohr-Coulomb: c = {:.2} kPa, φ = {:.2}° (R² {:.4})",
        fit.cohesion_pa * kpa,
        fit.friction_angle_deg,
        fit.r_squared
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 560)).into_drawing_area();
        let area = titled(&root, &title, &subtitle, fit.complete, WHAT)?;
        let mut chart = ChartBuilder::on(&area)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..smax * kpa, tmin..tmax.max(tmin + 1.0))
            .map_err(plot_error(WHAT))?;
        mesh(
            &mut chart,
            "normal stress σ (kPa)",
            "peak shear stress τ (kPa)",
            WHAT,
        )?;
        chart
            .draw_series(LineSeries::new(
                [(0.0, line(0.0)), (smax * kpa, line(smax))],
                DARK_BLUE.stroke_width(2),
            ))
            .map_err(plot_error(WHAT))?
            .label("τ = c + σ tan φ")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], DARK_BLUE.stroke_width(2)));
        chart
            .draw_series(fit.points.iter().map(|p| {
                let colour = if p.complete { BLUE } else { RED };
                Circle::new(
                    (p.normal_stress_pa * kpa, p.shear_strength_pa * kpa),
                    5,
                    colour.filled(),
                )
            }))
            .map_err(plot_error(WHAT))?
            .label("runs (peak force / area)")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLUE.filled()));
        legend(&mut chart, SeriesLabelPosition::UpperLeft, WHAT)?;
        root.present().map_err(plot_error(WHAT))?;
    }
    Ok(svg)
}
