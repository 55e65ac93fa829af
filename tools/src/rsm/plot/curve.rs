//! The fitted response against one free factor, with its confidence band, targets and
//! direct checks.

use super::{
    BLUE, Chart, FONT, GREY, PALETTE, RED, err, fixed_text, free_factors, legend_at,
    quietest_corner,
};
use crate::rsm::{Anova, RsmError, Solution, significant};
use plotters::prelude::*;
use plotters::style::RGBColor;
use statrs::distribution::{ContinuousCDF, StudentsT};

const WHAT: &str = "the response curve";
/// Intervals the free factor's range is cut into for the curve.
const STEPS: usize = 80;

/// The fitted response against the one free factor (the others at their fixed values or
/// centres), its 95 % confidence band of the mean, each target as a dashed line with the
/// setting that hits it marked, and, when the model has that one factor only, the runs.
/// `None` unless exactly one factor is free.
pub fn response_curve_svg(
    a: &Anova,
    solutions: &[Solution],
    fixed: &[(usize, f64)],
) -> Result<Option<String>, RsmError> {
    response_curve_checked_svg(a, solutions, fixed, &[])
}

/// Direct runs at one setting of the free factor, outside the fit (a calibration's checks).
#[derive(Debug, Clone, PartialEq)]
pub struct CheckRuns {
    /// The free factor's value, real units.
    pub x: f64,
    /// The response of each run.
    pub values: Vec<f64>,
    pub label: String,
}

/// [`response_curve_svg`] with direct checks drawn over it: each run a green point, their
/// mean with +- one standard deviation between runs as a bar.
pub fn response_curve_checked_svg(
    a: &Anova,
    solutions: &[Solution],
    fixed: &[(usize, f64)],
    checks: &[CheckRuns],
) -> Result<Option<String>, RsmError> {
    let free = free_factors(a, fixed);
    let [i] = free[..] else {
        return Ok(None);
    };
    let curve = fitted_curve(a, &curve_base(a, fixed), i)?;
    let runs = one_factor_runs(a);
    let frame = Frame::around(a, i, &curve, &runs, checks, solutions);
    let fixed_text = fixed_text(a, fixed);
    let mut title = format!("{} against {}", a.response, a.factors[i]);
    if !fixed_text.is_empty() {
        title += &format!(" ({})", fixed_text.join(", "));
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(err(WHAT))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&title, (FONT, 17))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(frame.x.0..frame.x.1, frame.y.0..frame.y.1)
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .x_desc(a.factors[i].as_str())
            .y_desc(a.response.as_str())
            .label_style((FONT, 12))
            .draw()
            .map_err(err(WHAT))?;
        draw_fit(&mut chart, a, &curve)?;
        if !runs.is_empty() {
            chart
                .draw_series(runs.iter().map(|p| Circle::new(*p, 4, GREY.filled())))
                .map_err(err(WHAT))?
                .label(format!("runs ({})", runs.len()))
                .legend(|(x, y)| Circle::new((x + 10, y), 4, GREY.filled()));
        }
        draw_checks(&mut chart, checks)?;
        draw_targets(&mut chart, a, i, solutions, frame.x)?;
        let occupied = occupied(&curve, &runs, checks, solutions, frame.x);
        let corner = quietest_corner(&occupied, frame.x, frame.y);
        legend_at(&mut chart, WHAT, corner)?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(Some(svg))
}

/// Every factor's setting along the curve, real units: the centre, unless fixed (the last
/// value, if a factor is given twice).
fn curve_base(a: &Anova, fixed: &[(usize, f64)]) -> Vec<f64> {
    let mut base: Vec<f64> = (0..a.factors.len()).map(|k| a.coding.centre(k)).collect();
    for (k, v) in fixed {
        base[*k] = *v;
    }
    base
}

/// One point of the fitted curve.
#[derive(Debug, Clone, Copy)]
struct CurvePoint {
    /// The free factor, real units.
    x: f64,
    fitted: f64,
    /// Half-width of the 95 % confidence band of the mean: t(0.975, df_res) SE(mean).
    half: f64,
}

/// The fitted response at STEPS + 1 evenly spaced settings of factor `i` across its range,
/// the others at `base`, with the band's half-width (0 where the standard error is unknown).
fn fitted_curve(a: &Anova, base: &[f64], i: usize) -> Result<Vec<CurvePoint>, RsmError> {
    let (x0, x1) = (a.coding.low[i], a.coding.high[i]);
    let df = a.residual_df().max(1) as f64;
    let t = StudentsT::new(0.0, 1.0, df)
        .map_err(err(WHAT))?
        .inverse_cdf(0.975);
    Ok((0..=STEPS)
        .map(|s| {
            let mut x = base.to_vec();
            x[i] = x0 + (x1 - x0) * s as f64 / STEPS as f64;
            let z = a.coding.code(&x);
            let half = a.mean_std_error(&z).map_or(0.0, |se| t * se);
            CurvePoint {
                x: x[i],
                fitted: a.predict_coded(&z),
                half,
            }
        })
        .collect())
}

/// The runs as (setting, response) when the model has one factor only (otherwise they do not
/// lie in the picture's plane).
fn one_factor_runs(a: &Anova) -> Vec<(f64, f64)> {
    if a.factors.len() == 1 {
        a.diagnostics
            .iter()
            .map(|d| (d.settings[0], d.actual))
            .collect()
    } else {
        vec![]
    }
}

/// The plotted ranges: x the free factor's range widened to every check, y everything drawn
/// (band, runs, checks, targets) with 6 % of its span added on each side.
struct Frame {
    x: (f64, f64),
    y: (f64, f64),
}

