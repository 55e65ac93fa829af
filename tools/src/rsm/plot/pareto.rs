//! Pareto chart of the standardized effects.

use super::{BLUE, FONT, GREY, err};
use crate::rsm::{Anova, RsmError};
use plotters::prelude::*;
use plotters::style::RGBColor;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Pareto chart: |t| of each term, largest first, with the t limit at alpha = 0.05 and the
/// Bonferroni limit (Design-Expert's two lines).
pub fn pareto_svg(a: &Anova) -> Result<String, RsmError> {
    const WHAT: &str = "the Pareto chart";
    let mut bars: Vec<(String, f64, bool)> = a
        .terms
        .iter()
        .filter_map(|t| t.t.map(|v| (t.name.clone(), v.abs(), v >= 0.0)))
        .collect();
    bars.sort_by(|x, y| y.1.total_cmp(&x.1));
    let df = a.residual_df().max(1) as f64;
    let tdist = StudentsT::new(0.0, 1.0, df).map_err(err(WHAT))?;
    let limit = tdist.inverse_cdf(1.0 - 0.025);
    let bonf = tdist.inverse_cdf(1.0 - 0.025 / bars.len().max(1) as f64);
    let top = bars.first().map_or(1.0, |b| b.1).max(bonf) * 1.1;
    let n = bars.len();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 520)).into_drawing_area();
        root.fill(&WHITE).map_err(err(WHAT))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "Pareto chart of {} (|t|; blue positive, orange negative)",
                    a.response
                ),
                (FONT, 17),
            )
            .margin(15)
            .x_label_area_size(60)
            .y_label_area_size(55)
            .build_cartesian_2d(0.0..n as f64, 0.0..top)
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .y_desc("|t| (standardized effect)")
            .label_style((FONT, 12))
            .draw()
            .map_err(err(WHAT))?;
        // Term names above their bars (axis labels would sit at the bars' edges).
        chart
            .draw_series(bars.iter().enumerate().map(|(k, b)| {
                Text::new(
                    b.0.clone(),
                    (k as f64 + 0.5, b.1 + top * 0.015),
                    TextStyle::from((FONT, 12).into_font()).pos(
                        plotters::style::text_anchor::Pos::new(
                            plotters::style::text_anchor::HPos::Center,
                            plotters::style::text_anchor::VPos::Bottom,
                        ),
                    ),
                )
            }))
            .map_err(err(WHAT))?;
        chart
            .draw_series(bars.iter().enumerate().map(|(k, b)| {
                let c = if b.2 { BLUE } else { RGBColor(255, 127, 14) };
                Rectangle::new([(k as f64 + 0.15, 0.0), (k as f64 + 0.85, b.1)], c.filled())
            }))
            .map_err(err(WHAT))?;
        for (v, label) in [(limit, "t limit (alpha 0.05)"), (bonf, "Bonferroni limit")] {
            chart
                .draw_series(DashedLineSeries::new(
                    [(0.0, v), (n as f64, v)],
                    6,
                    4,
                    GREY.stroke_width(1),
                ))
                .map_err(err(WHAT))?;
            chart
                .draw_series([Text::new(
                    format!("{label} {v:.3}"),
                    (n as f64 * 0.62, v + top * 0.02),
                    (FONT, 12),
                )])
                .map_err(err(WHAT))?;
        }
        root.present().map_err(err(WHAT))?;
    }
    Ok(svg)
}
