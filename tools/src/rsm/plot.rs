//! SVG pictures of a response surface: contour plot with a target line, the response against
//! one free factor with its targets, Pareto chart of the
//! standardized effects, main effects, predicted against actual.
//!
//! Drawn as the reducers' pictures are (plotters' SVG backend, text left to the viewer).

use super::{Anova, RsmError, Solution, significant};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::RGBColor;
use plotters::style::colors::colormaps::ViridisRGB;
use statrs::distribution::{ContinuousCDF, StudentsT};

const FONT: &str = "sans-serif";
const BLUE: RGBColor = RGBColor(31, 119, 180);
const RED: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(127, 127, 127);
/// Tableau's ten colours.
pub(crate) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn err<E: std::fmt::Display>(what: &'static str) -> impl Fn(E) -> RsmError {
    move |e| RsmError::Plot {
        what: what.to_string(),
        problem: e.to_string(),
    }
}

/// The legend, upper left on an opaque box.
fn legend<'a, 'b: 'a>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    what: &'static str,
) -> Result<(), RsmError> {
    legend_at(chart, what, SeriesLabelPosition::UpperLeft)
}

fn legend_at<'a, 'b: 'a>(
    chart: &mut ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    what: &'static str,
    position: SeriesLabelPosition,
) -> Result<(), RsmError> {
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, 12))
        .background_style(WHITE)
        .border_style(BLACK)
        .draw()
        .map_err(err(what))
}

/// The corner of the plot area `[x0, x1] x [y0, y1]` holding the fewest of `points`, for the
/// legend (a box of about 45 % of the width and 30 % of the height), so that it does not
/// cover the data or a target's label. Ties go in the order upper left, upper right, lower
/// left, lower right.
fn quietest_corner(points: &[(f64, f64)], x: (f64, f64), y: (f64, f64)) -> SeriesLabelPosition {
    let (w, h) = (x.1 - x.0, y.1 - y.0);
    let corners = [
        (SeriesLabelPosition::UpperLeft, true, true),
        (SeriesLabelPosition::UpperRight, false, true),
        (SeriesLabelPosition::LowerLeft, true, false),
        (SeriesLabelPosition::LowerRight, false, false),
    ];
    let count = |left: bool, upper: bool| {
        points
            .iter()
            .filter(|(px, py)| {
                let in_x = if left {
                    *px <= x.0 + 0.45 * w
                } else {
                    *px >= x.1 - 0.45 * w
                };
                let in_y = if upper {
                    *py >= y.1 - 0.3 * h
                } else {
                    *py <= y.0 + 0.3 * h
                };
                in_x && in_y
            })
            .count()
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperLeft);
    for (pos, left, upper) in corners {
        let n = count(left, upper);
        if n < best.0 {
            best = (n, pos);
        }
    }
    best.1
}

/// Contour plot of the surface over the solution's two free factors (the others at their
/// fixed values or centres), with the target's solutions drawn in red. `None` unless exactly
/// two factors are free.
pub fn contour_svg(
    a: &Anova,
    s: &Solution,
    fixed: &[(usize, f64)],
) -> Result<Option<String>, RsmError> {
    contour_marked_svg(a, s, fixed, &[])
}

