//! Shear force against shear displacement, the peak marked.

use super::{BLUE, GREY, RED, legend, mesh, padded, plot_error, title_block};
use crate::reduce::error::ReduceError;
use crate::reduce::shear::ShearResult;
use plotters::prelude::*;

const WHAT: &str = "the shear curve";

/// The force-displacement curve (mm, N), its peak (red) and the peak of the apparatus's
/// readings (dashed), with the normal pressure in the title.
pub fn shear_svg(result: &ShearResult) -> Result<String, ReduceError> {
    let a = &result.analysis;
    let mm = 1e3;
    let fmin = a.curve.iter().map(|p| p.1).fold(0.0, f64::min);
    let x = 0.0..(a.max_displacement_m * mm).max(1e-3) * 1.05;
    let y = padded(fmin, a.peak_shear_force_n, 0.08);
    let title = format!(
        "Direct shear at {:.1} kPa: peak {:.2} N ({:.2} kPa) at {:.2} mm",
        a.specimen.normal_pressure_pa / 1e3,
        a.peak_shear_force_n,
        a.peak_shear_stress_pa / 1e3,
        a.displacement_at_peak_m * mm
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 560)).into_drawing_area();
        let area = title_block(&root, &title, &result.source, WHAT)?;
        let mut chart = ChartBuilder::on(&area)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x.clone(), y)
            .map_err(plot_error(WHAT))?;
        mesh(
            &mut chart,
            "shear displacement (mm)",
            "shear force (N)",
            WHAT,
        )?;
        chart
            .draw_series(LineSeries::new(
                a.curve.iter().map(|&(s, f)| (s * mm, f)),
                BLUE.stroke_width(2),
            ))
            .map_err(plot_error(WHAT))?
            .label("shear force on the lower box")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        if let Some(f) = a.peak_at_readings_n {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x.start, f), (x.end, f)],
                    6,
                    4,
                    GREY.stroke_width(1),
                ))
                .map_err(plot_error(WHAT))?
                .label(format!(
                    "peak of readings every {:.1} mm: {f:.2} N",
                    a.reading_interval_m * mm
                ))
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], GREY));
        }
        chart
            .draw_series([Circle::new(
                (a.displacement_at_peak_m * mm, a.peak_shear_force_n),
                5,
                RED.filled(),
            )])
            .map_err(plot_error(WHAT))?
            .label(format!(
                "peak {:.2} N at {:.2} mm",
                a.peak_shear_force_n,
                a.displacement_at_peak_m * mm
            ))
            .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
        legend(&mut chart, SeriesLabelPosition::LowerRight, WHAT)?;
        root.present().map_err(plot_error(WHAT))?;
    }
    Ok(svg)
}
