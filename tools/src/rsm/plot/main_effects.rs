//! Main-effects plot: the response along each factor, the others at their centres.

use super::{FONT, PALETTE, err, legend};
use crate::rsm::{Anova, RsmError};
use plotters::prelude::*;

/// Main effects: the response along each factor from -1 to +1 with the others at their
/// centres.
pub fn main_effects_svg(a: &Anova) -> Result<String, RsmError> {
    const WHAT: &str = "the main-effects plot";
    let k = a.factors.len();
    let curve = |i: usize| -> Vec<(f64, f64)> {
        (0..=40)
            .map(|s| {
                let t = -1.0 + s as f64 / 20.0;
                let mut z = vec![0.0; k];
                z[i] = t;
                (t, a.predict_coded(&z))
            })
            .collect()
    };
    let curves: Vec<Vec<(f64, f64)>> = (0..k).map(curve).collect();
    let (lo, hi) = curves
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(p.1), h.max(p.1))
        });
    let pad = 0.08 * (hi - lo).max(1e-9);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(err(WHAT))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("Main effects on {} (others at their centres)", a.response),
                (FONT, 17),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(-1.05..1.05, (lo - pad)..(hi + pad))
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .x_desc("coded level")
            .y_desc(a.response.as_str())
            .label_style((FONT, 12))
            .draw()
            .map_err(err(WHAT))?;
        for (i, c) in curves.iter().enumerate() {
            let color = PALETTE[i % PALETTE.len()];
            chart
                .draw_series(LineSeries::new(c.iter().copied(), color.stroke_width(2)))
                .map_err(err(WHAT))?
                .label(format!(
                    "{} ({} .. {})",
                    a.factors[i], a.coding.low[i], a.coding.high[i]
                ))
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        legend(&mut chart, WHAT)?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(svg)
}
