//! Contour plot of the surface over two free factors, with a target's solutions and marked
//! settings.

use super::{Chart, FONT, RED, err, fixed_text, free_factors, legend};
use crate::rsm::{Anova, RsmError, Solution};
use plotters::prelude::*;
use plotters::style::RGBColor;
use plotters::style::colors::colormaps::ViridisRGB;
use std::ops::Range;

const WHAT: &str = "the contour plot";
/// Cells along each axis of the sampled surface.
const N: usize = 60;

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
    let free = free_factors(a, fixed);
    let [i, j] = free[..] else {
        return Ok(None);
    };
    let surface = Surface::sample(a, &slice_base(a, fixed), i, j);
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
            .build_cartesian_2d(surface.x.clone(), surface.y.clone())
            .map_err(err(WHAT))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(a.factors[i].as_str())
            .y_desc(a.factors[j].as_str())
            .label_style((FONT, 13))
            .draw()
            .map_err(err(WHAT))?;
        draw_heat_map(&mut chart, &surface)?;
        draw_iso_lines(&mut chart, &surface)?;
        draw_solutions(&mut chart, a, s, fixed, (i, j))?;
        draw_marks(&mut chart, marks, (i, j))?;
        legend(&mut chart, WHAT)?;
        root.present().map_err(err(WHAT))?;
    }
    Ok(Some(svg))
}

/// Every factor's setting on the slice, real units: the fixed value where one is given (the
/// first, if a factor is given twice), else the factor's centre.
fn slice_base(a: &Anova, fixed: &[(usize, f64)]) -> Vec<f64> {
    (0..a.factors.len())
        .map(|k| {
            fixed
                .iter()
                .find(|f| f.0 == k)
                .map_or(a.coding.centre(k), |f| f.1)
        })
        .collect()
}

/// The fitted surface sampled at (N + 1) x (N + 1) points spanning the two free factors'
/// ranges (real units), with its smallest and largest value.
struct Surface {
    x: Range<f64>,
    y: Range<f64>,
    /// `values[p][q]`: the response at (x_at(p), y_at(q)).
    values: Vec<Vec<f64>>,
    lo: f64,
    hi: f64,
}

impl Surface {
    /// Samples `a` over factors `i` (x) and `j` (y), the other factors at `base`.
    fn sample(a: &Anova, base: &[f64], i: usize, j: usize) -> Surface {
        let at = |xi: f64, xj: f64| {
            let mut x = base.to_vec();
            x[i] = xi;
            x[j] = xj;
            a.predict(&x)
        };
        let (x, y) = (
            a.coding.low[i]..a.coding.high[i],
            a.coding.low[j]..a.coding.high[j],
        );
        let mut values = vec![vec![0.0; N + 1]; N + 1];
        for (p, row) in values.iter_mut().enumerate() {
            for (q, v) in row.iter_mut().enumerate() {
                *v = at(grid_line(&x, p), grid_line(&y, q));
            }
        }
        let (lo, hi) = values
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(*v), h.max(*v))
            });
        Surface {
            x,
            y,
            values,
            lo,
            hi,
        }
    }

    fn x_at(&self, p: usize) -> f64 {
        grid_line(&self.x, p)
    }

    fn y_at(&self, q: usize) -> f64 {
        grid_line(&self.y, q)
    }
}

/// Grid line `k` of N cells over `r`: start + (end - start) k / N.
fn grid_line(r: &Range<f64>, k: usize) -> f64 {
    r.start + (r.end - r.start) * k as f64 / N as f64
}

/// Each cell filled with the Viridis colour of the mean of its four corners, scaled from the
/// surface's smallest to its largest value.
fn draw_heat_map<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>, s: &Surface) -> Result<(), RsmError> {
    let (grid, lo) = (&s.values, s.lo);
    let span = (s.hi - lo).max(1e-300);
    chart
        .draw_series(
            (0..N)
                .flat_map(|p| (0..N).map(move |q| (p, q)))
                .map(|(p, q)| {
                    let v =
                        0.25 * (grid[p][q] + grid[p + 1][q] + grid[p][q + 1] + grid[p + 1][q + 1]);
                    let c = ViridisRGB::get_color_normalized(v, lo, lo + span);
                    Rectangle::new(
                        [(s.x_at(p), s.y_at(q)), (s.x_at(p + 1), s.y_at(q + 1))],
                        c.mix(0.85).filled(),
                    )
                }),
        )
        .map_err(err(WHAT))?;
    Ok(())
}

/// Iso-lines at about ten round levels, by marching squares, each labelled at its middle
/// segment.
fn draw_iso_lines<'a, 'b: 'a>(chart: &mut Chart<'a, 'b>, s: &Surface) -> Result<(), RsmError> {
    for level in nice_levels(s.lo, s.hi, 10) {
        let segs = marching_squares(&s.values, level, |p| s.x_at(p), |q| s.y_at(q));
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
    Ok(())
}

/// The settings that hit the target, red dots over free factors `(i, j)`, with the target
/// and the fixed factors in the legend.
fn draw_solutions<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    a: &Anova,
    s: &Solution,
    fixed: &[(usize, f64)],
    (i, j): (usize, usize),
) -> Result<(), RsmError> {
    let fixed_text = fixed_text(a, fixed);
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
    Ok(())
}

/// Each labelled setting a cross over free factors `(i, j)`, white and orange in turn so
/// that neighbours can be told apart on any colour of the map.
fn draw_marks<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    marks: &[(Vec<f64>, String)],
    (i, j): (usize, usize),
) -> Result<(), RsmError> {
    for (k, (x, label)) in marks.iter().enumerate() {
        let color = [RGBColor(255, 255, 255), RGBColor(255, 127, 14)][k % 2];
        chart
            .draw_series([Cross::new((x[i], x[j]), 7, color.stroke_width(3))])
            .map_err(err(WHAT))?
            .label(label.as_str())
            .legend(move |(x, y)| Cross::new((x + 10, y), 5, color.stroke_width(3)));
    }
    Ok(())
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
