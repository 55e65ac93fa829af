//! The sample's speed down the slope against the plate's angle, the slide marked.

use super::{BLUE, GREY, RED, legend, mesh, padded, plot_error, title_block};
use crate::reduce::error::ReduceError;
use crate::reduce::tilt::TiltResult;
use plotters::prelude::*;

const WHAT: &str = "the tilt curve";

/// Speed (mm/s) against the plate's angle (degrees), the threshold (dashed) and the slide
/// angle (red).
pub fn tilt_svg(result: &TiltResult) -> Result<String, ReduceError> {
    let a = &result.analysis;
    let mm = 1e3;
    let threshold = a.slide_speed_m_per_s * mm;
    let smin = a.curve.iter().map(|p| p.1 * mm).fold(0.0, f64::min);
    let smax = a
        .curve
        .iter()
        .map(|p| p.1 * mm)
        .fold(2.0 * threshold, f64::max);
    let x = 0.0..a.max_angle_deg.max(1.0) * 1.05;
    let y = padded(smin, smax, 0.08);
    let title = match a.slide_angle_deg {
        Some(angle) => format!(
            "Slid at {angle:.2} degrees: static friction tan = {:.3}",
            angle.to_radians().tan()
        ),
        None => format!("Did not slide up to {:.1} degrees", a.max_angle_deg),
    };
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
            "plate angle (degrees)",
            "speed down the slope (mm/s)",
            WHAT,
        )?;
        chart
            .draw_series(LineSeries::new(
                a.curve.iter().map(|&(angle, s)| (angle, s * mm)),
                BLUE.stroke_width(2),
            ))
            .map_err(plot_error(WHAT))?
            .label("the sample's speed (median of its grains)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        chart
            .draw_series(DashedLineSeries::new(
                [(x.start, threshold), (x.end, threshold)],
                6,
                4,
                GREY.stroke_width(1),
            ))
            .map_err(plot_error(WHAT))?
            .label(format!("slide threshold {threshold:.1} mm/s"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], GREY));
        if let Some(angle) = a.slide_angle_deg {
            chart
                .draw_series([Circle::new((angle, threshold), 5, RED.filled())])
                .map_err(plot_error(WHAT))?
                .label(format!("slide angle {angle:.2} degrees"))
                .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::UpperLeft, WHAT)?;
        root.present().map_err(plot_error(WHAT))?;
    }
    Ok(svg)
}