/// [`contour_svg`] with labelled settings marked (real units of every factor).
pub fn contour_marked_svg(
    a: &Anova,
    s: &Solution,
    fixed: &[(usize, f64)],
    marks: &[(Vec<f64>, String)],
) -> Result<Option<String>, RsmError> {
    const WHAT: &str = "the contour plot";
    let free: Vec<usize> = (0..a.factors.len())
        .filter(|i| !fixed.iter().any(|f| f.0 == *i))
        .collect();
    let [i, j] = free[..] else {
        return Ok(None);
    };
    let base: Vec<f64> = (0..a.factors.len())
        .map(|k| {
            fixed
                .iter()
                .find(|f| f.0 == k)
                .map_or(a.coding.centre(k), |f| f.1)
        })
        .collect();
    let at = |xi: f64, xj: f64| {
        let mut x = base.clone();
        x[i] = xi;
        x[j] = xj;
        a.predict(&x)
    };
    let (xr, yr) = (
        a.coding.low[i]..a.coding.high[i],
        a.coding.low[j]..a.coding.high[j],
    );
    const N: usize = 60;
    let cell =
        |r: &std::ops::Range<f64>, k: usize| r.start + (r.end - r.start) * k as f64 / N as f64;
    let mut grid = vec![vec![0.0; N + 1]; N + 1];
    for (p, row) in grid.iter_mut().enumerate() {
        for (q, v) in row.iter_mut().enumerate() {
            *v = at(cell(&xr, p), cell(&yr, q));
        }
    }
    let (lo, hi) = grid
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
            (l.min(*v), h.max(*v))
        });
    let fixed_text: Vec<String> = fixed
        .iter()
        .map(|(k, v)| format!("{} = {v}", a.factors[*k]))
        .collect();
    let title = format!(
        "{} = {} ({}): {} settings",
        a.response,
        s.target,
        s.label,
        s.settings.len()
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(err(WHAT))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(&title, (FONT, 18))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(xr.clone(), yr.clone())
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(a.factors[i].as_str())
            .y_desc(a.factors[j].as_str())
            .label_style((FONT, 13))
            .draw()
            .map_err(err(WHAT))?;
        let span = (hi - lo).max(1e-300);
        chart
            .draw_series(
                (0..N)
                    .flat_map(|p| (0..N).map(move |q| (p, q)))
                    .map(|(p, q)| {
                        let v = 0.25
                            * (grid[p][q] + grid[p + 1][q] + grid[p][q + 1] + grid[p + 1][q + 1]);
                        let c = ViridisRGB::get_color_normalized(v, lo, lo + span);
                        Rectangle::new(
                            [
                                (cell(&xr, p), cell(&yr, q)),
                                (cell(&xr, p + 1), cell(&yr, q + 1)),
                            ],
                            c.mix(0.85).filled(),
                        )
                    }),
            )
            .map_err(err(WHAT))?;
        // Iso-lines at ten levels, by marching squares, labelled at their first segment.
        for level in nice_levels(lo, hi, 10) {
            let segs = marching_squares(&grid, level, |p| cell(&xr, p), |q| cell(&yr, q));
            chart
                .draw_series(
                    segs.iter()
                        .map(|s| PathElement::new(vec![s.0, s.1], WHITE.stroke_width(1))),
                )
                .map_err(err(WHAT))?;
            if let Some(s) = segs.get(segs.len() / 2) {
                chart
                    .draw_series([Text::new(
                        format!("{level}"),
                        s.0,
                        (FONT, 11).into_font().color(&WHITE),
                    )])
                    .map_err(err(WHAT))?;
            }
        }
        chart
            .draw_series(
                s.settings
                    .iter()
                    .map(|st| Circle::new((st.values[i], st.values[j]), 2, RED.filled())),
            )
            .map_err(err(WHAT))?
            .label(format!(
                "{} = {} {}",
                a.response,
                s.target,
                if fixed_text.is_empty() {
                    String::new()
                } else {
                    format!("({})", fixed_text.join(", "))
                }
            ))
            .legend(|(x, y)| Circle::new((x + 10, y), 4, RED.filled()));
        for (k, (x, label)) in marks.iter().enumerate() {
            let color = [RGBColor(255, 255, 255), RGBColor(255, 127, 14)][k % 2];
            chart
                .draw_series([Cross::new((x[i], x[j]), 7, color.stroke_width(3))])
                .map_err(err(WHAT))?
                .label(label.as_str())
                .legend(move |(x, y)| Cross::new((x + 10, y), 5, color.stroke_width(3)));
        }
        legend(&mut chart, WHAT)?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(Some(svg))
}

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
    const WHAT: &str = "the response curve";
    let free: Vec<usize> = (0..a.factors.len())
        .filter(|i| !fixed.iter().any(|f| f.0 == *i))
        .collect();
    let [i] = free[..] else {
        return Ok(None);
    };
    let mut base: Vec<f64> = (0..a.factors.len()).map(|k| a.coding.centre(k)).collect();
    for (k, v) in fixed {
        base[*k] = *v;
    }
    let (x0, x1) = (a.coding.low[i], a.coding.high[i]);
    let df = a.residual_df().max(1) as f64;
    let t = StudentsT::new(0.0, 1.0, df)
        .map_err(err(WHAT))?
        .inverse_cdf(0.975);
    // (x, fitted, half-width of the band)
    let curve: Vec<(f64, f64, f64)> = (0..=80)
        .map(|s| {
            let mut x = base.clone();
            x[i] = x0 + (x1 - x0) * s as f64 / 80.0;
            let z = a.coding.code(&x);
            let half = a.mean_std_error(&z).map_or(0.0, |se| t * se);
            (x[i], a.predict_coded(&z), half)
        })
        .collect();
    let runs: Vec<(f64, f64)> = if a.factors.len() == 1 {
        a.diagnostics
            .iter()
            .map(|d| (d.settings[0], d.actual))
            .collect()
    } else {
        vec![]
    };
    let ys = curve
        .iter()
        .flat_map(|c| [c.1 - c.2, c.1 + c.2])
        .chain(runs.iter().map(|r| r.1))
        .chain(checks.iter().flat_map(|c| c.values.iter().copied()))
        .chain(solutions.iter().map(|s| s.target));
    let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    let pad = 0.06 * (hi - lo).max(1e-9);
    let (xlo, xhi) = checks.iter().fold((x0.min(x1), x0.max(x1)), |(l, h), c| {
        (l.min(c.x), h.max(c.x))
    });
    let fixed_text: Vec<String> = fixed
        .iter()
        .map(|(k, v)| format!("{} = {v}", a.factors[*k]))
        .collect();
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
            .build_cartesian_2d(xlo..xhi, (lo - pad)..(hi + pad))
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .x_desc(a.factors[i].as_str())
            .y_desc(a.response.as_str())
            .label_style((FONT, 12))
            .draw()
            .map_err(err(WHAT))?;
        let band: Vec<(f64, f64)> = curve
            .iter()
            .map(|c| (c.0, c.1 + c.2))
            .chain(curve.iter().rev().map(|c| (c.0, c.1 - c.2)))
            .collect();
        chart
            .draw_series([Polygon::new(band, BLUE.mix(0.18).filled())])
            .map_err(err(WHAT))?
            .label(format!(
                "95 % confidence band of the mean ({} df)",
                a.residual_df()
            ))
            .legend(|(x, y)| {
                Rectangle::new([(x, y - 5), (x + 20, y + 5)], BLUE.mix(0.18).filled())
            });
        chart
            .draw_series(LineSeries::new(
                curve.iter().map(|c| (c.0, c.1)),
                BLUE.stroke_width(2),
            ))
            .map_err(err(WHAT))?
            .label(format!("{} model, R^2 {:.4}", a.order.name(), a.r2))
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE.stroke_width(2)));
        if !runs.is_empty() {
            chart
                .draw_series(runs.iter().map(|p| Circle::new(*p, 4, GREY.filled())))
                .map_err(err(WHAT))?
                .label(format!("runs ({})", runs.len()))
                .legend(|(x, y)| Circle::new((x + 10, y), 4, GREY.filled()));
        }
        const GREEN: RGBColor = PALETTE[2];
        for c in checks.iter().filter(|c| !c.values.is_empty()) {
            let n = c.values.len() as f64;
            let mean = c.values.iter().sum::<f64>() / n;
            let sd = if c.values.len() > 1 {
                (c.values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            } else {
                0.0
            };
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
            let label = match s.settings.len() {
                0 => format!("{} = {}: out of range", s.label, s.target),
                1 => format!(
                    "{}: {} = {}",
                    s.label,
                    a.factors[i],
                    significant(s.settings[0].values[i], 5)
                ),
                n => format!("{}: {n} settings", s.label),
            };
            chart
                .draw_series(hit.map(|x| Cross::new((x, s.target), 6, RED.stroke_width(2))))
                .map_err(err(WHAT))?;
            chart
                .draw_series([Text::new(
                    label,
                    (xlo + 0.01 * (xhi - xlo), s.target),
                    (FONT, 11).into_font().color(&RED),
                )])
                .map_err(err(WHAT))?;
        }
        // The legend goes where it covers least: the curve and its band, the runs, the
        // checks, and each target's label (drawn from the left edge along the target).
        let mut occupied: Vec<(f64, f64)> = curve
            .iter()
            .flat_map(|c| (0..=4).map(move |k| (c.0, c.1 - c.2 + 0.5 * c.2 * k as f64)))
            .chain(runs.iter().copied())
            .chain(
                checks
                    .iter()
                    .flat_map(|c| c.values.iter().map(move |v| (c.x, *v))),
            )
            .collect();
        for s in solutions {
            occupied
                .extend((0..=20).map(|k| (xlo + (xhi - xlo) * 0.4 * k as f64 / 20.0, s.target)));
        }
        let corner = quietest_corner(&occupied, (xlo, xhi), (lo - pad, hi + pad));
        legend_at(&mut chart, WHAT, corner)?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(Some(svg))
}