impl Frame {
    fn around(
        a: &Anova,
        i: usize,
        curve: &[CurvePoint],
        runs: &[(f64, f64)],
        checks: &[CheckRuns],
        solutions: &[Solution],
    ) -> Frame {
        let (x0, x1) = (a.coding.low[i], a.coding.high[i]);
        let ys = curve
            .iter()
            .flat_map(|c| [c.fitted - c.half, c.fitted + c.half])
            .chain(runs.iter().map(|r| r.1))
            .chain(checks.iter().flat_map(|c| c.values.iter().copied()))
            .chain(solutions.iter().map(|s| s.target));
        let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(v), h.max(v))
        });
        let pad = 0.06 * (hi - lo).max(1e-9);
        let x = checks.iter().fold((x0.min(x1), x0.max(x1)), |(l, h), c| {
            (l.min(c.x), h.max(c.x))
        });
        Frame {
            x,
            y: (lo - pad, hi + pad),
        }
    }
}

/// The confidence band (shaded) and the fitted line, each with its legend entry.
fn draw_fit<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &Anova,
    curve: &[CurvePoint],
) -> Result<(), RsmError> {
    let band: Vec<(f64, f64)> = curve
        .iter()
        .map(|c| (c.x, c.fitted + c.half))
        .chain(curve.iter().rev().map(|c| (c.x, c.fitted - c.half)))
        .collect();
    chart
        .draw_series([Polygon::new(band, BLUE.mix(0.18).filled())])
        .map_err(err(WHAT))?
        .label(format!(
            "95 % confidence band of the mean ({} df)",
            a.residual_df()
        ))
        .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 20, y + 5)], BLUE.mix(0.18).filled()));
    chart
        .draw_series(LineSeries::new(
            curve.iter().map(|c| (c.x, c.fitted)),
            BLUE.stroke_width(2),
        ))
        .map_err(err(WHAT))?
        .label(format!("{} model, R^2 {:.4}", a.order.name(), a.r2))
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
    Ok(())
}

/// Mean and sample standard deviation (n - 1) of `values`; the deviation is 0 for one value.
fn mean_and_sd(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let sd = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, sd)
}

/// Each check with runs: its runs as green points and their mean +- one standard deviation
/// as a black bar.
fn draw_checks<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    checks: &[CheckRuns],
) -> Result<(), RsmError> {
    const GREEN: RGBColor = PALETTE[2];
    for c in checks.iter().filter(|c| !c.values.is_empty()) {
        let (mean, sd) = mean_and_sd(&c.values);
        chart
            .draw_series(
                c.values
                    .iter()
                    .map(|v| Circle::new((c.x, *v), 3, GREEN.filled())),
            )
            .map_err(err(WHAT))?;
        chart
            .draw_series([ErrorBar::new_vertical(
                c.x,
                mean - sd,
                mean,
                mean + sd,
                BLACK.stroke_width(2),
                10,
            )])
            .map_err(err(WHAT))?
            .label(c.label.as_str())
            .legend(|(x, y)| Circle::new((x + 10, y), 3, GREEN.filled()));
    }
    Ok(())
}

/// Each target a dashed red line across `x`, the settings that hit it red crosses, and a
/// label at the left edge saying what hits it.
fn draw_targets<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &Anova,
    i: usize,
    solutions: &[Solution],
    (xlo, xhi): (f64, f64),
) -> Result<(), RsmError> {
    for s in solutions {
        chart
            .draw_series(DashedLineSeries::new(
                [(xlo, s.target), (xhi, s.target)],
                6,
                4,
                RED.stroke_width(1),
            ))
            .map_err(err(WHAT))?;
        let hit = s.settings.iter().map(|st| st.values[i]);
        chart
            .draw_series(hit.map(|x| Cross::new((x, s.target), 6, RED.stroke_width(2))))
            .map_err(err(WHAT))?;
        chart
            .draw_series([Text::new(
                target_label(a, i, s),
                (xlo + 0.01 * (xhi - xlo), s.target),
                (FONT, 11).into_font().color(&RED),
            )])
            .map_err(err(WHAT))?;
    }
    Ok(())
}

/// What hits a target: nothing, the one setting of factor `i`, or how many settings.
fn target_label(a: &Anova, i: usize, s: &Solution) -> String {
    match s.settings.len() {
        0 => format!("{} = {}: out of range", s.label, s.target),
        1 => format!(
            "{}: {} = {}",
            s.label,
            a.factors[i],
            significant(s.settings[0].values[i], 5)
        ),
        n => format!("{}: {n} settings", s.label),
    }
}

/// Points the legend should not cover: the curve and its band, the runs, the checks, and
/// each target's label (drawn from the left edge along the target, over about 40 % of `x`).
fn occupied(
    curve: &[CurvePoint],
    runs: &[(f64, f64)],
    checks: &[CheckRuns],
    solutions: &[Solution],
    (xlo, xhi): (f64, f64),
) -> Vec<(f64, f64)> {
    let mut occupied: Vec<(f64, f64)> = curve
        .iter()
        .flat_map(|c| (0..=4).map(move |k| (c.x, c.fitted - c.half + 0.5 * c.half * k as f64)))
        .chain(runs.iter().copied())
        .chain(
            checks
                .iter()
                .flat_map(|c| c.values.iter().map(move |v| (c.x, *v))),
        )
        .collect();
    for s in solutions {
        occupied.extend((0..=20).map(|k| (xlo + (xhi - xlo) * 0.4 * k as f64 / 20.0, s.target)));
    }
    occupied
}
