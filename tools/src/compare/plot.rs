//! SVG plots of a comparison (plotters' SVG backend): simulated against measured with
//! error bars, and residuals against a condition.

use super::Row;
use plotters::prelude::*;
use plotters::style::RGBColor;

const FONT: &str = "sans-serif";
const BLUE: RGBColor = RGBColor(31, 119, 180);
const GREY: RGBColor = RGBColor(127, 127, 127);

fn err<E: std::fmt::Display>(what: &str) -> impl Fn(E) -> String + '_ {
    move |e| format!("{what}: {e}")
}

/// (lo, hi) padded by 6 % of the span (and never empty).
fn padded(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = 0.06 * (hi - lo).max(1e-9 * hi.abs().max(1.0));
    (lo - pad, hi + pad)
}

/// Points (x, y, sd) with +/- sd bars where sd > 0.
fn points_with_bars(
    chart: &mut ChartContext<
        '_,
        SVGBackend<'_>,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    pts: &[(f64, f64, f64)],
    what: &str,
) -> Result<(), String> {
    chart
        .draw_series(pts.iter().filter(|p| p.2 > 0.0).map(|p| {
            ErrorBar::new_vertical(p.0, p.1 - p.2, p.1, p.1 + p.2, BLUE.stroke_width(1), 8)
        }))
        .map_err(err(what))?;
    chart
        .draw_series(
            pts.iter()
                .map(|p| Circle::new((p.0, p.1), 4, BLUE.filled())),
        )
        .map_err(err(what))?;
    Ok(())
}

/// A row's conditions as a point label: "6 %", "1.55 MPa", "100 kPa"; a condition whose
/// name carries no unit suffix as "name value".
pub fn condition_label(conditions: &std::collections::BTreeMap<String, f64>) -> String {
    let one = |(name, v): (&String, &f64)| {
        if name.ends_with("_pct") {
            format!("{v} %")
        } else if name.ends_with("_mpa") {
            format!("{v} MPa")
        } else if name.ends_with("_pa") && v.abs() >= 1e3 {
            format!("{} kPa", v / 1e3)
        } else if name.ends_with("_pa") {
            format!("{v} Pa")
        } else {
            format!("{name} {v}")
        }
    };
    conditions.iter().map(one).collect::<Vec<_>>().join(", ")
}

/// Simulated mean against measured value for one observable's rows, with the 1:1 line,
/// bars of +/- one standard error of the residual on the simulated value, and each point
/// labelled with its conditions (which row misses is what a reader asks first).
pub fn simulated_vs_measured_svg(rows: &[&Row]) -> Result<String, String> {
    let what = "simulated-vs-measured plot";
    let labelled: Vec<((f64, f64, f64), String)> = rows
        .iter()
        .filter_map(|r| {
            let p = (r.measured, r.simulated?, r.std_error.unwrap_or(0.0));
            Some((p, condition_label(&r.conditions)))
        })
        .collect();
    let pts: Vec<(f64, f64, f64)> = labelled.iter().map(|(p, _)| *p).collect();
    let (lo, hi) = padded(
        pts.iter()
            .flat_map(|p| [p.0, p.1 - p.2, p.1 + p.2].into_iter()),
    );
    let Some(first) = rows.first() else {
        return Err(format!("{what}: no rows"));
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (600, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(err(what))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!("{} {}: simulated vs measured", first.test, first.observable),
                (FONT, 17),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(lo..hi, lo..hi)
            .map_err(err(what))?;
        chart
            .configure_mesh()
            .x_desc(format!("measured {} ({})", first.observable, first.unit))
            .y_desc(format!("simulated ({})", first.unit))
            .label_style((FONT, 12))
            .draw()
            .map_err(err(what))?;
        chart
            .draw_series(LineSeries::new([(lo, lo), (hi, hi)], GREY.stroke_width(1)))
            .map_err(err(what))?;
        points_with_bars(&mut chart, &pts, what)?;
        chart
            .draw_series(labelled.iter().map(|((x, y, _), label)| {
                EmptyElement::at((*x, *y))
                    + Text::new(label.clone(), (7, -14), (FONT, 11).into_font().color(&GREY))
            }))
            .map_err(err(what))?;
        root.present().map_err(err(what))?;
    }
    Ok(svg)
}

/// Residual (simulated - measured) against `condition` for one observable's rows, with
/// +/- one standard error bars and the zero line.
pub fn residuals_svg(rows: &[&Row], condition: &str) -> Result<String, String> {
    let what = "residual plot";
    let pts: Vec<(f64, f64, f64)> = rows
        .iter()
        .filter_map(|r| {
            Some((
                *r.conditions.get(condition)?,
                r.residual()?,
                r.std_error.unwrap_or(0.0),
            ))
        })
        .collect();
    let Some(first) = rows.first() else {
        return Err(format!("{what}: no rows"));
    };
    let (xlo, xhi) = padded(pts.iter().map(|p| p.0));
    let (ylo, yhi) = padded(
        pts.iter()
            .flat_map(|p| [p.1 - p.2, p.1 + p.2, 0.0].into_iter()),
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (600, 420)).into_drawing_area();
        root.fill(&WHITE).map_err(err(what))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{} {}: residual against {condition}",
                    first.test, first.observable
                ),
                (FONT, 17),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(xlo..xhi, ylo..yhi)
            .map_err(err(what))?;
        chart
            .configure_mesh()
            .x_desc(condition)
            .y_desc(format!("simulated - measured ({})", first.unit))
            .label_style((FONT, 12))
            .draw()
            .map_err(err(what))?;
        chart
            .draw_series(LineSeries::new(
                [(xlo, 0.0), (xhi, 0.0)],
                GREY.stroke_width(1),
            ))
            .map_err(err(what))?;
        points_with_bars(&mut chart, &pts, what)?;
        root.present().map_err(err(what))?;
    }
    Ok(svg)
}

