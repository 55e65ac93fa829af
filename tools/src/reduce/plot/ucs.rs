//! Corrected axial stress against axial strain, failure marked.

use super::{BLUE, GREY, RED, legend, mesh, padded, plot_error, title_block};
use crate::reduce::error::ReduceError;
use crate::reduce::ucs::{Failure, UcsResult};
use plotters::prelude::*;

const WHAT: &str = "the compression curve";

/// The stress-strain curve (%, kPa), the strain limit (dashed) and the failure point (red).
pub fn ucs_svg(result: &UcsResult) -> Result<String, ReduceError> {
    let a = &result.analysis;
    let pct = 100.0;
    let max_strain = a.curve.iter().map(|p| p.0).fold(a.strain_limit, f64::max);
    let smin = a.curve.iter().map(|p| p.1).fold(0.0, f64::min);
    let smax = a.curve.iter().map(|p| p.1).fold(a.ucs_kpa, f64::max);
    let x = 0.0..max_strain * pct * 1.05;
    let y = padded(smin, smax, 0.08);
    let rule = match a.failure {
        Failure::Peak => "peak",
        Failure::StrainLimit => "still rising: at the strain limit",
        Failure::EndOfData => "record ends before failure: lower bound",
    };
    let title = format!(
        "Unconfined compressive strength {:.2} kPa at {:.2} % strain",
        a.ucs_kpa,
        a.strain_at_failure * pct
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 560)).into_drawing_area();
        let area = title_block(&root, &title, &result.source, WHAT)?;
        let mut chart = ChartBuilder::on(&area)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(x, y.clone())
            .map_err(plot_error(WHAT))?;
        mesh(&mut chart, "axial strain (%)", "stress F / A_c (kPa)", WHAT)?;
        chart
            .draw_series(LineSeries::new(
                a.curve.iter().map(|&(e, s)| (e * pct, s)),
                BLUE.stroke_width(2),
            ))
            .map_err(plot_error(WHAT))?
            .label("stress on the corrected area A_0 / (1 - strain)")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        let limit = a.strain_limit * pct;
        chart
            .draw_series(DashedLineSeries::new(
                [(limit, y.start), (limit, y.end)],
                6,
                4,
                GREY.stroke_width(1),
            ))
            .map_err(plot_error(WHAT))?
            .label(format!("strain limit {limit:.0} %"))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], GREY));
        chart
            .draw_series([Circle::new(
                (a.strain_at_failure * pct, a.ucs_kpa),
                5,
                RED.filled(),
            )])
            .map_err(plot_error(WHAT))?
            .label(format!("failure ({rule}): {:.2} kPa", a.ucs_kpa))
            .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
        legend(&mut chart, SeriesLabelPosition::LowerRight, WHAT)?;
        root.present().map_err(plot_error(WHAT))?;
    }
    Ok(svg)
}
