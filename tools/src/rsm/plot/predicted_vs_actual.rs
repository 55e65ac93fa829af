//! Predicted against actual response.

use super::{FONT, GREY, RED, err};
use crate::rsm::{Anova, RsmError};
use plotters::prelude::*;

/// Predicted against actual response, with the line of equality.
pub fn predicted_vs_actual_svg(a: &Anova) -> Result<String, RsmError> {
    const WHAT: &str = "the predicted-vs-actual plot";
    let pts: Vec<(f64, f64)> = a
        .diagnostics
        .iter()
        .map(|d| (d.actual, d.predicted))
        .collect();
    let (lo, hi) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.0.min(p.1)), h.max(p.0.max(p.1)))
        });
    let pad = 0.06 * (hi - lo).max(1e-9);
    let r = (lo - pad)..(hi + pad);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (640, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(err(WHAT))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{}: predicted vs actual (R^2 {:.4})", a.response, a.r2),
                (FONT, 17),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(r.clone(), r.clone())
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .x_desc("actual")
            .y_desc("predicted")
            .label_style((FONT, 12))
            .draw()
            .map_err(err(WHAT))?;
        chart
            .draw_series(LineSeries::new(
                [(r.start, r.start), (r.end, r.end)],
                GREY.stroke_width(1),
            ))
            .map_err(err(WHAT))?;
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 4, RED.filled())))
            .map_err(err(WHAT))?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(svg)
}