/// About `n` round levels strictly inside (lo, hi).
fn nice_levels(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if !(hi > lo) {
        return vec![];
    }
    let raw = (hi - lo) / n as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let mut v = (lo / step).ceil() * step;
    let mut out = vec![];
    while v < hi {
        if v > lo {
            out.push((v / step).round() * step);
        }
        v += step;
    }
    out
}

type Seg = ((f64, f64), (f64, f64));

/// Segments of the iso-line `level` of `grid[p][q]` (p along x, q along y).
fn marching_squares(
    grid: &[Vec<f64>],
    level: f64,
    x: impl Fn(usize) -> f64,
    y: impl Fn(usize) -> f64,
) -> Vec<Seg> {
    let mut out = vec![];
    let lerp = |a: f64, b: f64, fa: f64, fb: f64| a + (b - a) * (level - fa) / (fb - fa);
    for p in 0..grid.len() - 1 {
        for q in 0..grid[p].len() - 1 {
            // Corners counter-clockwise from (p, q); an edge is crossed when its ends differ.
            let c = [(p, q), (p + 1, q), (p + 1, q + 1), (p, q + 1)];
            let mut pts = vec![];
            for e in 0..4 {
                let (a, b) = (c[e], c[(e + 1) % 4]);
                let (fa, fb) = (grid[a.0][a.1], grid[b.0][b.1]);
                if (fa < level) != (fb < level) {
                    pts.push((lerp(x(a.0), x(b.0), fa, fb), lerp(y(a.1), y(b.1), fa, fb)));
                }
            }
            for pair in pts.chunks(2) {
                if let [s, t] = pair {
                    out.push((*s, *t));
                }
            }
        }
    }
    out
}

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

#[cfg(test)]
mod tests {
    use super::quietest_corner;
    use plotters::prelude::SeriesLabelPosition as P;

    /// A rising curve with its target's label along the top left (the repose curve at 12 %,
    /// where the label sat under the legend): the legend leaves the upper left for the lower
    /// right, the one corner without points.
    #[test]
    fn the_legend_goes_to_the_corner_with_fewest_points() {
        let mut pts: Vec<(f64, f64)> = (0..=10)
            .map(|k| (k as f64 / 10.0, 40.0 + k as f64 / 2.0))
            .collect();
        pts.extend((0..=8).map(|k| (k as f64 / 20.0, 44.8)));
        let at = quietest_corner(&pts, (0.0, 1.0), (40.0, 45.0));
        assert!(matches!(at, P::LowerRight), "{at:?}");
        // Nothing anywhere: the usual upper left.
        assert!(matches!(
            quietest_corner(&[], (0.0, 1.0), (0.0, 1.0)),
            P::UpperLeft
        ));
        // Only the upper left taken: the upper right.
        let at = quietest_corner(&[(0.1, 0.9)], (0.0, 1.0), (0.0, 1.0));
        assert!(matches!(at, P::UpperRight), "{at:?}");
    }
}