/// RMSE of one observable across a project's compare runs, in order (x: run number).
pub fn history_svg(observable: &str, unit: &str, rmse: &[f64]) -> Result<String, String> {
    let what = "history plot";
    let n = rmse.len();
    if n == 0 {
        return Err(format!("{what}: no runs"));
    }
    let (_, hi) = padded(rmse.iter().copied().chain([0.0]));
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (520, 340)).into_drawing_area();
        root.fill(&WHITE).map_err(err(what))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{observable}: RMSE per compare run"), (FONT, 16))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.5..(n as f64 + 0.5), 0.0..hi)
            .map_err(err(what))?;
        chart
            .configure_mesh()
            .x_desc("compare run (oldest first)")
            .y_desc(format!("RMSE ({unit})"))
            .x_labels(n.min(12))
            .x_label_formatter(&|x| format!("{}", x.round() as i64))
            .label_style((FONT, 12))
            .draw()
            .map_err(err(what))?;
        let pts: Vec<(f64, f64)> = rmse
            .iter()
            .enumerate()
            .map(|(k, v)| ((k + 1) as f64, *v))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(2)))
            .map_err(err(what))?;
        chart
            .draw_series(pts.iter().map(|p| Circle::new(*p, 4, BLUE.filled())))
            .map_err(err(what))?;
        root.present().map_err(err(what))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    fn row(conditions: &[(&str, f64)], measured: f64) -> Row {
        Row {
            test: "direct_shear".into(),
            observable: "peak_shear_force_n".into(),
            unit: "N".into(),
            conditions: conditions
                .iter()
                .map(|(k, v)| (k.to_string(), *v))
                .collect::<BTreeMap<_, _>>(),
            measured,
            simulated: Some(measured + 1.0),
            std_error: Some(0.5),
        }
    }

    #[test]
    fn each_point_is_labelled_with_its_conditions() {
        let a = row(&[("moisture_pct", 6.0), ("normal_pressure_pa", 1e5)], 40.0);
        let b = row(&[("moisture_pct", 12.0), ("firmness_mpa", 1.55)], 55.0);
        let c = row(&[("drop_mm", 60.0)], 50.0);
        assert_eq!(condition_label(&a.conditions), "6 %, 100 kPa");
        assert_eq!(condition_label(&b.conditions), "1.55 MPa, 12 %");
        assert_eq!(condition_label(&c.conditions), "drop_mm 60");
        let svg = simulated_vs_measured_svg(&[&a, &b, &c]).unwrap();
        for label in ["6 %, 100 kPa", "1.55 MPa, 12 %", "drop_mm 60"] {
            assert!(svg.contains(label), "{label} missing from the plot");
        }
    }
}
